//! Growing one axis in its canonical frame (base at the origin, along +z, bending towards
//! +x), in metres: its internodes as low-polygon tapering cylinders, and its laterals placed
//! by spiral phyllotaxy, each made by a [`Laterals`] strategy (an approximate instance with
//! its own geometry, or an exact instance of a variant).
//!
//! Random streams: an axis draws its own shape from `rng.fork(0)` and hands lateral `j` the
//! stream `rng.fork(j + 1)`, so that changing one branch does not reshuffle the others.

use super::frame::{Centerline, Placement, basis};
use super::species::{MAX_BRANCH_ORDER, SHOOT, Species};
use crate::generate::rng::Rng;
use crate::generate::shapes::{cylinder, frame, leaf};
use crate::scene::Cluster;
use glam::Vec3;
use std::f32::consts::{PI, TAU};

/// Material indices of the tree's surfaces.
#[derive(Clone, Copy, Debug)]
pub struct TreeMaterials {
    /// Bark of every axis and stem (one-sided).
    pub bark: u32,
    /// Leaves (two-sided, translucent).
    pub leaf: u32,
}

/// How laterals become nodes of their parent.
pub trait Laterals {
    /// The node of a lateral of `kind` (1 to 3, or [`SHOOT`]) and `age` (years), placed by
    /// `place` in its parent's frame (metres), drawing from `rng`.
    fn lateral(
        &mut self,
        species: &Species,
        kind: u32,
        age: f32,
        place: &Placement,
        rng: &mut Rng,
    ) -> Cluster;
}

/// Grows an axis of `kind` (0 to 3) and `age` (years), `length` metres long, with its
/// laterals and a terminal leafy shoot; returns a plain cluster carrying kind and age.
pub fn grow_axis(
    species: &Species,
    kind: u32,
    age: f32,
    length: f32,
    mats: TreeMaterials,
    rng: &Rng,
    laterals: &mut dyn Laterals,
) -> Cluster {
    let p = &species.axes[kind.min(MAX_BRANCH_ORDER) as usize];
    let mut own = rng.fork(0);
    let mut c = Cluster {
        axis: Some(kind),
        age: Some(age),
        ..Cluster::default()
    };
    // Internodes: the mean count +-1, a slightly wobbling line bending towards the parent.
    let segments = own.int(p.segments.saturating_sub(1).max(1), p.segments + 1);
    let bend = own.vary(p.bend_deg, 0.3).to_radians();
    let line = Centerline::new(length, segments, bend, 0.04, &mut own);
    let r0 = p.radius_ratio * length * own.vary(1.0, 0.1);
    let radius = |t: f32| r0 * (1.0 - (1.0 - p.tip_ratio) * t);
    for i in 0..line.segments() {
        let (t0, t1) = (
            i as f32 / line.segments() as f32,
            (i + 1) as f32 / line.segments() as f32,
        );
        cylinder(
            &mut c,
            line.points[i],
            line.points[i + 1],
            radius(t0),
            radius(t1),
            p.sides,
            mats.bark,
        );
    }
    // Laterals along the zone, spiralling; their age follows the year their node was made.
    let span = (p.zone[1] - p.zone[0]) * length;
    let count = ((p.lateral_density * span * own.vary(1.0, p.count_spread)).round() as u32).max(1);
    let phase = own.range(0.0, TAU);
    let divergence = species.divergence_deg.to_radians();
    for j in 0..count {
        let mut lr = rng.fork(j as u64 + 1);
        let t = p.zone[0]
            + (p.zone[1] - p.zone[0]) * (j as f32 + 0.5 + lr.range(-0.3, 0.3)) / count as f32;
        let lateral_age = (age * (1.0 - t) - 0.5 + lr.range(-0.4, 0.4)).max(0.2);
        let child_kind = if kind >= MAX_BRANCH_ORDER || lateral_age < species.shoot_age {
            SHOOT
        } else {
            kind + 1
        };
        let insertion = if child_kind == SHOOT {
            species.shoot.insertion_deg
        } else {
            species.axes[child_kind as usize].insertion_deg
        };
        let (at, tangent) = line.at(t);
        let (u, v) = frame(tangent);
        let phi = phase + j as f32 * divergence + lr.range(-0.2, 0.2);
        let theta = lr.vary(insertion, 0.2).to_radians();
        let d = (tangent * theta.cos() + (u * phi.cos() + v * phi.sin()) * theta.sin()).normalize();
        let place = Placement {
            at,
            rotation: basis(d, tangent),
        };
        let node = laterals.lateral(species, child_kind, lateral_age, &place, &mut lr);
        c.children.push(node);
    }
    // The terminal shoot: this year's growth at the tip, in line with the axis.
    let mut tr = rng.fork(count as u64 + 1);
    let (tip, tangent) = line.at(1.0);
    let place = Placement {
        at: tip,
        rotation: basis(tangent, Vec3::X),
    };
    c.children
        .push(laterals.lateral(species, SHOOT, 1.0, &place, &mut tr));
    c
}

/// Grows a leafy shoot `length` metres long: a thin stem and a spiral of two-sided leaves,
/// larger in the middle of the shoot; a plain cluster of kind [`SHOOT`].
pub fn grow_shoot(
    species: &Species,
    age: f32,
    length: f32,
    mats: TreeMaterials,
    rng: &Rng,
) -> Cluster {
    let s = &species.shoot;
    let mut r = rng.fork(0);
    let mut c = Cluster {
        axis: Some(SHOOT),
        age: Some(age),
        ..Cluster::default()
    };
    let line = Centerline::new(length, s.segments, r.range(0.0, 0.3), 0.05, &mut r);
    let scale = length / s.length;
    let r0 = s.radius * scale;
    for i in 0..line.segments() {
        let t0 = i as f32 / line.segments() as f32;
        let t1 = (i + 1) as f32 / line.segments() as f32;
        cylinder(
            &mut c,
            line.points[i],
            line.points[i + 1],
            r0 * (1.0 - 0.5 * t0),
            r0 * (1.0 - 0.5 * t1),
            s.sides,
            mats.bark,
        );
    }
    let n = r.int(
        s.leaves.saturating_sub(s.leaf_spread).max(1),
        s.leaves + s.leaf_spread,
    );
    let phase = r.range(0.0, TAU);
    let divergence = 144f32.to_radians();
    for j in 0..n {
        let t = 0.08 + 0.92 * (j as f32 + 0.5) / n as f32;
        let (p, tangent) = line.at(t);
        let (u, v) = frame(tangent);
        let phi = phase + j as f32 * divergence + r.range(-0.25, 0.25);
        let theta = r.vary(s.leaf_angle_deg, 0.2).to_radians();
        let d = tangent * theta.cos() + (u * phi.cos() + v * phi.sin()) * theta.sin();
        let size = s.leaf_length * scale * (0.7 + 0.45 * (PI * t).sin()) * r.vary(1.0, 0.12);
        leaf(
            &mut c,
            p + d * (s.petiole * size),
            d,
            tangent,
            size,
            size * s.leaf_width,
            mats.leaf,
        );
    }
    c
}
