//! Kernels of clusters seen from a point: a small cluster polygon by polygon (the exact form
//! factors, solid angles and vector form factors of its polygons that face the point, and
//! visibility rays drawn to them by weight), a larger one as the box of uniform radiance its
//! surfaces fill (its silhouette's form factor).

use super::ids::{Elem, Kind};
use super::state::State;
use crate::formfactor::{facing_side, point_polygon, point_polygon_light};
use crate::limits::NONE;
use crate::sampling::{hash3, point_on, unit2};
use crate::visibility::Visibility;
use core::f32::consts::PI;
use glam::Vec3;

/// Clusters of at most this many polygons are seen polygon by polygon (exactly) from a
/// receiver; larger ones as a point-like volume.
pub(crate) const SMALL_CLUSTER: u32 = 32;

/// True for a cluster whose polygons links evaluate one by one.
pub(crate) fn small_cluster(st: &State, ws: &[u8], e: Elem) -> bool {
    e.kind() == Kind::Cluster && st.cluster(ws, e.index()).polygons <= SMALL_CLUSTER
}

/// The polygons of cluster `e` and the side of each that faces `x` (None: `x` in its plane
/// or that side does not emit), through `f(index in the cluster, polygon, corners)`.
pub(crate) fn each_facing(
    st: &State,
    ws: &[u8],
    e: Elem,
    x: Vec3,
    mut f: impl FnMut(u32, u32, &[Vec3]),
) {
    let c = st.cluster(ws, e.index());
    for k in 0..c.polygons {
        let (poly, corners, n) = cluster_polygon(st, ws, c.first_polygon + k);
        let rec = st.polygon(ws, poly);
        let Some(side) = facing_side(x, corners[0], Vec3::from(rec.normal)) else {
            continue;
        };
        if side >= State::sides(Elem(rec.root)) {
            continue;
        }
        f(k, poly, &corners[..n]);
    }
}

/// The input polygon at position `k` of the cluster order, with its corners and their count.
pub(crate) fn cluster_polygon(st: &State, ws: &[u8], k: u32) -> (u32, [Vec3; 4], usize) {
    let poly = st.ordered(ws, k);
    let p = st.patch(ws, Elem(st.polygon(ws, poly).root));
    let mut corners = [Vec3::ZERO; 4];
    for (c, src) in corners.iter_mut().zip(p.corners) {
        *c = src.into();
    }
    (poly, corners, p.corner_count())
}

/// What a small cluster's polygons facing a point bring it, polygon by polygon: each one's
/// weight (its form factor or solid angle at the point) and where it sits in the cluster,
/// so that visibility rays go to the polygons in proportion to what they bring. (Rays to
/// points anywhere in the cluster would count its faces turned away, hidden behind its own
/// front, as shadow: a block seen from beside another got about half its light.)
pub(crate) struct Facing {
    pub count: usize,
    at: [u32; SMALL_CLUSTER as usize],
    weight: [f32; SMALL_CLUSTER as usize],
    pub total: f32,
}

impl Facing {
    pub fn new() -> Self {
        Facing {
            count: 0,
            at: [0; SMALL_CLUSTER as usize],
            weight: [0.0; SMALL_CLUSTER as usize],
            total: 0.0,
        }
    }

    pub fn push(&mut self, k: u32, w: f32) {
        if w > 0.0 && self.count < self.at.len() {
            self.at[self.count] = k;
            self.weight[self.count] = w;
            self.count += 1;
            self.total += w;
        }
    }

    /// Fraction of the light of the facing polygons that reaches `x` unblocked: `rays`
    /// rays, each to a polygon drawn by weight and a point on it in front of the plane
    /// through `x` with normal `nr` (when given); and two of the polygon sides they reached,
    /// drawn by what they let through (see `Link::witness`).
    #[allow(clippy::too_many_arguments)]
    pub fn visible_witnessed<V: Visibility + ?Sized>(
        &self,
        st: &State,
        ws: &[u8],
        e: Elem,
        x: Vec3,
        nr: Option<Vec3>,
        from: u32,
        seed: u32,
        rays: u32,
        vis: &V,
    ) -> (f32, Witnesses) {
        let mut wit = Witnesses::EMPTY;
        if self.count == 0 || self.total <= 0.0 {
            return (1.0, wit);
        }
        let first = st.cluster(ws, e.index()).first_polygon;
        let mut seen = 0.0f32;
        for j in 0..rays {
            let h = hash3(seed, j, 0xB7);
            let target = (h >> 8) as f32 * (1.0 / 16_777_216.0) * self.total;
            let mut pick = self.count - 1;
            let mut acc = 0.0f32;
            for i in 0..self.count {
                acc += self.weight[i];
                if target < acc {
                    pick = i;
                    break;
                }
            }
            let (poly, corners, n) = cluster_polygon(st, ws, first + self.at[pick]);
            let mut y = Vec3::ZERO;
            for t in 0..4 {
                let (u, v) = unit2(hash3(h, t, 0xB8));
                y = point_on(&corners[..n], u, v);
                if nr.is_none_or(|nr| nr.dot(y - x) > 0.0) {
                    break;
                }
            }
            let t = vis.transmittance(x, y, [from, poly]);
            seen += t;
            let normal = Vec3::from(st.polygon(ws, poly).normal);
            if let Some(side) = facing_side(x, corners[0], normal) {
                wit.offer([poly | ((side as u32) << 31); 2], t, hash3(h, j, 0x3E));
            }
        }
        (seen / rays.max(1) as f32, wit)
    }
}

