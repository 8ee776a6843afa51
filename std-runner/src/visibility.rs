//! Visibility between two points by ray casting through an `obvhs` compressed wide BVH
//! (CWBVH) over the scene's polygons: the runner's implementation of the core's
//! [`Visibility`] trait.
//!
//! The BVH only culls; whether a polygon blocks a segment is decided by an exact test in
//! f64 on the original world-space corners ([`Prepared::crosses`]), so the answer is a
//! function of the geometry alone (not of the tree's shape, the build parameters or the
//! thread count). The same test over the polygons that reach a box
//! ([`ObvhsVisibility::candidates`], [`ObvhsVisibility::transmittance_among`]) gives the same
//! answers for every segment inside that box without walking the tree.
//!
//! Scale-freedom: the segment is parameterised by `t` in [0, 1] from `from` to `to`, and only
//! crossings with [`T_MARGIN`] < `t` < 1 - [`T_MARGIN`] count, a margin relative to the
//! segment's own length. The BVH is built in a normalised frame (scene centred, scaled by a
//! power of two to a unit half-extent) and its boxes are padded by 1e-5 of that unit, which
//! makes the f32 box tests conservative at any scene scale.

use crate::directional::DirectionalGrid;
use glam::{DVec3, UVec2, Vec3, Vec3A};
use hirad_core::visibility::Visibility;
use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb as BvhAabb;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::builder::build_cwbvh;
use obvhs::ray::Ray;
use std::fmt;
use std::time::Duration;

/// Crossings closer than this fraction of the segment's length to either end are ignored
/// (the surfaces the segment starts and ends on are skipped by id; this margin only absorbs
/// rounding where the segment meets a neighbouring polygon).
pub const T_MARGIN: f32 = 1e-5;

/// Padding of every primitive's box, in the normalised frame (scene half-extent = 1): keeps
/// the f32 slab tests of the BVH conservative for grazing rays and for ray directions whose
/// components are too small for obvhs to invert.
const BOX_PAD: f32 = 1e-5;

/// obvhs' CWBVH node test clamps the entry distance to at least 1e-4 (in ray units) and
/// ignores `Ray::tmin`. Rays are therefore given `(to - from) / RAY_STRETCH` as direction so
/// that the segment spans `0..RAY_STRETCH` and the clamp (1e-4 / 16 = 6.25e-6 of the segment)
/// lies below [`T_MARGIN`]. A power of two keeps the scaling exact.
const RAY_STRETCH: f32 = 16.0;

/// Most bytes per polygon that the directional grids may hold together (one grid takes
/// 75 to 100 on maize canopies: a few suns fit, a sky of a hundred directions would not).
pub const DIRECTIONAL_BYTES_PER_POLYGON: usize = 512;

/// Groups of coincident polygons larger than this are first tested as a whole (see
/// `ObvhsVisibility::slot_boxes`).
const GROUP_TEST: u32 = 4;

/// Why a polygon list cannot be used for visibility.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum VisibilityError {
    /// A polygon does not have 3 or 4 corners.
    Corners {
        /// Index of the polygon.
        polygon: usize,
        /// Its corner count.
        count: usize,
    },
    /// A corner is NaN or infinite.
    NonFinite {
        /// Index of the polygon.
        polygon: usize,
    },
    /// More polygons than `u32` ids can name.
    TooMany,
}

impl fmt::Display for VisibilityError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            VisibilityError::Corners { polygon, count } => {
                write!(
                    f,
                    "polygon {polygon} has {count} corners; 3 or 4 are needed"
                )
            }
            VisibilityError::NonFinite { polygon } => {
                write!(
                    f,
                    "polygon {polygon} has a corner that is not a finite number"
                )
            }
            VisibilityError::TooMany => f.write_str("too many polygons for 32-bit ids"),
        }
    }
}

impl std::error::Error for VisibilityError {}

