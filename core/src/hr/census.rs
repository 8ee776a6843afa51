//! Counting what the expanded scene will need before anything is loaded: clusters (scene
//! nodes, expanded instances and the grouping levels inserted under crowded clusters), input
//! polygons by sidedness, the deepest nesting and the largest child list. Shared by planning
//! and loading, so that the plan is exact. One pass over the image; originals are counted
//! once and remembered in a small caller-provided scratch.

use super::error::HrError;
use crate::image::{SceneSource, SceneView};
use crate::limits::MAX_NODE_DEPTH;
use crate::material::TWO_SIDED;
use crate::{MaterialId, NodeId, OriginalId, PolyId};
use bytemuck::{Pod, Zeroable};

/// What a subtree expands to.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
#[repr(C)]
pub struct Census {
    /// Clusters, grouping levels included.
    pub clusters: u64,
    /// Input polygons with one-sided materials.
    pub polys_one_sided: u64,
    /// Input polygons with two-sided materials.
    pub polys_two_sided: u64,
    /// Deepest cluster nesting (the subtree's root = 1), grouping levels excluded.
    pub depth: u32,
    /// Largest child list of any cluster before grouping.
    pub max_children: u32,
}

impl Census {
    /// All input polygons.
    pub fn polygons(&self) -> u64 {
        self.polys_one_sided + self.polys_two_sided
    }

    fn add(&mut self, o: &Census) -> Result<(), HrError> {
        self.clusters = self
            .clusters
            .checked_add(o.clusters)
            .ok_or(HrError::SceneTooLarge)?;
        self.polys_one_sided = self
            .polys_one_sided
            .checked_add(o.polys_one_sided)
            .ok_or(HrError::SceneTooLarge)?;
        self.polys_two_sided = self
            .polys_two_sided
            .checked_add(o.polys_two_sided)
            .ok_or(HrError::SceneTooLarge)?;
        self.depth = self.depth.max(o.depth);
        self.max_children = self.max_children.max(o.max_children);
        Ok(())
    }
}

/// Clusters inserted under a cluster with `n` children so that none has more than `m`: the
/// children are halved recursively (see `load`), each half of two or more becoming a cluster.
pub fn grouping_clusters(n: u64, m: u32) -> u64 {
    let m = m.max(2) as u64;
    if n <= m {
        return 0;
    }
    let wrap = |k: u64| {
        if k <= 1 {
            0
        } else {
            1 + grouping_clusters(k, m as u32)
        }
    };
    wrap(n - n / 2) + wrap(n / 2)
}

/// Bytes of scratch [`census`] needs.
pub fn census_scratch_bytes<S: SceneSource>(view: &SceneView<S>) -> usize {
    let info = view.info();
    info.originals as usize * core::mem::size_of::<Census>() + (info.materials as usize).div_ceil(8)
}

/// An open node while walking a tree.
#[derive(Clone, Copy)]
struct Frame {
    end: u32,
    children: u64,
    acc: Census,
}

/// Counts the expanded scene. `scratch` must hold [`census_scratch_bytes`].
pub fn census<S: SceneSource>(
    view: &SceneView<S>,
    max_children: u32,
    scratch: &mut [u8],
) -> Result<Census, HrError> {
    let info = *view.info();
    let memo_bytes = info.originals as usize * core::mem::size_of::<Census>();
    if scratch.len() < census_scratch_bytes(view) {
        return Err(HrError::ScratchTooSmall);
    }
    let (memo_bytes, rest) = scratch.split_at_mut(memo_bytes);
    let two_sided = &mut rest[..(info.materials as usize).div_ceil(8)];
    two_sided.fill(0);
    for m in 0..info.materials {
        if view.material_record(MaterialId(m))?.flags & TWO_SIDED != 0 {
            two_sided[m as usize / 8] |= 1 << (m % 8);
        }
    }
    // No originals: nothing to remember (and an empty scratch may sit at any address, which
    // a cast to an aligned type would refuse).
    let memo: &mut [Census] = if memo_bytes.is_empty() {
        &mut []
    } else {
        bytemuck::try_cast_slice_mut(memo_bytes).map_err(|_| HrError::ScratchTooSmall)?
    };
    for k in 0..info.originals {
        let root = view.original(OriginalId(k))?.root;
        memo[k as usize] = tree(view, root, max_children, two_sided, memo)?;
    }
    tree(view, info.scene_root.0, max_children, two_sided, memo)
}

fn tree<S: SceneSource>(
    view: &SceneView<S>,
    root: u32,
    max_children: u32,
    two_sided: &[u8],
    memo: &[Census],
) -> Result<Census, HrError> {
    let mut stack: heapless::Vec<Frame, MAX_NODE_DEPTH> = heapless::Vec::new();
    let end = view.node(NodeId(root))?.subtree_end;
    let mut result = Census::default();
    let mut i = root;
    while i < end {
        let rec = view.node(NodeId(i))?;
        let exact = match rec.instance() {
            Some(id) => {
                let inst = view.instance(id)?;
                inst.is_exact()
                    .then(|| memo.get(inst.original as usize).copied())
                    .flatten()
            }
            None => None,
        };
        if let Some(sub) = exact {
            // An exact instance expands to its original's root cluster.
            match stack.last_mut() {
                Some(parent) => {
                    parent.children += 1;
                    parent.acc.add(&Census {
                        depth: sub.depth,
                        ..sub
                    })?;
                }
                None => result = sub,
            }
        } else {
            let mut own = Census {
                clusters: 1,
                ..Census::default()
            };
            let mut polys = [crate::image::PolygonRecord::default(); 32];
            let mut done = 0u32;
            while done < rec.poly_count {
                let n = (rec.poly_count - done).min(32);
                view.polygons(PolyId(rec.poly_first + done), &mut polys[..n as usize])?;
                for p in &polys[..n as usize] {
                    let m = p.material as usize;
                    if two_sided
                        .get(m / 8)
                        .is_some_and(|b| b & (1 << (m % 8)) != 0)
                    {
                        own.polys_two_sided += 1;
                    } else {
                        own.polys_one_sided += 1;
                    }
                }
                done += n;
            }
            let frame = Frame {
                end: rec.subtree_end,
                children: rec.poly_count as u64,
                acc: own,
            };
            stack.push(frame).map_err(|_| HrError::SceneTooLarge)?;
        }
        // Close every subtree that ends after this node.
        while stack.last().is_some_and(|f| f.end == i + 1) {
            let Some(mut f) = stack.pop() else { break };
            f.acc.clusters = f
                .acc
                .clusters
                .checked_add(grouping_clusters(f.children, max_children))
                .ok_or(HrError::SceneTooLarge)?;
            f.acc.max_children = f
                .acc
                .max_children
                .max(f.children.min(u32::MAX as u64) as u32);
            f.acc.depth += 1;
            match stack.last_mut() {
                Some(parent) => {
                    parent.children += 1;
                    parent.acc.add(&f.acc)?;
                }
                None => result = f.acc,
            }
        }
        i += 1;
    }
    Ok(result)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grouping_counts() {
        assert_eq!(grouping_clusters(8, 8), 0);
        // 9 -> 5 + 4: two clusters, neither split again.
        assert_eq!(grouping_clusters(9, 8), 2);
        // 17 -> 9 + 8 -> (5 + 4) + 8: 9 and 8 wrapped, 9 split into two wrapped halves.
        assert_eq!(grouping_clusters(17, 8), 4);
        // A binary tree over n leaves has n - 2 internal nodes below the root.
        assert_eq!(grouping_clusters(1 << 20, 2), (1 << 20) - 2);
    }
}
