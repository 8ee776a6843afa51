//! Closed instances that block rays with their original's own polygons (see
//! [`Settings::blocking_polygons`](super::settings::Settings::blocking_polygons)): the
//! original is expanded once per level into its own frame, every instance inside it placed,
//! with a BVH over it; a segment is taken into a closed instance's frame and tested there,
//! as ray tracers instance geometry. Its shadows are then the contents' own, where `tau`
//! alone would shade like a uniform medium. An approximate instance's own polygons (its
//! subtree in the file, see [`own_blocking_polygons`]) are loaded the same way, one region
//! per instance, from its node instead of its original's root.
//!
//! Storage, from a region's first byte: the corners (12 floats per polygon, in the
//! original's frame, m), the corner counts (one byte each: the count, and [`TWO_SIDED`]),
//! the polygons' sides' areas summed in order (m^2, a two-sided polygon's twice, for drawing
//! points evenly over every side, see [`OriginalGeometry::sample`]), the BVH's nodes and its
//! order.

use super::error::HrError;
use super::layout::up;
use crate::bvh::{Bvh, BvhNode, BvhVisibility, PolygonSet};
use crate::geometry::Similarity;
use crate::image::{SceneSource, SceneView};
use crate::limits::{MAX_NODE_DEPTH, NONE};
use crate::{NodeId, OriginalId, PolyId, VertexId};
use glam::Vec3;

/// Most polygons an original may block with (the exchange notes where its rays land in 20
/// bits, see `exchange`).
pub(crate) const MAX_BLOCKING_POLYGONS: u32 = (1 << 20) - 1;

/// The polygons `original` blocks with when closed, if it does: at most `limit` (and
/// [`MAX_BLOCKING_POLYGONS`]) once expanded, and at least one.
pub(crate) fn blocking_polygons<S: SceneSource>(
    view: &SceneView<S>,
    original: u32,
    limit: u32,
) -> Result<Option<u32>, HrError> {
    let n = view.original(OriginalId(original))?.expanded_polygons;
    let limit = limit.min(MAX_BLOCKING_POLYGONS);
    Ok((n > 0 && n <= limit as u64).then_some(n as u32))
}

/// The polygons closed instance node `rec` blocks with of its own, if it does: an
/// approximate instance (its own subtree is in the file, its original only stands in for it
/// through the tables) of at most `limit` (and [`MAX_BLOCKING_POLYGONS`]) polygons once
/// expanded, and at least one. A ray then meets the leaves it really has where it stands,
/// not its original's placed there (another branch's sunflecks).
pub(crate) fn own_blocking_polygons<S: SceneSource>(
    view: &SceneView<S>,
    rec: &crate::image::NodeRecord,
    limit: u32,
) -> Result<Option<u32>, HrError> {
    let Some(id) = rec.instance() else {
        return Ok(None);
    };
    if view.instance(id)?.is_exact() {
        return Ok(None);
    }
    let n = rec.expanded_polygons;
    let limit = limit.min(MAX_BLOCKING_POLYGONS);
    Ok((n > 0 && n <= limit as u64).then_some(n as u32))
}

/// A count byte's flag: the polygon's material is two-sided.
const TWO_SIDED: u8 = 0x10;

/// Byte offsets of the parts of a region holding `n` polygons, from its start: corners,
/// counts, summed areas, BVH nodes, BVH order, end.
fn parts(n: u32) -> [usize; 6] {
    let corners = 0;
    let counts = corners + up(48 * n as usize);
    let areas = counts + up(n as usize);
    let nodes = areas + up(4 * n as usize);
    let order = nodes + up(crate::bvh::nodes_needed(n) * core::mem::size_of::<BvhNode>());
    let end = order + up(4 * n as usize);
    [corners, counts, areas, nodes, order, end]
}

/// Bytes of the region of an original of `n` polygons.
pub(crate) fn bytes_needed(n: u32) -> usize {
    parts(n)[5]
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
    let root = view.original(OriginalId(original))?.root;
    load_from(view, region, root, n)
}

