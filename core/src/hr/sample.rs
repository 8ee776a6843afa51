//! Points on elements for visibility rays and cluster transfers, chosen deterministically
//! from a hash of the two elements and the ray number; cosine-distributed directions, the
//! area weights of points on a quad, and strides that shuffle stratified samples.

use super::ids::{Elem, Kind};
use super::state::State;
use crate::sampling::{hash3, point_on, unit2};
use glam::Vec3;

/// A point on a surface inside `e` (area-weighted descent through clusters), and the input
/// polygon it lies on. `seed` varies the choice.
pub(crate) fn point_in(s: &State, ws: &[u8], e: Elem, seed: u32) -> (Vec3, u32) {
    let mut cur = e;
    let mut h = seed;
    // Clusters nest at most a few hundred deep (scene nesting plus grouping levels); bound
    // the walk anyway.
    for _ in 0..4096 {
        match cur.kind() {
            Kind::Cluster => {
                let c = s.cluster(ws, cur.index());
                if c.child_count == 0 || c.area <= 0.0 {
                    let p = (Vec3::from(c.bbox_min) + Vec3::from(c.bbox_max)) * 0.5;
                    return (p, crate::limits::NONE);
                }
                h = hash3(h, cur.0, 0x5EED);
                let target = (h >> 8) as f32 * (1.0 / 16_777_216.0) * c.area;
                let mut acc = 0.0f32;
                let mut pick = s.child(ws, c.children + c.child_count - 1);
                for k in 0..c.child_count {
                    let child = s.child(ws, c.children + k);
                    acc += area(s, ws, child);
                    if target < acc {
                        pick = child;
                        break;
                    }
                }
                cur = pick;
            }
            Kind::Source => return (Vec3::ZERO, crate::limits::NONE),
            Kind::Instance => {
                let p = super::instance_kernel::point_of(s, ws, cur.index(), hash3(h, cur.0, 0x1A));
                return (p, crate::limits::NONE);
            }
            _ => {
                let p = s.patch(ws, cur);
                let mut corners = [Vec3::ZERO; 4];
                for (c, src) in corners.iter_mut().zip(p.corners) {
                    *c = src.into();
                }
                let (u, v) = unit2(hash3(h, cur.0, 0xC0FFEE));
                return (point_on(&corners[..p.corner_count()], u, v), p.poly);
            }
        }
    }
    (Vec3::ZERO, crate::limits::NONE)
}

/// Surface area inside an element (one side, m^2).
pub(crate) fn area(s: &State, ws: &[u8], e: Elem) -> f32 {
    match e.kind() {
        Kind::Cluster => s.cluster(ws, e.index()).area,
        Kind::Source => 0.0,
        // Its equivalent surface (see `load::finish_clusters`).
        Kind::Instance => 0.25 * s.instance(ws, e.index()).area_ref,
        _ => s.patch(ws, e).area,
    }
}