/// The exact form factor from a point (normal `nr`) to the polygons of a cluster that face
/// it, polygon by polygon.
pub(crate) fn cluster_form_factor(st: &State, ws: &[u8], e: Elem, x: Vec3, nr: Vec3) -> Facing {
    let mut out = Facing::new();
    each_facing(st, ws, e, x, |k, _, c| out.push(k, point_polygon(x, nr, c)));
    out
}

/// True when `x` lies outside the box (so that the box's faces seen from it are a proper
/// silhouette).
pub(crate) fn outside(x: Vec3, min: Vec3, max: Vec3) -> bool {
    x.cmplt(min).any() || x.cmpgt(max).any()
}

/// The faces of a box that face the outside point `x` (at most three), through `f`.
pub(crate) fn box_faces(x: Vec3, min: Vec3, max: Vec3, mut f: impl FnMut(&[Vec3; 4])) {
    for axis in 0..3 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        if max[u] <= min[u] || max[v] <= min[v] {
            continue;
        }
        let at = if x[axis] > max[axis] {
            max[axis]
        } else if x[axis] < min[axis] {
            min[axis]
        } else {
            continue;
        };
        let mut corners = [Vec3::ZERO; 4];
        for (k, (a, b)) in [
            (min[u], min[v]),
            (max[u], min[v]),
            (max[u], max[v]),
            (min[u], max[v]),
        ]
        .into_iter()
        .enumerate()
        {
            corners[k][axis] = at;
            corners[k][u] = a;
            corners[k][v] = b;
        }
        f(&corners);
    }
}

/// Form factor from a point (normal `n`) outside a box to the box's silhouette.
pub(crate) fn box_form_factor(x: Vec3, n: Vec3, min: Vec3, max: Vec3) -> f32 {
    let mut sum = 0.0f32;
    box_faces(x, min, max, |c| sum += point_polygon(x, n, c));
    sum.min(1.0)
}

/// The solid angle of a box seen from the outside point `x`, over pi (its fluence factor:
/// at most 4).
pub(crate) fn box_fluence(x: Vec3, min: Vec3, max: Vec3) -> f32 {
    let mut sum = 0.0f32;
    box_faces(x, min, max, |c| sum += point_polygon_light(x, c).0);
    (sum / PI).min(4.0)
}

/// Where a point receives: on one side (the plane's normal), on the sides of the polygon
/// it lies on (its normal and how many sides it has), or from every direction alike (a
/// closed instance: what it intercepts from a direction is the light's flux density
/// across that direction times its cross-section there, so a polygon brings its solid
/// angle over pi, the fluence, not its cosine-weighted form factor).
#[derive(Clone, Copy, Debug)]
pub(crate) enum Plane {
    Facing(Vec3),
    Sides(Vec3, usize),
    Sphere,
}

/// Two polygon sides drawn among the samples of a gathered link, each with probability its
/// share of their summed contributions `total` (see `Link::witness`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Witnesses {
    pub total: f32,
    pub pick: [u32; 2],
}

impl Witnesses {
    pub(crate) const EMPTY: Witnesses = Witnesses {
        total: 0.0,
        pick: [NONE; 2],
    };

    /// Offers `pick` (a side, or another set's picks) with weight `w` (`h`: the draws).
    pub(crate) fn offer(&mut self, pick: [u32; 2], w: f32, h: u32) {
        if w.is_nan() || w <= 0.0 {
            return;
        }
        self.total += w;
        for (r, mine) in self.pick.iter_mut().enumerate() {
            if pick[r] != NONE && unit2(hash3(h, r as u32, 0x3B)).0 * self.total < w {
                *mine = pick[r];
            }
        }
    }
}