/// Ray-cast visibility over a fixed list of triangles and quads (a quad is tested as the
/// triangles `a b c` and `a c d`). Polygon ids are indices into the list given to
/// [`ObvhsVisibility::new`]. Immutable after construction, hence `Sync`.
pub struct ObvhsVisibility {
    /// `None` when there are no polygons.
    bvh: Option<CwBvh>,
    /// The polygons prepared for the exact test, in the order of the tree's leaves: the
    /// polygons a leaf stands for lie side by side (one stream of memory per leaf, no
    /// lookups through ids).
    slotted: Vec<Slotted>,
    /// Polygon id -> its place in `slotted`.
    place: Vec<u32>,
    /// Padded boxes in the normalised frame, per polygon (for box queries).
    boxes: Vec<BvhAabb>,
    /// The BVH is built over distinct boxes: primitive slot `k` of the tree stands for the
    /// polygons `slotted[slots[k]..slots[k + 1]]`, all with the same box. Thousands of
    /// coincident polygons would otherwise give a tree deeper than obvhs' traversal stack
    /// (which then silently drops nodes).
    slots: Vec<u32>,
    /// Per slot of more than [`GROUP_TEST`] polygons, the exact world box of its polygons
    /// (m): a segment whose part inside it lies within [`T_MARGIN`] of an end crosses none of
    /// them, so thousands of coincident polygons cost one test, not thousands.
    slot_boxes: Vec<(DVec3, DVec3)>,
    /// Grids for rays along the directions of the scene's sources (see
    /// [`ObvhsVisibility::with_directions`]).
    directional: Vec<DirectionalGrid>,
    /// Centre of the normalised frame (m).
    centre: Vec3,
    /// World-to-normalised scale (1/m), a power of two.
    inv_scale: f32,
}

impl fmt::Debug for ObvhsVisibility {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("ObvhsVisibility")
            .field("polygons", &self.place.len())
            .field("centre", &self.centre)
            .field("inv_scale", &self.inv_scale)
            .finish()
    }
}