/// Expands the subtree of node `root` (an original's root, or an approximate instance's
/// node: its own polygons, see [`own_blocking_polygons`]) of `n` polygons into `region`
/// (of [`bytes_needed`]`(n)` bytes), in the frame of `root`'s contents, and builds its BVH.
pub(crate) fn load_from<S: SceneSource>(
    view: &SceneView<S>,
    region: &mut [u8],
    root: u32,
    n: u32,
) -> Result<(), HrError> {
    let p = parts(n);
    if region.len() < p[5] {
        return Err(HrError::SceneTooLarge);
    }
    let (head, tail) = region.split_at_mut(p[3]);
    let (head, area_bytes) = head.split_at_mut(p[2]);
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
            let two = view
                .material_record(crate::MaterialId(pr[0].material))?
                .flags
                & crate::material::TWO_SIDED
                != 0;
            counts[written as usize] = c as u8 | if two { TWO_SIDED } else { 0 };
            written += 1;
        }
        Ok(())
    };
    // The root's own polygons, then its nodes in order; an instance inside is walked in its
    // own frame (an exact one: its original's nodes; an approximate one: its own subtree).
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
    // Areas summed in order.
    let areas: &mut [f32] = bytemuck::try_cast_slice_mut(&mut area_bytes[..4 * n as usize])
        .map_err(|_| HrError::SceneTooLarge)?;
    // Summed by sides: a two-sided polygon's area twice, so that points drawn by it are
    // spread evenly over every side (see `sample`).
    let mut sum = 0.0f32;
    for (k, a) in areas.iter_mut().enumerate() {
        let mut c = [Vec3::ZERO; 4];
        let m = polys.corners(k as u32, &mut c);
        let sides = if polys.counts[k] & TWO_SIDED != 0 {
            2.0
        } else {
            1.0
        };
        sum += sides * area_of(&c[..m]);
        *a = sum;
    }
    let (nodes, rest) = tail.split_at_mut(p[4] - p[3]);
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
        (c & !TWO_SIDED) as usize
    }
}

/// An original's polygons and BVH as loaded by [`load`].
#[derive(Clone, Copy)]
pub(crate) struct OriginalGeometry<'a> {
    vis: BvhVisibility<'a, RegionPolygons<'a>>,
    areas: &'a [f32],
}

/// A point drawn on an original's polygons (see [`OriginalGeometry::sample`]), in its
/// frame.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SurfacePoint {
    pub point: Vec3,
    /// Unit normal of the side drawn.
    pub normal: Vec3,
    pub polygon: u32,
}

/// Area of a planar convex polygon (m^2).
fn area_of(c: &[Vec3]) -> f32 {
    let mut a = Vec3::ZERO;
    for k in 1..c.len().saturating_sub(1) {
        a += (c[k] - c[0]).cross(c[k + 1] - c[0]);
    }
    0.5 * a.length()
}

impl<'a> OriginalGeometry<'a> {
    /// The geometry in `region` (see [`load`]); `None` if the region is not one.
    pub(crate) fn over(region: &'a [u8], n: u32) -> Option<Self> {
        let p = parts(n);
        if region.len() < p[5] || n == 0 {
            return None;
        }
        let corners: &[f32] = bytemuck::try_cast_slice(&region[..48 * n as usize]).ok()?;
        let counts = &region[p[1]..p[1] + n as usize];
        let areas: &[f32] = bytemuck::try_cast_slice(&region[p[2]..p[2] + 4 * n as usize]).ok()?;
        let nodes: &[BvhNode] = bytemuck::try_cast_slice(
            &region[p[3]..p[3] + crate::bvh::nodes_needed(n) * core::mem::size_of::<BvhNode>()],
        )
        .ok()?;
        let order: &[u32] = bytemuck::try_cast_slice(&region[p[4]..p[4] + 4 * n as usize]).ok()?;
        let bvh = Bvh::new_unchecked(nodes, order);
        Some(OriginalGeometry {
            vis: BvhVisibility::new(bvh, RegionPolygons { corners, counts }),
            areas,
        })
    }

    /// Polygon `q`'s unit front normal (in the original's frame; zero if it has none).
    pub(crate) fn normal(&self, q: u32) -> Vec3 {
        let mut c = [Vec3::ZERO; 4];
        let m = self.vis.polygons().corners(q, &mut c);
        if m < 3 {
            return Vec3::ZERO;
        }
        (c[1] - c[0]).cross(c[m - 1] - c[0]).normalize_or_zero()
    }

    /// Calls `f` with each polygon's area (m^2, in the original's frame), in order.
    pub(crate) fn each_area(&self, mut f: impl FnMut(f32)) {
        let polys = self.vis.polygons();
        let mut before = 0.0f32;
        for (k, &s) in self.areas.iter().enumerate() {
            let sides = if polys.counts[k] & TWO_SIDED != 0 {
                2.0
            } else {
                1.0
            };
            f((s - before) / sides);
            before = s;
        }
    }