/// A point on a surface inside `e` drawn towards `target`: down the cluster tree, each child
/// is chosen in proportion to its area times `1 / (d^2 + reach^2 + r^2)` (`d` the distance
/// from its box's centre to `target`, `r` its radius), so that the parts of a large receiver
/// near a small emitter, where the light falls, get the samples. Returns the point, its
/// polygon and its weight: the ratio of the area density to the sampling density (1 for
/// [`point_in`]'s draw), so that weighted means over such points are unbiased means over
/// the surfaces. (Drawn by area alone, a few points of a soil under a plant rarely land
/// near it: the estimate of what it gets is usually far too small and now and then far too
/// large.)
pub(crate) fn point_toward(
    s: &State,
    ws: &[u8],
    e: Elem,
    target: Vec3,
    reach: f32,
    seed: u32,
) -> (Vec3, u32, f32) {
    if !(reach.is_finite() && target.is_finite()) {
        let (x, p) = point_in(s, ws, e, seed);
        return (x, p, 1.0);
    }
    let mut cur = e;
    let mut h = seed;
    let mut weight = 1.0f32;
    let r2 = reach * reach;
    let pull = |s: &State, child: Elem| -> (f32, f32) {
        let a = area(s, ws, child);
        let (c, r) = match child.kind() {
            Kind::Cluster => {
                let cc = s.cluster(ws, child.index());
                let (lo, hi) = (Vec3::from(cc.bbox_min), Vec3::from(cc.bbox_max));
                ((lo + hi) * 0.5, 0.5 * (hi - lo).length())
            }
            Kind::Instance => {
                let c = s.instance(ws, child.index());
                let (lo, hi) = (Vec3::from(c.bbox_min), Vec3::from(c.bbox_max));
                ((lo + hi) * 0.5, 0.5 * (hi - lo).length())
            }
            _ => {
                let p = s.patch(ws, child);
                let n = p.corner_count();
                let mut sum = Vec3::ZERO;
                for c in &p.corners[..n] {
                    sum += Vec3::from(*c);
                }
                (sum / n as f32, libm::sqrtf(p.area))
            }
        };
        let d2 = (c - target).length_squared();
        (a, a / (d2 + r2 + r * r).max(f32::MIN_POSITIVE))
    };
    for _ in 0..4096 {
        match cur.kind() {
            Kind::Cluster => {
                let c = s.cluster(ws, cur.index());
                if c.child_count == 0 || c.area <= 0.0 {
                    let p = (Vec3::from(c.bbox_min) + Vec3::from(c.bbox_max)) * 0.5;
                    return (p, crate::limits::NONE, weight);
                }
                let mut total = 0.0f32;
                for k in 0..c.child_count {
                    total += pull(s, s.child(ws, c.children + k)).1;
                }
                h = hash3(h, cur.0, 0x70A4);
                let target_w = (h >> 8) as f32 * (1.0 / 16_777_216.0) * total;
                let mut acc = 0.0f32;
                let mut pick = (s.child(ws, c.children + c.child_count - 1), 0.0f32, 0.0f32);
                for k in 0..c.child_count {
                    let child = s.child(ws, c.children + k);
                    let (a, g) = pull(s, child);
                    if g <= 0.0 {
                        continue;
                    }
                    pick = (child, a, g);
                    acc += g;
                    if target_w < acc {
                        break;
                    }
                }
                let (child, a, g) = pick;
                if g <= 0.0 || total <= 0.0 {
                    let p = (Vec3::from(c.bbox_min) + Vec3::from(c.bbox_max)) * 0.5;
                    return (p, crate::limits::NONE, weight);
                }
                // Area share over sampling share.
                weight *= (a / c.area) / (g / total);
                cur = child;
            }
            Kind::Source => return (Vec3::ZERO, crate::limits::NONE, 0.0),
            Kind::Instance => {
                let p = super::instance_kernel::point_of(s, ws, cur.index(), hash3(h, cur.0, 0x1B));
                return (p, crate::limits::NONE, weight);
            }
            _ => {
                let p = s.patch(ws, cur);
                let mut corners = [Vec3::ZERO; 4];
                for (c, src) in corners.iter_mut().zip(p.corners) {
                    *c = src.into();
                }
                let (u, v) = unit2(hash3(h, cur.0, 0xC0FFEE));
                return (point_on(&corners[..p.corner_count()], u, v), p.poly, weight);
            }
        }
    }
    (Vec3::ZERO, crate::limits::NONE, 0.0)
}

/// A cosine-distributed unit direction about `n` from `u, v` in [0, 1).
pub(crate) fn cosine_direction(n: Vec3, u: f32, v: f32) -> Vec3 {
    let (t, b) = n.any_orthonormal_pair();
    let r = libm::sqrtf(u);
    let phi = 2.0 * core::f32::consts::PI * v;
    let z = libm::sqrtf((1.0 - u).max(0.0));
    (t * (r * libm::cosf(phi)) + b * (r * libm::sinf(phi)) + n * z).normalize_or_zero()
}

/// Area weight of the sample at `(u, v)`: the Jacobian of the bilinear map on a quad (1 on a
/// triangle, whose map preserves area).
pub(crate) fn jacobian(corners: &[Vec3], u: f32, v: f32) -> f32 {
    if corners.len() != 4 {
        return 1.0;
    }
    let (a, b, c, d) = (corners[0], corners[1], corners[2], corners[3]);
    let du = (b - a) * (1.0 - v) + (c - d) * v;
    let dv = (d - a) * (1.0 - u) + (c - b) * u;
    du.cross(dv).length()
}

/// A stride in `count / 2 .. count` coprime with `count` (1 for small counts), chosen from
/// `h`: walking `j * stride mod count` visits every index once.
pub(crate) fn coprime_stride(count: u32, h: u32) -> u32 {
    if count <= 2 {
        return 1;
    }
    let gcd = |mut a: u32, mut b: u32| {
        while b != 0 {
            (a, b) = (b, a % b);
        }
        a
    };
    let mut s = count / 2 + h % (count / 2).max(1);
    while gcd(s, count) != 1 {
        s += 1;
        if s >= count {
            s = 1;
        }
    }
    s
}

/// The mean of [`jacobian`] over the unit square (exact for a bilinear quad: its value at the
/// centre).
pub(crate) fn mean_jacobian(corners: &[Vec3]) -> f32 {
    let j = jacobian(corners, 0.5, 0.5);
    if j > 0.0 { j } else { 1.0 }
}
