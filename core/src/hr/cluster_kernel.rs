//! Kernels of clusters seen from a point: a small cluster polygon by polygon (the exact form
//! factors, solid angles and vector form factors of its polygons that face the point, and
//! visibility rays drawn to them by weight), a larger one as the box of uniform radiance its
//! surfaces fill (its silhouette's form factor).

use super::ids::{Elem, Kind};
use super::state::State;
use crate::formfactor::{facing_side, point_polygon, point_polygon_light};
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
    /// through `x` with normal `nr` (when given).
    #[allow(clippy::too_many_arguments)]
    pub fn visible<V: Visibility + ?Sized>(
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
    ) -> f32 {
        if self.count == 0 || self.total <= 0.0 {
            return 1.0;
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
            seen += vis.transmittance(x, y, [from, poly]);
        }
        seen / rays.max(1) as f32
    }
}

/// The exact form factor from a point (normal `nr`) to the polygons of a cluster that face
/// it, polygon by polygon.
pub(crate) fn cluster_form_factor(st: &State, ws: &[u8], e: Elem, x: Vec3, nr: Vec3) -> Facing {
    let mut out = Facing::new();
    each_facing(st, ws, e, x, |k, _, c| out.push(k, point_polygon(x, nr, c)));
    out
}

/// Solid angle and vector form factor at `x` of the polygons of a cluster that face it;
/// the weights are the solid angles.
pub(crate) fn cluster_light(st: &State, ws: &[u8], e: Elem, x: Vec3) -> (f32, Vec3, Facing) {
    let (mut omega, mut phi) = (0.0f32, Vec3::ZERO);
    let mut facing = Facing::new();
    each_facing(st, ws, e, x, |k, _, c| {
        let (o, p) = point_polygon_light(x, c);
        if o.is_finite() {
            omega += o;
            phi += p;
            facing.push(k, o);
        }
    });
    (omega.min(4.0 * PI), phi, facing)
}

/// True when `x` lies outside the box (so that the box's faces seen from it are a proper
/// silhouette).
pub(crate) fn outside(x: Vec3, min: Vec3, max: Vec3) -> bool {
    x.cmplt(min).any() || x.cmpgt(max).any()
}

/// Area of the box's shadow along the unit direction `w` (m^2).
pub(crate) fn box_projected_area(min: Vec3, max: Vec3, w: Vec3) -> f32 {
    let d = max - min;
    w.x.abs() * d.y * d.z + w.y.abs() * d.x * d.z + w.z.abs() * d.x * d.y
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

/// Solid angle and vector form factor of a box's silhouette seen from an outside point.
pub(crate) fn box_light(x: Vec3, min: Vec3, max: Vec3) -> (f32, Vec3) {
    let (mut omega, mut phi) = (0.0f32, Vec3::ZERO);
    box_faces(x, min, max, |c| {
        let (o, p) = point_polygon_light(x, c);
        omega += o;
        phi += p;
    });
    (omega, phi)
}
