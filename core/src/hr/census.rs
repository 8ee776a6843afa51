//! Counting what the expanded scene will need before anything is loaded: clusters (scene
//! nodes, expanded instances and the grouping levels inserted under crowded clusters), input
//! polygons by sidedness, the deepest nesting and the largest child list, and the instances
//! that stay closed with what their tables and received light take. Shared by planning
//! and loading, so that the plan is exact. One pass over the image; originals are counted
//! once and remembered in a small caller-provided scratch.

use super::error::HrError;
use super::settings::{BlockingLimits, Inline, Instancing};
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
    /// Instances that stay closed (see [`Instancing`]).
    pub instances: u64,
    /// Floats of the light they receive (see `tables::closed::Received`).
    pub received_floats: u64,
    /// Originals of the closed instances, each once: their tables' values (floats) and
    /// visible fractions (bytes).
    pub table_floats: u64,
    /// See `table_floats`.
    pub table_bytes: u64,
    /// Originals with closed instances.
    pub closed_originals: u32,
    /// Zero.
    pub reserved: u32,
    /// Bytes of the polygons closed instances block with (see
    /// `Settings::blocking_polygons`): their originals', each once, and approximate
    /// instances' own, each instance's, where they block with them (see `own_polygons`).
    pub blocking_bytes: u64,
    /// Own polygons of the closed approximate instances that block with them (see
    /// `Settings::own_polygons`; 0 where the level's are too many), and their bytes.
    pub own_polygons: u64,
    /// See `own_polygons`.
    pub own_bytes: u64,
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
        self.instances = self
            .instances
            .checked_add(o.instances)
            .ok_or(HrError::SceneTooLarge)?;
        self.received_floats = self
            .received_floats
            .checked_add(o.received_floats)
            .ok_or(HrError::SceneTooLarge)?;
        self.own_polygons = self
            .own_polygons
            .checked_add(o.own_polygons)
            .ok_or(HrError::SceneTooLarge)?;
        self.own_bytes = self
            .own_bytes
            .checked_add(o.own_bytes)
            .ok_or(HrError::SceneTooLarge)?;
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
    info.originals as usize * core::mem::size_of::<Census>()
        + (info.materials as usize).div_ceil(8)
        + (info.originals as usize).div_ceil(8)
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
    census_level(
        view,
        max_children,
        Instancing::None,
        Inline::NONE,
        BlockingLimits::NONE,
        scratch,
    )
}

/// Counts the scene as a solve with `instancing` loads it (the originals `inline` names
/// expanded in place), closed instances blocking with the polygons `blocking` allows (see
/// `Settings::blocking_polygons`, `Settings::own_polygons`). `scratch` must hold
/// [`census_scratch_bytes`].
pub fn census_level<S: SceneSource>(
    view: &SceneView<S>,
    max_children: u32,
    instancing: Instancing,
    inline: Inline<'_>,
    blocking: BlockingLimits,
    scratch: &mut [u8],
) -> Result<Census, HrError> {
    census_at(
        view,
        max_children,
        instancing,
        inline,
        blocking,
        view.info().scene_root.0,
        scratch,
    )
}

