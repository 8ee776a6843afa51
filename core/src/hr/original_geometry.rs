//! Closed instances that block rays with their original's own polygons (see
//! [`Settings::blocking_polygons`](super::settings::Settings::blocking_polygons)): the
//! original is expanded once per level into its own frame, every instance inside it placed,
//! with a BVH over it; a segment is taken into a closed instance's frame and tested there,
//! as ray tracers instance geometry. Its shadows are then the contents' own, where `tau`
//! alone would shade like a uniform medium.
//!
//! Storage, from a region's first byte: the corners (12 floats per polygon, in the
//! original's frame, m), the corner counts (one byte each), the BVH's nodes and its order.

use super::error::HrError;
use super::layout::up;
use crate::bvh::{Bvh, BvhNode, BvhVisibility, PolygonSet};
use crate::geometry::Similarity;
use crate::image::{SceneSource, SceneView};
use crate::limits::{MAX_NODE_DEPTH, NONE};
use crate::{NodeId, OriginalId, PolyId, VertexId};
use glam::Vec3;

/// The polygons `original` blocks with when closed, if it does: at most `limit` once
/// expanded (and at least one).
pub(crate) fn blocking_polygons<S: SceneSource>(
    view: &SceneView<S>,
    original: u32,
    limit: u32,
) -> Result<Option<u32>, HrError> {
    let n = view.original(OriginalId(original))?.expanded_polygons;
    Ok((n > 0 && n <= limit as u64).then_some(n as u32))
}

/// Byte offsets of the parts of a region holding `n` polygons, from its start: corners,
/// counts, BVH nodes, BVH order, end.
fn parts(n: u32) -> [usize; 5] {
    let corners = 0;
    let counts = corners + up(48 * n as usize);
    let nodes = counts + up(n as usize);
    let order = nodes + up(crate::bvh::nodes_needed(n) * core::mem::size_of::<BvhNode>());
    let end = order + up(4 * n as usize);
    [corners, counts, nodes, order, end]
}

/// Bytes of the region of an original of `n` polygons.
pub(crate) fn bytes_needed(n: u32) -> usize {
    parts(n)[4]
}

/// A node range still to walk and the transform of its nodes to the original's frame.
#[derive(Clone, Copy)]
struct Frame {
    next: u32,
    end: u32,
    place: Similarity,
}

/// Expands `original` (of `n` polygons, see [`blocking_polygons`]) into `region` (of
/// [`bytes_needed`]`(n)` bytes) and builds its BVH.
pub(crate) fn load<S: SceneSource>(
    view: &SceneView<S>,
    region: &mut [u8],
    original: u32,
    n: u32,
) -> Result<(), HrError> {
    let p = parts(n);
    if region.len() < p[4] {
        return Err(HrError::SceneTooLarge);
    }
    let (head, tail) = region.split_at_mut(p[2]);
    let (corner_bytes, count_bytes) = head.split_at_mut(p[1]);
    let corners: &mut [f32] = bytemuck::try_cast_slice_mut(&mut corner_bytes[..48 * n as usize])
        .map_err(|_| HrError::SceneTooLarge)?;
    let counts = &mut count_bytes[..n as usize];
    let mut written = 0u32;
    let mut emit = |rec: &crate::image::NodeRecord, place: &Similarity| -> Result<(), HrError> {
        for k in 0..rec.poly_count {
            let mut pr = [crate::image::PolygonRecord::default()];
            view.polygons(PolyId(rec.poly_first + k), &mut pr)?;
            let c = pr[0].corner_count();
            if written >= n || !(3..=4).contains(&c) {
                return Err(HrError::BadGeometry {
                    polygon: written as u64,
                });
            }
            let out = &mut corners[12 * written as usize..12 * (written as usize + 1)];
            out.fill(0.0);
            for j in 0..c {
                let mut v = [[0.0f32; 3]];
                view.vertices(VertexId(rec.vert_first + pr[0].corners[j]), &mut v)?;
                let x = place.point(v[0].into());
                out[3 * j..3 * j + 3].copy_from_slice(&x.to_array());
            }
            counts[written as usize] = c as u8;
            written += 1;
        }
        Ok(())
    };
    // The root's own polygons, then its nodes in order; an instance inside is walked in its
    // own frame (an exact one: its original's nodes; an approximate one: its own subtree).
    let root = view.original(OriginalId(original))?.root;
    let rec = view.node(NodeId(root))?;
    emit(&rec, &Similarity::IDENTITY)?;
    let mut stack: heapless::Vec<Frame, MAX_NODE_DEPTH> = heapless::Vec::new();
    let _ = stack.push(Frame {
        next: root + 1,
        end: rec.subtree_end,
        place: Similarity::IDENTITY,
    });
    while let Some(f) = stack.last_mut() {
        if f.next >= f.end {
            stack.pop();
            continue;
        }
        let j = f.next;
        let rec = view.node(NodeId(j))?;
        let Some(id) = rec.instance() else {
            f.next = j + 1;
            let place = f.place;
            emit(&rec, &place)?;
            continue;
        };
        f.next = rec.subtree_end;
        let inst = view.instance(id)?;
        let place = f.place.compose(&inst.transform());
        let frame = if inst.is_exact() {
            let r = view.original(inst.original())?.root;
            let rr = view.node(NodeId(r))?;
            emit(&rr, &place)?;
            Frame {
                next: r + 1,
                end: rr.subtree_end,
                place,
            }
        } else {
            emit(&rec, &place)?;
            Frame {
                next: j + 1,
                end: rec.subtree_end,
                place,
            }
        };
        stack.push(frame).map_err(|_| HrError::SceneTooLarge)?;
    }
    if written != n {
        return Err(HrError::BadGeometry {
            polygon: written as u64,
        });
    }
    let polys = RegionPolygons { corners, counts };
    let (nodes, rest) = tail.split_at_mut(p[3] - p[2]);
    let nodes: &mut [BvhNode] = bytemuck::try_cast_slice_mut(
        &mut nodes[..crate::bvh::nodes_needed(n) * core::mem::size_of::<BvhNode>()],
    )
    .map_err(|_| HrError::SceneTooLarge)?;
    let order: &mut [u32] = bytemuck::try_cast_slice_mut(&mut rest[..4 * n as usize])
        .map_err(|_| HrError::SceneTooLarge)?;
    crate::bvh::build(n, |i| polys.bounds(i), nodes, order).map_err(|_| HrError::SceneTooLarge)?;
    Ok(())
}

