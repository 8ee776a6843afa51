//! `A(dir)` against the box's shadow measured apart, and `tau(dir)` of a ball of black
//! leaves against an exact projection of the leaves along `dir` (issue 17's acceptance):
//! the reference rasterises the leaves' projected quads on a fine grid, with no ray caster.

use super::tau::{projected_area, tau};
use crate::sampling::{hash3, unit2};
use crate::visibility::Visibility;
use glam::{Vec2, Vec3};

/// Leaves: planar quads, brute-force segment tests (the table's own rays go through this).
pub(super) struct Leaves(pub(super) Vec<[Vec3; 4]>);

/// Moller-Trumbore on one triangle: the segment `from -> to` meets it strictly inside.
fn meets(from: Vec3, to: Vec3, a: Vec3, b: Vec3, c: Vec3) -> bool {
    let d = to - from;
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return false;
    }
    let s = from - a;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    let t = e2.dot(q) / det;
    u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0 && t < 1.0
}

impl Leaves {
    /// The leaves the segment meets (not those in `skip`), with the parameter where.
    fn hits(&self, from: Vec3, to: Vec3, skip: [u32; 2]) -> impl Iterator<Item = (u32, f32)> + '_ {
        self.0.iter().enumerate().filter_map(move |(i, q)| {
            if skip.contains(&(i as u32)) {
                return None;
            }
            if !(meets(from, to, q[0], q[1], q[2]) || meets(from, to, q[0], q[2], q[3])) {
                return None;
            }
            let n = (q[1] - q[0]).cross(q[2] - q[0]);
            let t = n.dot(q[0] - from) / n.dot(to - from);
            Some((i as u32, t))
        })
    }
}

impl Visibility for Leaves {
    fn transmittance(&self, from: Vec3, to: Vec3, skip: [u32; 2]) -> f32 {
        if self.hits(from, to, skip).next().is_some() {
            0.0
        } else {
            1.0
        }
    }
    fn first_hit(&self, from: Vec3, to: Vec3, skip: [u32; 2]) -> Option<(u32, f32)> {
        self.hits(from, to, skip)
            .min_by(|a, b| a.1.partial_cmp(&b.1).unwrap_or(core::cmp::Ordering::Equal))
    }
}

extern crate std;
use std::vec::Vec;

pub(super) fn unit(k: u32, seed: u32) -> Vec3 {
    let (a, b) = unit2(hash3(k, seed, 0xBA11));
    let z = 1.0 - 2.0 * a;
    let r = libm::sqrtf((1.0 - z * z).max(0.0));
    let phi = 2.0 * core::f32::consts::PI * b;
    Vec3::new(r * libm::cosf(phi), r * libm::sinf(phi), z)
}

/// `count` square leaves of side `size` at random places and tilts in a ball of `radius`
/// around `centre`; returns them and their bounding box.
pub(super) fn ball(
    count: u32,
    radius: f32,
    size: f32,
    centre: Vec3,
    seed: u32,
) -> (Leaves, Vec3, Vec3) {
    let mut leaves = Vec::new();
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for k in 0..count {
        let r = radius * libm::cbrtf(unit2(hash3(k, seed, 0x12)).0);
        let c = centre + unit(k, seed) * r;
        let n = unit(k, seed + 1);
        let t = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
        let u = n.cross(t).normalize() * (0.5 * size);
        let v = n.cross(u);
        let q = [c - u - v, c + u - v, c + u + v, c - u + v];
        for p in q {
            lo = lo.min(p);
            hi = hi.max(p);
        }
        leaves.push(q);
    }
    (Leaves(leaves), lo, hi)
}

/// Inside a convex polygon given counter-clockwise or clockwise.
fn inside(p: Vec2, poly: &[Vec2]) -> bool {
    let mut sign = 0.0f32;
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let c = (b - a).perp_dot(p - a);
        if c != 0.0 {
            if sign != 0.0 && c.signum() != sign {
                return false;
            }
            sign = c.signum();
        }
    }
    true
}

/// The box's shadow and the part of it the leaves leave open, on an `n x n` raster of the
/// plane perpendicular to `d`: (open fraction, shadow area m^2). The box's shadow is the
/// union of its six faces' projections.
pub(super) fn projection(leaves: &Leaves, lo: Vec3, hi: Vec3, d: Vec3, n: u32) -> (f32, f32) {
    let t = if d.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let e1 = d.cross(t).normalize();
    let e2 = d.cross(e1);
    let flat = |p: Vec3| Vec2::new(p.dot(e1), p.dot(e2));
    let corner = |k: u32| {
        Vec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        )
    };
    // The six faces by their corner indices (bit patterns), each a parallelogram.
    let faces = [
        [0, 1, 3, 2],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 3, 7, 5],
    ];
    let faces: Vec<[Vec2; 4]> = faces.iter().map(|f| f.map(|k| flat(corner(k)))).collect();
    let quads: Vec<[Vec2; 4]> = leaves.0.iter().map(|q| q.map(flat)).collect();
    let (mut min, mut max) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
    for f in &faces {
        for p in f {
            min = min.min(*p);
            max = max.max(*p);
        }
    }
    let step = (max - min) / n as f32;
    let (mut shadow, mut open) = (0u32, 0u32);
    for j in 0..n {
        for i in 0..n {
            let p = min + Vec2::new((i as f32 + 0.5) * step.x, (j as f32 + 0.5) * step.y);
            if !faces.iter().any(|f| inside(p, f)) {
                continue;
            }
            shadow += 1;
            if !quads.iter().any(|q| inside(p, q)) {
                open += 1;
            }
        }
    }
    (open as f32 / shadow as f32, shadow as f32 * step.x * step.y)
}

#[test]
fn projected_area_is_the_box_shadow() {
    let (lo, hi) = (Vec3::new(-1.0, 2.0, 0.5), Vec3::new(3.0, 2.5, 4.0));
    let empty = Leaves(Vec::new());
    for k in 0..40 {
        let d = unit(k, 5);
        let a = projected_area(lo, hi, d);
        let (_, raster) = projection(&empty, lo, hi, d, 400);
        assert!((a - raster).abs() < 0.01 * a, "{d}: {a} vs {raster}");
        let est = tau(&empty, lo, hi, d, 64, k);
        assert_eq!(est.tau, 1.0);
        assert!(
            (est.area - a).abs() < 0.02 * a,
            "{d}: sampled {} vs {a}",
            est.area
        );
    }
    // Along an axis: one face.
    assert!((projected_area(lo, hi, Vec3::Z) - 4.0 * 0.5).abs() < 1e-6);
}

#[test]
fn a_ball_of_black_leaves_lets_through_what_its_projection_leaves_open() {
    for (case, (count, size, scale)) in [
        (150u32, 0.3f32, 1.0f32),
        (400, 0.15, 0.001),
        (60, 0.5, 1000.0),
    ]
    .into_iter()
    .enumerate()
    {
        let centre = Vec3::new(3.0, -2.0, 1.0) * scale;
        let (leaves, lo, hi) = ball(count, scale, size * scale, centre, 9 + case as u32);
        for k in 0..6 {
            let d = unit(k, 40 + case as u32);
            let (want, _) = projection(&leaves, lo, hi, d, 500);
            let got = tau(&leaves, lo, hi, d, 96, k).tau;
            assert!(
                (got - want).abs() < 0.01,
                "case {case}, direction {d}: tau {got}, the projection leaves {want} open"
            );
            assert!(
                want > 0.05 && want < 0.95,
                "case {case}: tau {want} says little"
            );
        }
    }
}