/// [`census_level`] of the level whose root is node `root` (the scene's root, an opened
/// instance's original's root, or an opened approximate instance).
pub(crate) fn census_at<S: SceneSource>(
    view: &SceneView<S>,
    max_children: u32,
    instancing: Instancing,
    inline: Inline<'_>,
    blocking: BlockingLimits,
    root: u32,
    scratch: &mut [u8],
) -> Result<Census, HrError> {
    let info = *view.info();
    let memo_bytes = info.originals as usize * core::mem::size_of::<Census>();
    if scratch.len() < census_scratch_bytes(view) {
        return Err(HrError::ScratchTooSmall);
    }
    let (memo_bytes, rest) = scratch.split_at_mut(memo_bytes);
    let (two_sided, rest) = rest.split_at_mut((info.materials as usize).div_ceil(8));
    let closed = &mut rest[..(info.originals as usize).div_ceil(8)];
    two_sided.fill(0);
    closed.fill(0);
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
    if instancing == Instancing::None {
        for k in 0..info.originals {
            let root = view.original(OriginalId(k))?.root;
            memo[k as usize] = tree(view, root, max_children, two_sided, memo)?;
        }
        return tree(view, root, max_children, two_sided, memo);
    }
    let mut c = level_tree(
        view,
        root,
        max_children,
        two_sided,
        inline,
        blocking,
        closed,
    )?;
    // The tables of every original with closed instances, each once.
    for k in 0..info.originals {
        if closed[k as usize / 8] & (1 << (k % 8)) == 0 {
            continue;
        }
        let t = view
            .table_of(OriginalId(k))?
            .ok_or(HrError::NoTables { original: k })?;
        c.closed_originals += 1;
        c.table_floats = c
            .table_floats
            .checked_add(t.values())
            .ok_or(HrError::SceneTooLarge)?;
        c.table_bytes = c
            .table_bytes
            .checked_add(super::load_instances::as_loaded(&t).visible_bytes())
            .ok_or(HrError::SceneTooLarge)?;
        if let Some(n) = super::original_geometry::blocking_polygons(view, k, blocking.each)? {
            c.blocking_bytes = c
                .blocking_bytes
                .checked_add(super::original_geometry::bytes_needed(n) as u64)
                .ok_or(HrError::SceneTooLarge)?;
        }
    }
    // The approximate instances' own polygons, all of them or none.
    if c.own_polygons <= u64::from(blocking.own) {
        c.blocking_bytes = c
            .blocking_bytes
            .checked_add(c.own_bytes)
            .ok_or(HrError::SceneTooLarge)?;
    } else {
        c.own_polygons = 0;
        c.own_bytes = 0;
    }
    Ok(c)
}

/// The originals with closed instances in the level [`census_at`] last counted with
/// `scratch` (one bit each, as [`Inline`]).
pub(crate) fn closed_bits<'s, S: SceneSource>(view: &SceneView<S>, scratch: &'s [u8]) -> &'s [u8] {
    let info = view.info();
    let at = info.originals as usize * core::mem::size_of::<Census>()
        + (info.materials as usize).div_ceil(8);
    &scratch[at..at + (info.originals as usize).div_ceil(8)]
}

/// Every original's expanded census, into `memo` (one per original, in order).
pub(crate) fn expanded_originals<S: SceneSource>(
    view: &SceneView<S>,
    memo: &mut [Census],
) -> Result<(), HrError> {
    for k in 0..view.info().originals {
        let root = view.original(OriginalId(k))?.root;
        let c = tree(view, root, 2, &[], memo)?;
        if let Some(m) = memo.get_mut(k as usize) {
            *m = c;
        }
    }
    Ok(())
}

/// Input polygons in the expansion of node `node`'s subtree (an exact instance: its
/// original's), from the originals' expanded census `memo`.
pub(crate) fn subtree_polygons<S: SceneSource>(
    view: &SceneView<S>,
    node: u32,
    memo: &[Census],
) -> Result<u64, HrError> {
    Ok(tree(view, node, 2, &[], memo)?.polygons())
}

/// A closed instance of `original` at node `rec`: one instance, the floats of the light it
/// receives, its own polygons' bytes where it blocks with them (see
/// `original_geometry::own_blocking_polygons`), and its original marked in `closed`.
fn closed_instance<S: SceneSource>(
    view: &SceneView<S>,
    original: u32,
    rec: &crate::image::NodeRecord,
    blocking: BlockingLimits,
    closed: &mut [u8],
) -> Result<Census, HrError> {
    let own = super::original_geometry::own_blocking_polygons(view, rec, blocking.each)?;
    let t = view
        .table_of(OriginalId(original))?
        .ok_or(HrError::NoTables { original })?;
    if let Some(b) = closed.get_mut(original as usize / 8) {
        *b |= 1 << (original % 8);
    }
    Ok(Census {
        instances: 1,
        // All the light, the power its direct light brought, what links and the exchange handed.
        received_floats: super::state::received_parts_floats(
            t.bands as usize,
            t.scatterers as usize,
            t.incoming_side as usize * t.incoming_side as usize,
        ) as u64,
        own_polygons: own.map_or(0, u64::from),
        own_bytes: own.map_or(0, |n| super::original_geometry::bytes_needed(n) as u64),
        ..Census::default()
    })
}

/// A node of a level being walked: the next child node to visit and the end of its
/// subtree, its children so far and what it holds.
#[derive(Clone, Copy)]
struct LevelFrame {
    next: u32,
    end: u32,
    children: u64,
    acc: Census,
}