impl ObvhsVisibility {
    /// Builds the BVH over `polygons` (world corners, 3 or 4 each; polygon id = index).
    pub fn new<P: AsRef<[Vec3]>>(polygons: &[P]) -> Result<Self, VisibilityError> {
        if polygons.len() >= u32::MAX as usize {
            return Err(VisibilityError::TooMany);
        }
        let mut corners = Vec::with_capacity(polygons.len());
        let mut counts = Vec::with_capacity(polygons.len());
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for (polygon, p) in polygons.iter().enumerate() {
            let p = p.as_ref();
            if p.len() != 3 && p.len() != 4 {
                return Err(VisibilityError::Corners {
                    polygon,
                    count: p.len(),
                });
            }
            if p.iter().any(|c| !c.is_finite()) {
                return Err(VisibilityError::NonFinite { polygon });
            }
            let mut c = [p[p.len() - 1]; 4];
            c[..p.len()].copy_from_slice(p);
            for v in p {
                lo = lo.min(*v);
                hi = hi.max(*v);
            }
            corners.push(c);
            counts.push(p.len() as u8);
        }
        if corners.is_empty() {
            return Ok(ObvhsVisibility {
                bvh: None,
                slotted: Vec::new(),
                place: Vec::new(),
                boxes: Vec::new(),
                slots: vec![0],
                slot_boxes: Vec::new(),
                directional: Vec::new(),
                centre: Vec3::ZERO,
                inv_scale: 1.0,
            });
        }
        // Halve before subtracting so that opposite extremes near f32::MAX do not overflow.
        let centre = lo * 0.5 + hi * 0.5;
        let half = (hi * 0.5 - lo * 0.5).max_element();
        let inv_scale = inv_power_of_two(half);
        let boxes: Vec<BvhAabb> = corners
            .iter()
            .zip(&counts)
            .map(|(c, &n)| {
                let mut b = BvhAabb::INVALID;
                for v in &c[..n as usize] {
                    b.extend(Vec3A::from((*v - centre) * inv_scale));
                }
                BvhAabb::new(b.min - BOX_PAD, b.max + BOX_PAD)
            })
            .collect();
        // Distinct boxes, in order of first appearance (deterministic).
        let mut order: Vec<u32> = (0..boxes.len() as u32).collect();
        let key = |b: &BvhAabb| {
            [
                b.min.x.to_bits(),
                b.min.y.to_bits(),
                b.min.z.to_bits(),
                b.max.x.to_bits(),
                b.max.y.to_bits(),
                b.max.z.to_bits(),
            ]
        };
        order.sort_by_key(|&i| (key(&boxes[i as usize]), i));
        let (mut groups, mut members, mut unique) = (vec![0u32], Vec::new(), Vec::new());
        for (n, &i) in order.iter().enumerate() {
            if n > 0 && key(&boxes[order[n - 1] as usize]) != key(&boxes[i as usize]) {
                groups.push(members.len() as u32);
            }
            if n == 0 || key(&boxes[order[n - 1] as usize]) != key(&boxes[i as usize]) {
                unique.push(boxes[i as usize]);
            }
            members.push(i);
        }
        groups.push(members.len() as u32);
        let group_boxes: Vec<(DVec3, DVec3)> = groups
            .windows(2)
            .map(|w| {
                let (mut lo, mut hi) =
                    (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
                for &m in &members[w[0] as usize..w[1] as usize] {
                    for v in &corners[m as usize][..counts[m as usize] as usize] {
                        lo = lo.min(v.as_dvec3());
                        hi = hi.max(v.as_dvec3());
                    }
                }
                // Widened a little against rounding (relative to the box and its place).
                let pad =
                    (hi - lo).max_element() * 1e-6 + lo.abs().max(hi.abs()).max_element() * 1e-12;
                (lo - DVec3::splat(pad), hi + DVec3::splat(pad))
            })
            .collect();
        let bvh = build_cwbvh(
            &unique,
            BvhBuildParams::medium_build(),
            &mut Duration::default(),
        );
        // The polygons in the order of the tree's primitive slots (each group once; any the
        // tree did not take go last, reachable by id only).
        let (mut order, mut slots, mut slot_boxes) = (Vec::new(), vec![0u32], Vec::new());
        let mut place = vec![u32::MAX; corners.len()];
        for &g in &bvh.primitive_indices {
            let g = g as usize;
            for &id in &members[groups[g] as usize..groups[g + 1] as usize] {
                if place[id as usize] == u32::MAX {
                    place[id as usize] = order.len() as u32;
                }
                order.push(id);
            }
            slots.push(order.len() as u32);
            slot_boxes.push(group_boxes[g]);
        }
        for id in 0..corners.len() as u32 {
            if place[id as usize] == u32::MAX {
                place[id as usize] = order.len() as u32;
                order.push(id);
            }
        }
        let slotted = order
            .iter()
            .map(|&id| Slotted {
                corners: corners[id as usize],
                id,
                quad: counts[id as usize] == 4,
            })
            .collect();
        Ok(ObvhsVisibility {
            bvh: Some(bvh),
            slotted,
            place,
            boxes,
            slots,
            slot_boxes,
            directional: Vec::new(),
            centre,
            inv_scale,
        })
    }

    /// Adds a grid of the polygons projected along each of `directions` (unit directions of
    /// sources: the scene's suns), in order, while the grids together hold at most
    /// [`DIRECTIONAL_BYTES_PER_POLYGON`] bytes per polygon (or 16 MiB): rays along them
    /// ([`Visibility::transmittance_towards`]) then test the few polygons of one cell
    /// instead of walking the BVH, with the same exact test and so the same answers; rays
    /// along other directions walk the BVH. `polygons` are those given to
    /// [`ObvhsVisibility::new`] (a list of another length adds no grid).
    pub fn with_directions<P: AsRef<[Vec3]>>(
        mut self,
        polygons: &[P],
        directions: &[Vec3],
    ) -> Self {
        if polygons.len() != self.len() {
            // Not the polygons the caster was built over: no grid rather than wrong ids.
            return self;
        }
        let budget = (DIRECTIONAL_BYTES_PER_POLYGON * polygons.len()).max(16 << 20);
        for &d in directions {
            if self.directional.iter().any(|g| g.runs_along(d)) {
                continue;
            }
            let Some(g) = DirectionalGrid::new(polygons, d) else {
                continue;
            };
            if self.directional_bytes() + g.bytes() > budget {
                break;
            }
            self.directional.push(g);
        }
        self
    }

    /// Bytes held by the directional grids.
    pub fn directional_bytes(&self) -> usize {
        self.directional.iter().map(DirectionalGrid::bytes).sum()
    }

    /// Whether the segment `o + t d` can cross a polygon of slot `k` at
    /// `T_MARGIN < t < 1 - T_MARGIN` (always true for small slots, which are tested
    /// polygon by polygon anyway).
    #[inline]
    fn slot_reachable(&self, k: usize, o: DVec3, d: DVec3) -> bool {
        if self.slots[k + 1] - self.slots[k] <= GROUP_TEST {
            return true;
        }
        let (lo, hi) = self.slot_boxes[k];
        let m = 0.5 * T_MARGIN as f64;
        let (mut t0, mut t1) = (m, 1.0 - m);
        for k in 0..3 {
            if d[k] == 0.0 {
                if o[k] < lo[k] || o[k] > hi[k] {
                    return false;
                }
            } else {
                let (a, b) = ((lo[k] - o[k]) / d[k], (hi[k] - o[k]) / d[k]);
                t0 = t0.max(a.min(b));
                t1 = t1.min(a.max(b));
            }
        }
        t0 <= t1
    }

    /// Number of polygons.
    pub fn len(&self) -> usize {
        self.place.len()
    }

    /// True when there are no polygons (nothing ever blocks).
    pub fn is_empty(&self) -> bool {
        self.place.is_empty()
    }

    /// The polygons that tree primitive slot `k` stands for (see `slots`).
    #[inline]
    fn slot(&self, k: usize) -> &[Slotted] {
        &self.slotted[self.slots[k] as usize..self.slots[k + 1] as usize]
    }

    /// The nearest crossing of polygon `id` by the segment `o + t d`, if any.
    #[inline]
    fn crossing_of(&self, id: usize, o: DVec3, d: DVec3) -> Option<f64> {
        self.slotted[self.place[id] as usize].crossing(o, d)
    }

    /// True when polygon `id` crosses the open segment `o + t d`, `T_MARGIN < t < 1 - T_MARGIN`.
    #[inline]
    fn blocks(&self, id: usize, o: DVec3, d: DVec3) -> bool {
        self.slotted[self.place[id] as usize].crosses(o, d)
    }

    /// Writes into `out` (cleared first, ascending) every polygon other than `skip` whose box
    /// overlaps the box `lo..hi`: a superset of the polygons that can block any segment lying
    /// inside that box. Empty means every such segment is clear.
    pub fn candidates(&self, lo: Vec3, hi: Vec3, skip: [u32; 2], out: &mut Vec<u32>) {
        out.clear();
        let Some(bvh) = &self.bvh else {
            return;
        };
        let (l, h) = (
            (lo - self.centre) * self.inv_scale,
            (hi - self.centre) * self.inv_scale,
        );
        if !l.is_finite() || !h.is_finite() {
            out.extend((0..self.len() as u32).filter(|id| !skip.contains(id)));
            return;
        }
        let query = BvhAabb::new(Vec3A::from(l) - BOX_PAD, Vec3A::from(h) + BOX_PAD);
        let mut state = bvh.new_traversal(Vec3A::ZERO);
        let mut node;
        obvhs::traverse!(
            bvh,
            node,
            state,
            node.intersect_aabb(&query, state.oct_inv4),
            {
                for p in self.slot(state.primitive_id as usize) {
                    if !skip.contains(&p.id) && query.intersect_aabb(&self.boxes[p.id as usize]) {
                        out.push(p.id);
                    }
                }
            }
        );
        out.sort_unstable();
    }

    /// [`Visibility::transmittance`] testing only the polygons in `candidates` (as filled by
    /// [`ObvhsVisibility::candidates`] for a box that contains the segment): the same answer,
    /// without walking the BVH.
    #[inline]
    pub fn transmittance_among(&self, from: Vec3, to: Vec3, candidates: &[u32]) -> f32 {
        let (o, d) = (from.as_dvec3(), (to - from).as_dvec3());
        let blocked = candidates.iter().any(|&id| self.blocks(id as usize, o, d));
        if blocked { 0.0 } else { 1.0 }
    }
}

/// The smallest power of two `s` with `half * s <= 1` clamped to the normal f32 range,
/// so that the normalised frame is an exact rescaling.
fn inv_power_of_two(half: f32) -> f32 {
    if !half.is_finite() || half <= 0.0 {
        return 1.0;
    }
    let e = half.log2().ceil().clamp(-120.0, 120.0);
    2f32.powi(-(e as i32))
}

/// A polygon for the exact segment test: its corners as given (the triangles `a b c` and,
/// for quads, `a c d` are prepared in f64 when tested: four times less memory to read than
/// keeping them prepared, and memory is what a ray waits for in a large scene) and its id.
#[derive(Clone, Copy, Debug)]
struct Slotted {
    corners: [Vec3; 4],
    id: u32,
    quad: bool,
}

impl Slotted {
    /// Triangle `k` (0: `a b c`, 1: `a c d`), prepared.
    #[inline]
    fn triangle(&self, k: usize) -> Prepared {
        let [a, b, c, d] = self.corners.map(|v| v.as_dvec3());
        if k == 0 {
            Prepared::new(a, b, c)
        } else {
            Prepared::new(a, c, d)
        }
    }