/// What the surfaces of cluster `e` bring the point `x`, polygon by polygon, estimated by
/// descent: each of `rays` samples walks down `e`'s tree choosing a child in proportion to
/// a cheap guess of what it brings (its area over its squared distance, nothing from a box
/// wholly behind a receiving plane), ends on one polygon and takes its exact form factor to
/// the receiving side(s) at `x` (summed over the sides a receiving polygon has) times one
/// visibility ray to it (none without `occlude`), divided by the probability of the walk. The mean is the visible
/// form factor of the cluster's polygons, unbiased whatever the guesses: close by, a volume
/// of uniform radiance misjudges both how much its near and far leaves bring and how much of
/// them `x` sees (a plant's neighbours got a quarter of its light). Returns the estimate, the
/// light's mean direction (towards the emitter; length: its collimation), the same
/// without occlusion, and two of the polygon sides its samples met, drawn by their
/// contributions (see `Link::witness`).
#[allow(clippy::too_many_arguments)]
pub(crate) fn gathered<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    e: Elem,
    x: Vec3,
    plane: Plane,
    skip: u32,
    seed: u32,
    rays: u32,
    occlude: bool,
    vis: &V,
) -> (f32, Vec3, f32, Witnesses) {
    let mut wit = Witnesses::EMPTY;
    let nr = match plane {
        Plane::Facing(n) => Some(n),
        Plane::Sides(n, 1) => Some(n),
        Plane::Sides(..) | Plane::Sphere => None,
    };
    let n = rays.max(1);
    let (mut sum, mut dir, mut open) = (0.0f32, Vec3::ZERO, 0.0f32);
    for j in 0..n {
        let mut h = hash3(seed, j, 0xDE5C);
        let mut cur = e;
        let mut weight = 1.0f32;
        // Down to a polygon.
        let mut found = false;
        for _ in 0..4096 {
            if cur.kind() != Kind::Cluster {
                found = true;
                break;
            }
            let c = st.cluster(ws, cur.index());
            let mut total = 0.0f32;
            let mut guesses = [0.0f32; 16];
            let kids = c.child_count.min(16);
            for k in 0..kids {
                let g = guess(st, ws, st.child(ws, c.children + k), x, plane);
                guesses[k as usize] = g;
                total += g;
            }
            if total <= 0.0 || !total.is_finite() {
                break;
            }
            h = hash3(h, cur.0, 0xD1);
            let target = (h >> 8) as f32 * (1.0 / 16_777_216.0) * total;
            let (mut acc, mut pick) = (0.0f32, NONE);
            for k in 0..kids {
                let g = guesses[k as usize];
                if g <= 0.0 {
                    continue;
                }
                pick = k;
                acc += g;
                if target < acc {
                    break;
                }
            }
            if pick == NONE {
                break;
            }
            weight *= total / guesses[pick as usize];
            cur = st.child(ws, c.children + pick);
        }
        if !found {
            continue;
        }
        // One polygon (a root patch).
        let p = st.patch(ws, cur);
        let Some((value, side, (corners, m))) = polygon_value(st, ws, cur, x, plane) else {
            continue;
        };
        let corners = &corners[..m];
        let (omega, phi) = point_polygon_light(x, corners);
        let towards = if omega.is_finite() && omega > 0.0 {
            phi * (PI / omega)
        } else {
            Vec3::ZERO
        };
        let mut y = corners[0];
        for t in 0..4 {
            let (u, v) = unit2(hash3(h, t, 0xB8));
            y = point_on(corners, u, v);
            if nr.is_none_or(|nr| nr.dot(y - x) > 0.0) {
                break;
            }
        }
        let seen = if occlude {
            vis.transmittance(x, y, [skip, p.poly])
        } else {
            1.0
        };
        open += weight * value;
        sum += weight * value * seen;
        dir += towards * (weight * value * seen);
        let id = p.poly | ((side as u32) << 31);
        wit.offer([id; 2], weight * value * seen, hash3(h, j, 0x3A));
    }
    let inv = 1.0 / n as f32;
    let mean = if sum > 0.0 { dir / sum } else { Vec3::ZERO };
    (sum * inv, mean, open * inv, wit)
}

/// The area through which cluster `c`'s polygons take a cone of light of unit flux density
/// whose axis and collimation are `dir`'s (m^2): each polygon's area times its share on
/// every side it has (see `oriented::share`), so that a link's power divided by it is the
/// flux density that hands its polygons exactly that power.
pub(crate) fn shared_area(st: &State, ws: &[u8], cluster: u32, dir: Vec3) -> f32 {
    let c = st.cluster(ws, cluster);
    let collimation = dir.length().min(1.0);
    let axis = dir.normalize_or_zero();
    let mut sum = 0.0f32;
    for k in c.first_polygon..c.first_polygon + c.polygons {
        let poly = st.ordered(ws, k);
        let rec = st.polygon(ws, poly);
        let root = Elem(rec.root);
        let t = if collimation > 0.0 {
            Vec3::from(rec.normal).dot(axis)
        } else {
            0.0
        };
        let p = st.patch(ws, root);
        let mut share = super::cone::cone_share(collimation, t);
        if State::sides(root) == 2 {
            share += super::cone::cone_share(collimation, -t);
        }
        sum += p.area * share;
    }
    sum
}