    /// The area of the polygons' sides (m^2, in the original's frame): a two-sided polygon's
    /// twice, as [`Self::sample`] draws its sides.
    pub(crate) fn sides_area(&self) -> f32 {
        self.areas.last().copied().unwrap_or(0.0)
    }

    /// A point drawn evenly over every side of the polygons from three numbers in [0, 1):
    /// `a` picks the polygon and, for a two-sided one, the side (from where `a` falls
    /// within the polygon's share); `(u, v)` the point on it (uniform on a parallelogram or
    /// a triangle).
    pub(crate) fn sample(&self, a: f32, u: f32, v: f32) -> Option<SurfacePoint> {
        let total = self.sides_area();
        if total.is_nan() || total <= 0.0 {
            return None;
        }
        let target = a * total;
        let k = self
            .areas
            .partition_point(|&s| s <= target)
            .min(self.areas.len() - 1);
        let lo = if k == 0 { 0.0 } else { self.areas[k - 1] };
        let within = (target - lo) / (self.areas[k] - lo).max(f32::MIN_POSITIVE);
        let (point, normal) = self.point_on(k as u32, u, v)?;
        let two = self.vis.polygons().counts[k] & TWO_SIDED != 0;
        let normal = if two && within >= 0.5 {
            -normal
        } else {
            normal
        };
        Some(SurfacePoint {
            point,
            normal,
            polygon: k as u32,
        })
    }

    /// True when polygon `q`'s material is two-sided.
    pub(crate) fn two_sided(&self, q: u32) -> bool {
        self.vis
            .polygons()
            .counts
            .get(q as usize)
            .is_some_and(|&c| c & TWO_SIDED != 0)
    }

    /// Polygons.
    pub(crate) fn polygons(&self) -> u32 {
        self.areas.len() as u32
    }

    /// A point of polygon `q` from `(u, v)` in [0, 1) (uniform on a parallelogram or a
    /// triangle) and its unit front normal, in the original's frame; `None` for a degenerate
    /// or missing polygon.
    pub(crate) fn point_on(&self, q: u32, u: f32, v: f32) -> Option<(Vec3, Vec3)> {
        let mut c = [Vec3::ZERO; 4];
        let m = self.vis.polygons().corners(q, &mut c);
        if m < 3 {
            return None;
        }
        let normal = (c[1] - c[0]).cross(c[m - 1] - c[0]).normalize_or_zero();
        let point = if m == 3 {
            let (u, v) = if u + v > 1.0 {
                (1.0 - u, 1.0 - v)
            } else {
                (u, v)
            };
            c[0] + (c[1] - c[0]) * u + (c[2] - c[0]) * v
        } else {
            crate::sampling::point_on(&c[..4], u, v)
        };
        Some((point, normal))
    }

    /// Where the segment `from..to`, in the original's frame, first meets one of its
    /// polygons other than `skip` (its parameter).
    pub(crate) fn first_hit_local(&self, from: Vec3, to: Vec3, skip: u32) -> Option<f32> {
        self.vis.first_hit(from, to, [skip, NONE]).map(|(_, t)| t)
    }

    /// True when the segment `from..to` (world) meets a polygon of the instance placed by
    /// `place` (with the margins of [`BvhVisibility::blocker`]).
    pub(crate) fn blocks(&self, place: &Similarity, from: Vec3, to: Vec3) -> bool {
        let (a, b) = local(place, from, to);
        self.vis.blocker(a, b, [NONE, NONE]).is_some()
    }

    /// Where the segment `from..to` (world) first meets a polygon of the instance placed by
    /// `place` before the parameter `t_max`: the polygon (in the original's expanded order)
    /// and its parameter (0 at `from`, 1 at `to`).
    pub(crate) fn first_hit(
        &self,
        place: &Similarity,
        from: Vec3,
        to: Vec3,
        t_max: f32,
    ) -> Option<(u32, f32)> {
        let (a, b) = local(place, from, to);
        self.vis.first_hit_before(a, b, [NONE, NONE], t_max)
    }
}

/// A world segment in the frame `place` maps to world (the parameter along it unchanged).
fn local(place: &Similarity, from: Vec3, to: Vec3) -> (Vec3, Vec3) {
    (
        crate::tables::closed::local_point(place, from),
        crate::tables::closed::local_point(place, to),
    )
}