    /// The nearest crossing by the segment `o + t d`, if any (see [`Prepared::crossing`]).
    #[inline]
    fn crossing(&self, o: DVec3, d: DVec3) -> Option<f64> {
        let a = self.triangle(0).crossing(o, d);
        let b = if self.quad {
            self.triangle(1).crossing(o, d)
        } else {
            None
        };
        match (a, b) {
            (Some(x), Some(y)) => Some(x.min(y)),
            (x, y) => x.or(y),
        }
    }

    /// Whether the segment `o + t d` crosses it (see [`Prepared::crosses`]).
    #[inline]
    fn crosses(&self, o: DVec3, d: DVec3) -> bool {
        self.triangle(0).crosses(o, d) || (self.quad && self.triangle(1).crosses(o, d))
    }
}

/// A triangle prepared for the exact segment test, in f64: a corner, the unnormalised
/// normal `n = (b - a) x (c - a)`, and the dual edge vectors that give barycentric
/// coordinates of a point of its plane by two dot products.
#[derive(Clone, Copy, Debug)]
pub struct Prepared {
    a: DVec3,
    n: DVec3,
    du: DVec3,
    dv: DVec3,
}

impl Prepared {
    /// Prepares the triangle `a b c` (a degenerate one never blocks).
    pub fn new(a: DVec3, b: DVec3, c: DVec3) -> Prepared {
        let (e1, e2) = (b - a, c - a);
        let n = e1.cross(e2);
        let n2 = n.length_squared();
        if !(n2 > 0.0 && n2.is_finite()) {
            return Prepared {
                a,
                n: DVec3::ZERO,
                du: DVec3::ZERO,
                dv: DVec3::ZERO,
            };
        }
        Prepared {
            a,
            n,
            du: e2.cross(n) / n2,
            dv: n.cross(e1) / n2,
        }
    }