/// What element `e` may bring the point `x` (receiving `plane`), to draw from: close by, a
/// polygon's exact form factor or a cluster's box's; farther, a bound (area times the
/// largest cosine at `x` over pi times the squared distance to its box, at most 1);
/// nothing when its box lies wholly behind the receiving plane. Drawn by
/// guesses from the boxes' centres, the floor right in front of a skirting board was drawn
/// one time in a hundred and weighted a hundredfold: such links were heavy-tailed (most
/// estimates far too low, a few ten times too high).
fn guess(st: &State, ws: &[u8], e: Elem, x: Vec3, plane: Plane) -> f32 {
    let (lo, hi, a, polygon) = match e.kind() {
        Kind::Cluster => {
            let c = st.cluster(ws, e.index());
            (
                Vec3::from(c.bbox_min),
                Vec3::from(c.bbox_max),
                c.area,
                false,
            )
        }
        Kind::Source => return 0.0,
        _ => {
            let p = st.patch(ws, e);
            let (lo, hi) = p.bounds();
            (lo, hi, p.area, true)
        }
    };
    if a <= 0.0 {
        return 0.0;
    }
    if let Plane::Sphere = plane {
        // The solid angle of its box (a polygon's own, exact): a flat cluster of tiles seen
        // at a grazing angle covers far less than its area over the squared distance.
        if polygon {
            return polygon_value(st, ws, e, x, plane).map_or(0.0, |(v, _, _)| v);
        }
        return if outside(x, lo, hi) {
            box_fluence(x, lo, hi).max(f32::MIN_POSITIVE)
        } else {
            4.0
        };
    }
    let (n, both) = match plane {
        Plane::Facing(n) | Plane::Sides(n, 1) => (n, false),
        Plane::Sides(n, _) => (n, true),
        Plane::Sphere => return 0.0,
    };
    // The box corner farthest along the normal: nothing when it lies behind the plane.
    let far = Vec3::new(
        if n.x > 0.0 { hi.x } else { lo.x },
        if n.y > 0.0 { hi.y } else { lo.y },
        if n.z > 0.0 { hi.z } else { lo.z },
    );
    let reach = n.dot(far - x);
    if !both && reach <= 0.0 {
        return 0.0;
    }
    let d2 = (x.clamp(lo, hi) - x).length_squared();
    // Close by (within its radius): a polygon's exact form factor, a cluster's box's (exact
    // for a flat cluster such as a floor's tiles, at worst too large for a volume; a box
    // around `x`, a hemisphere).
    if d2 < 0.25 * (hi - lo).length_squared() {
        if polygon {
            return polygon_value(st, ws, e, x, plane).map_or(0.0, |(v, _, _)| v);
        }
        if !outside(x, lo, hi) {
            return if both { 2.0 } else { 1.0 };
        }
        let mut f = box_form_factor(x, n, lo, hi);
        if both {
            f += box_form_factor(x, -n, lo, hi);
        }
        return f;
    }
    // Farther: its area times a bound on the cosine at `x` over pi times the squared
    // distance to its box, at most a hemisphere.
    let cos = if both {
        1.0
    } else {
        (reach / libm::sqrtf(d2)).min(1.0)
    };
    (a * cos / (PI * d2).max(f32::MIN_POSITIVE)).min(1.0)
}

/// The exact form factor from `x` (receiving `plane`) to the polygon of root patch `e`, with
/// its side facing `x` and its corners; `None` when it sends `x` nothing (its one side
/// turned away, or wholly behind the plane).
fn polygon_value(
    st: &State,
    ws: &[u8],
    e: Elem,
    x: Vec3,
    plane: Plane,
) -> Option<(f32, usize, ([Vec3; 4], usize))> {
    let p = st.patch(ws, e);
    let rec = st.polygon(ws, p.poly);
    let normal = Vec3::from(rec.normal);
    let mut corners = [Vec3::ZERO; 4];
    for (c, src) in corners.iter_mut().zip(p.corners) {
        *c = src.into();
    }
    let m = p.corner_count();
    let side = facing_side(x, corners[0], normal)?;
    if side >= State::sides(e) {
        return None;
    }
    let value = match plane {
        Plane::Facing(n) | Plane::Sides(n, 1) => point_polygon(x, n, &corners[..m]),
        Plane::Sides(n, _) => {
            point_polygon(x, n, &corners[..m]) + point_polygon(x, -n, &corners[..m])
        }
        Plane::Sphere => point_polygon_light(x, &corners[..m]).0 / PI,
    };
    (value.is_finite() && value > 0.0).then_some((value, side, (corners, m)))
}