/// The census of the level whose root is node `root`: instances below it stay closed
/// (leaves) unless `inline` expands their original, whose contents (an exact instance's
/// original's tree, an approximate one's own nodes) then count as part of the level, their
/// own instances closed or expanded by the same rule. Originals with closed instances are
/// marked in `closed`.
fn level_tree<S: SceneSource>(
    view: &SceneView<S>,
    root: u32,
    max_children: u32,
    two_sided: &[u8],
    inline: Inline<'_>,
    blocking: BlockingLimits,
    closed: &mut [u8],
) -> Result<Census, HrError> {
    let mut stack: heapless::Vec<LevelFrame, MAX_NODE_DEPTH> = heapless::Vec::new();
    let push = |stack: &mut heapless::Vec<LevelFrame, MAX_NODE_DEPTH>, node: u32| {
        let rec = view.node(NodeId(node))?;
        let own = own_polygons(view, &rec, two_sided)?;
        stack
            .push(LevelFrame {
                next: node + 1,
                end: rec.subtree_end,
                children: rec.poly_count as u64,
                acc: own,
            })
            .map_err(|_| HrError::SceneTooLarge)
    };
    push(&mut stack, root)?;
    loop {
        let Some(top) = stack.last_mut() else {
            return Err(HrError::SceneTooLarge);
        };
        if top.next >= top.end {
            let Some(mut f) = stack.pop() else { break };
            close(&mut f.acc, f.children, max_children)?;
            match stack.last_mut() {
                Some(parent) => {
                    parent.children += 1;
                    parent.acc.add(&f.acc)?;
                }
                None => return Ok(f.acc),
            }
            continue;
        }
        let j = top.next;
        let rec = view.node(NodeId(j))?;
        top.next = rec.subtree_end.max(j + 1);
        let node = match rec.instance() {
            None => j,
            Some(id) => {
                let inst = view.instance(id)?;
                if !inline.expands(inst.original) {
                    let leaf = closed_instance(view, inst.original, &rec, blocking, closed)?;
                    top.children += 1;
                    top.acc.add(&leaf)?;
                    continue;
                }
                if inst.is_exact() {
                    view.original(inst.original())?.root
                } else {
                    j
                }
            }
        };
        push(&mut stack, node)?;
    }
    Err(HrError::SceneTooLarge)
}

/// Completes the census of a cluster with `children` child entries once its subtree is
/// walked: its grouping levels, its widest child list, one more level of depth.
fn close(acc: &mut Census, children: u64, max_children: u32) -> Result<(), HrError> {
    acc.clusters = acc
        .clusters
        .checked_add(grouping_clusters(children, max_children))
        .ok_or(HrError::SceneTooLarge)?;
    acc.max_children = acc.max_children.max(children.min(u32::MAX as u64) as u32);
    acc.depth += 1;
    Ok(())
}

/// A cluster for node `rec` and its own polygons by sidedness.
fn own_polygons<S: SceneSource>(
    view: &SceneView<S>,
    rec: &crate::image::NodeRecord,
    two_sided: &[u8],
) -> Result<Census, HrError> {
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
    Ok(own)
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
        open(view, &rec, two_sided, memo, &mut stack, &mut result)?;
        // Close every subtree that ends after this node.
        while stack.last().is_some_and(|f| f.end == i + 1) {
            let Some(mut f) = stack.pop() else { break };
            close(&mut f.acc, f.children, max_children)?;
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

/// Counts node `rec` of an expanded tree: an exact instance as its original's census (from
/// `memo`), any other node as a cluster with its own polygons, pushed to be closed with its
/// subtree.
fn open<S: SceneSource>(
    view: &SceneView<S>,
    rec: &crate::image::NodeRecord,
    two_sided: &[u8],
    memo: &[Census],
    stack: &mut heapless::Vec<Frame, MAX_NODE_DEPTH>,
    result: &mut Census,
) -> Result<(), HrError> {
    {
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
                None => *result = sub,
            }
        } else {
            let own = own_polygons(view, rec, two_sided)?;
            let frame = Frame {
                end: rec.subtree_end,
                children: rec.poly_count as u64,
                acc: own,
            };
            stack.push(frame).map_err(|_| HrError::SceneTooLarge)?;
        }
    }
    Ok(())
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