    /// The parameter t at which the segment `o + t d` crosses the triangle (edges included),
    /// if `T_MARGIN < t < 1 - T_MARGIN`: [`Prepared::crosses`] with the crossing's place.
    #[inline]
    pub fn crossing(&self, o: DVec3, d: DVec3) -> Option<f64> {
        let so = self.n.dot(o - self.a);
        let nd = self.n.dot(d);
        let se = so + nd;
        if nd == 0.0 || (so > 0.0 && se > 0.0) || (so < 0.0 && se < 0.0) {
            return None;
        }
        let t = -so / nd;
        let m = T_MARGIN as f64;
        if !(t > m && t < 1.0 - m) {
            return None;
        }
        let r = o + d * t - self.a;
        let (u, v) = (r.dot(self.du), r.dot(self.dv));
        (u >= 0.0 && v >= 0.0 && u + v <= 1.0).then_some(t)
    }

    /// Does the segment `o + t d` cross the triangle (edges included) with
    /// `T_MARGIN < t < 1 - T_MARGIN`? A segment parallel to the plane never crosses it; one
    /// whose ends lie strictly on one side is rejected before any division. No absolute
    /// tolerance.
    #[inline]
    pub fn crosses(&self, o: DVec3, d: DVec3) -> bool {
        let so = self.n.dot(o - self.a);
        let nd = self.n.dot(d);
        let se = so + nd;
        if nd == 0.0 || (so > 0.0 && se > 0.0) || (so < 0.0 && se < 0.0) {
            return false;
        }
        let t = -so / nd;
        let m = T_MARGIN as f64;
        if !(t > m && t < 1.0 - m) {
            return false;
        }
        let r = o + d * t - self.a;
        let (u, v) = (r.dot(self.du), r.dot(self.dv));
        u >= 0.0 && v >= 0.0 && u + v <= 1.0
    }
}

impl Visibility for ObvhsVisibility {
    /// 0.0 when a polygon not named in `skip` crosses the open segment (see [`T_MARGIN`]),
    /// else 1.0. A degenerate or non-finite segment is never blocked.
    fn transmittance(&self, from: Vec3, to: Vec3, skip: [u32; 2]) -> f32 {
        let Some(bvh) = &self.bvh else {
            return 1.0;
        };
        let d = to - from;
        if !from.is_finite() || !d.is_finite() || d == Vec3::ZERO {
            return 1.0;
        }
        let origin = (from - self.centre) * self.inv_scale;
        let dir = d * (self.inv_scale / RAY_STRETCH);
        if !origin.is_finite() || dir == Vec3::ZERO {
            // The segment is below f32 resolution in the normalised frame: test every
            // polygon directly.
            return self.brute_force(from, to, skip);
        }
        let ray = Ray::new(
            Vec3A::from(origin),
            Vec3A::from(dir),
            0.0,
            RAY_STRETCH * (1.0 - T_MARGIN),
        );
        let (o, dd) = (from.as_dvec3(), d.as_dvec3());
        let clear = bvh.ray_traverse_miss(ray, |_, k| {
            let blocked = self.slot_reachable(k, o, dd)
                && self
                    .slot(k)
                    .iter()
                    .any(|p| p.id != skip[0] && p.id != skip[1] && p.crosses(o, dd));
            if blocked { 0.0 } else { f32::INFINITY }
        });
        if clear { 1.0 } else { 0.0 }
    }