/// The polygons of a region (corners in the original's frame).
#[derive(Clone, Copy)]
struct RegionPolygons<'a> {
    corners: &'a [f32],
    counts: &'a [u8],
}

impl PolygonSet for RegionPolygons<'_> {
    fn count(&self) -> u32 {
        self.counts.len() as u32
    }

    fn corners(&self, id: u32, out: &mut [Vec3; 4]) -> usize {
        let Some(&c) = self.counts.get(id as usize) else {
            return 0;
        };
        let f = &self.corners[12 * id as usize..12 * id as usize + 12];
        for (j, o) in out.iter_mut().enumerate() {
            *o = Vec3::new(f[3 * j], f[3 * j + 1], f[3 * j + 2]);
        }
        c as usize
    }
}

/// An original's polygons and BVH as loaded by [`load`].
#[derive(Clone, Copy)]
pub(crate) struct OriginalGeometry<'a> {
    vis: BvhVisibility<'a, RegionPolygons<'a>>,
}

impl<'a> OriginalGeometry<'a> {
    /// The geometry in `region` (see [`load`]); `None` if the region is not one.
    pub(crate) fn over(region: &'a [u8], n: u32) -> Option<Self> {
        let p = parts(n);
        if region.len() < p[4] || n == 0 {
            return None;
        }
        let corners: &[f32] = bytemuck::try_cast_slice(&region[..48 * n as usize]).ok()?;
        let counts = &region[p[1]..p[1] + n as usize];
        let nodes: &[BvhNode] = bytemuck::try_cast_slice(
            &region[p[2]..p[2] + crate::bvh::nodes_needed(n) * core::mem::size_of::<BvhNode>()],
        )
        .ok()?;
        let order: &[u32] = bytemuck::try_cast_slice(&region[p[3]..p[3] + 4 * n as usize]).ok()?;
        let bvh = Bvh::new_unchecked(nodes, order);
        Some(OriginalGeometry {
            vis: BvhVisibility::new(bvh, RegionPolygons { corners, counts }),
        })
    }

    /// True when the segment `from..to` (world) meets a polygon of the instance placed by
    /// `place` (with the margins of [`BvhVisibility::blocker`]).
    pub(crate) fn blocks(&self, place: &Similarity, from: Vec3, to: Vec3) -> bool {
        let (a, b) = local(place, from, to);
        self.vis.blocker(a, b, [NONE, NONE]).is_some()
    }

    /// Where the segment `from..to` (world) first meets a polygon of the instance placed by
    /// `place`: its parameter (0 at `from`, 1 at `to`).
    pub(crate) fn first_hit(&self, place: &Similarity, from: Vec3, to: Vec3) -> Option<f32> {
        let (a, b) = local(place, from, to);
        self.vis.first_hit(a, b, [NONE, NONE]).map(|(_, t)| t)
    }
}

/// A world segment in the frame `place` maps to world (the parameter along it unchanged).
fn local(place: &Similarity, from: Vec3, to: Vec3) -> (Vec3, Vec3) {
    (
        crate::tables::closed::local_point(place, from),
        crate::tables::closed::local_point(place, to),
    )
}