    /// Along a direction with a grid, the polygons of the origin's cell only; else the BVH.
    fn transmittance_towards(&self, from: Vec3, to: Vec3, towards: Vec3, skip: [u32; 2]) -> f32 {
        if let Some(g) = self.directional.iter().find(|g| g.runs_along(towards))
            && from.is_finite()
            && to.is_finite()
        {
            let (o, d) = (from.as_dvec3(), (to - from).as_dvec3());
            let hit = g.any(o, d, |id| {
                id != skip[0] && id != skip[1] && self.blocks(id as usize, o, d)
            });
            if let Some(blocked) = hit {
                return if blocked { 0.0 } else { 1.0 };
            }
        }
        self.transmittance(from, to, skip)
    }

    /// The nearest crossing by the same exact test as [`Visibility::transmittance`]; ties
    /// between polygons crossed at the same t go to the lower id.
    fn first_hit(&self, from: Vec3, to: Vec3, skip: [u32; 2]) -> Option<(u32, f32)> {
        let bvh = self.bvh.as_ref()?;
        let d = to - from;
        if !from.is_finite() || !d.is_finite() || d == Vec3::ZERO {
            return None;
        }
        let origin = (from - self.centre) * self.inv_scale;
        let dir = d * (self.inv_scale / RAY_STRETCH);
        let (o, dd) = (from.as_dvec3(), d.as_dvec3());
        if !origin.is_finite() || dir == Vec3::ZERO {
            return self.first_hit_brute_force(from, to, skip);
        }
        let ray = Ray::new(
            Vec3A::from(origin),
            Vec3A::from(dir),
            0.0,
            RAY_STRETCH * (1.0 - T_MARGIN),
        );
        let mut best: Option<(u32, f64)> = None;
        let mut hit = obvhs::ray::RayHit::none();
        bvh.ray_traverse(ray, &mut hit, |_, k| {
            let mut nearest = f32::INFINITY;
            if !self.slot_reachable(k, o, dd) {
                return nearest;
            }
            for p in self.slot(k) {
                let id = p.id;
                if id == skip[0] || id == skip[1] {
                    continue;
                }
                if let Some(t) = p.crossing(o, dd) {
                    if best.is_none_or(|(bid, bt)| t < bt || (t == bt && id < bid)) {
                        best = Some((id, t));
                    }
                    // Keep looking a little beyond: f32 traversal against f64 crossings.
                    nearest = nearest.min((t as f32 * RAY_STRETCH) * (1.0 + 1e-5));
                }
            }
            nearest
        });
        best.map(|(id, t)| (id, t as f32))
    }
}

impl ObvhsVisibility {
    /// The same answer as [`Visibility::transmittance`] by testing every polygon (no BVH):
    /// the reference the BVH is checked against, and the fallback for segments too short for
    /// the BVH's f32 frame.
    pub fn brute_force(&self, from: Vec3, to: Vec3, skip: [u32; 2]) -> f32 {
        let (o, d) = (from.as_dvec3(), (to - from).as_dvec3());
        let blocked = (0..self.len())
            .any(|id| id as u32 != skip[0] && id as u32 != skip[1] && self.blocks(id, o, d));
        if blocked { 0.0 } else { 1.0 }
    }

    /// The same answer as [`Visibility::first_hit`] by testing every polygon (no BVH).
    pub fn first_hit_brute_force(
        &self,
        from: Vec3,
        to: Vec3,
        skip: [u32; 2],
    ) -> Option<(u32, f32)> {
        let (o, d) = (from.as_dvec3(), (to - from).as_dvec3());
        let mut best: Option<(u32, f64)> = None;
        for id in 0..self.len() {
            if id as u32 == skip[0] || id as u32 == skip[1] {
                continue;
            }
            if let Some(t) = self.crossing_of(id, o, d)
                && best.is_none_or(|(_, bt)| t < bt)
            {
                best = Some((id as u32, t));
            }
        }
        best.map(|(id, t)| (id, t as f32))
    }
}

#[cfg(test)]
#[path = "visibility_tests.rs"]
mod tests;
