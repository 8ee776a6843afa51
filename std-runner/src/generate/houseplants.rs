//! The room's plant originals: a potted orchid (a Phalaenopsis: broad folded leaves, two
//! arching flower spikes with open flowers and buds, aerial roots, a stake) and a potted
//! palm (an areca-like clump of arching fronds, each with two rows of drooping leaflets).
//! Leaves and petals are two-sided translucent polygons; pots, stems and roots one-sided.
//!
//! Local frames (metres, z up): the origin is the middle of the pot's bottom.

use super::mesh::{lathe, ribbon, tube};
use crate::generate::rng::Rng;
use crate::generate::shapes::{cylinder, frame, sphere};
use crate::scene::Cluster;
use glam::Vec3;
use std::f32::consts::{PI, TAU};

/// Materials of the plants (indices into the scene's materials).
#[derive(Clone, Copy, Debug)]
pub struct PlantMaterials {
    /// Glazed orchid pot.
    pub ceramic: u32,
    /// Terracotta palm pot.
    pub terracotta: u32,
    /// Potting soil.
    pub soil: u32,
    /// Orchid bark mix.
    pub bark: u32,
    /// Leaves and leaflets (two-sided).
    pub leaf: u32,
    /// Green stems, rachises, stakes, buds.
    pub stem: u32,
    /// Orchid petals and sepals (two-sided).
    pub petal: u32,
    /// Orchid lip and column.
    pub lip: u32,
    /// Aerial roots.
    pub root: u32,
}

/// Points of a curve that starts at `base`, heads along azimuth `azimuth` (radians from +x),
/// and whose angle from the vertical grows from `theta0` to `theta1` (radians) as
/// `(s / length)^power`: `segments + 1` points over `length` metres.
fn arch(
    base: Vec3,
    azimuth: f32,
    length: f32,
    theta0: f32,
    theta1: f32,
    power: f32,
    segments: u32,
) -> Vec<Vec3> {
    let mut pts = vec![base];
    let mut p = base;
    let ds = length / segments as f32;
    for i in 0..segments {
        let t = (i as f32 + 0.5) / segments as f32;
        let th = theta0 + (theta1 - theta0) * t.powf(power);
        p += Vec3::new(th.sin() * azimuth.cos(), th.sin() * azimuth.sin(), th.cos()) * ds;
        pts.push(p);
    }
    pts
}

/// The horizontal unit vector perpendicular to azimuth `azimuth`.
fn across(azimuth: f32) -> Vec3 {
    Vec3::new(-azimuth.sin(), azimuth.cos(), 0.0)
}

/// A folded leaf along `spine` with `widths`: two half-blades meeting at the midrib, each
/// lifted by `fold` radians, so that the leaf is a shallow V open upwards.
fn folded_leaf(c: &mut Cluster, spine: &[Vec3], widths: &[f32], azimuth: f32, fold: f32, m: u32) {
    let s = across(azimuth);
    for sign in [-1.0f32, 1.0] {
        let side = (s * sign * fold.cos() + Vec3::Z * fold.sin()).normalize();
        let half: Vec<Vec3> = spine
            .iter()
            .zip(widths)
            .map(|(p, w)| *p + side * (w * 0.25))
            .collect();
        let w: Vec<f32> = widths.iter().map(|w| w * 0.5).collect();
        ribbon(c, &half, &w, side, Vec3::Z, m);
    }
}

/// A pot: outer wall with a rolled rim, inner wall down to the soil at `fill`, and the soil
/// surface; profile heights and radii in metres.
fn pot(wall: &[(f32, f32)], soil_z: f32, sides: u32, pot_m: u32, soil_m: u32) -> Cluster {
    let mut pot = Cluster::named("pot");
    let mut shell = Cluster::named("shell");
    lathe(&mut shell, Vec3::ZERO, Vec3::Z, wall, sides, pot_m);
    let inner = wall.last().map_or(0.0, |w| w.1);
    let mut soil = Cluster::named("soil");
    lathe(
        &mut soil,
        Vec3::ZERO,
        Vec3::Z,
        &[
            (soil_z, inner),
            (soil_z + 0.004, inner * 0.5),
            (soil_z + 0.006, 0.0),
        ],
        sides,
        soil_m,
    );
    pot.children = vec![shell, soil];
    pot
}

/// One orchid flower centred at `centre`, facing `facing` (unit), `size` metres across:
/// a dorsal sepal, two lateral sepals, two broad petals, a lip, a column and its pedicel
/// from `stem_point`.
fn flower(
    c: &mut Cluster,
    stem_point: Vec3,
    centre: Vec3,
    facing: Vec3,
    size: f32,
    m: &PlantMaterials,
) {
    cylinder(c, stem_point, centre, 0.002, 0.002, 4, m.stem);
    let right = facing
        .cross(Vec3::Z)
        .try_normalize()
        .unwrap_or(frame(facing).0);
    let up = right.cross(facing);
    // (angle in the flower plane from `right`, length, width, material)
    let parts = [
        (90.0f32, 0.45, 0.22, m.petal),
        (215.0, 0.45, 0.22, m.petal),
        (325.0, 0.45, 0.22, m.petal),
        (15.0, 0.45, 0.42, m.petal),
        (165.0, 0.45, 0.42, m.petal),
        (270.0, 0.32, 0.2, m.lip),
    ];
    for (deg, len, wid, mat) in parts {
        let a = deg.to_radians();
        let e = right * a.cos() + up * a.sin();
        let side = facing.cross(e);
        // Cupped: the tips bend forwards.
        let spine: Vec<Vec3> = (0..=5)
            .map(|j| {
                let t = j as f32 / 5.0;
                centre + e * (len * size * t) + facing * (0.25 * len * size * t * t)
            })
            .collect();
        let w = wid * size;
        ribbon(
            c,
            &spine,
            &[0.0, 0.55 * w, 0.9 * w, w, 0.8 * w, 0.0],
            side,
            facing,
            mat,
        );
    }
    lathe(
        c,
        centre,
        facing,
        &[(0.0, 0.005), (0.008, 0.004), (0.012, 0.0)],
        5,
        m.lip,
    );
}

/// A Phalaenopsis orchid in a glazed pot, about 60 cm tall; `rng` varies leaves, spikes and
/// flowers. About 1,200 polygons.
pub fn orchid(m: &PlantMaterials, rng: &mut Rng) -> Cluster {
    let soil_z = 0.11;
    let pot = pot(
        &[
            (0.0, 0.05),
            (0.005, 0.056),
            (0.12, 0.066),
            (0.125, 0.069),
            (0.13, 0.067),
            (0.13, 0.061),
            (soil_z, 0.058),
        ],
        soil_z,
        24,
        m.ceramic,
        m.bark,
    );
    let crown = Vec3::new(0.0, 0.0, soil_z + 0.01);
    let base_az = rng.range(0.0, TAU);

    let mut leaves = Cluster::named("leaves");
    for k in 0..5 {
        let mut leaf = Cluster::named(&format!("leaf{k}"));
        let az = base_az + PI * k as f32 + rng.range(-0.35, 0.35);
        let len = rng.vary(0.2 + 0.015 * k as f32, 0.1);
        let start = crown + Vec3::new(0.0, 0.0, 0.008 * k as f32);
        let spine = arch(
            start,
            az,
            len,
            rng.range(1.0, 1.3),
            rng.range(1.9, 2.2),
            1.2,
            6,
        );
        let w = rng.vary(0.075, 0.1);
        let widths = [0.4, 0.8, 0.95, 1.0, 0.92, 0.7, 0.0].map(|f| f * w);
        folded_leaf(&mut leaf, &spine, &widths, az, 0.3, m.leaf);
        leaves.children.push(leaf);
    }

    let mut spikes = Cluster::named("spikes");
    for k in 0..2 {
        let mut spike = Cluster::named(&format!("spike{k}"));
        let az = base_az + PI * 0.5 + PI * k as f32 + rng.range(-0.5, 0.5);
        let len = rng.vary(0.62, 0.08);
        let path = arch(crown, az, len, 0.08, rng.range(1.9, 2.1), 3.0, 16);
        let mut stem = Cluster::named("stem");
        let radii: Vec<f32> = (0..=16)
            .map(|i| 0.0035 - 0.0013 * i as f32 / 16.0)
            .collect();
        tube(&mut stem, &path, &radii, 6, m.stem);
        let mut flowers = Cluster::named("flowers");
        for f in 0..7 {
            let i = 9 + f;
            let p = path[i];
            let t = (path[i + 1] - path[i - 1]).normalize();
            let side = if f % 2 == 0 { 1.0 } else { -1.0 };
            let out = (across(az) * side * 0.6 + Vec3::new(az.cos(), az.sin(), 0.0)).normalize();
            let facing = (out - t * out.dot(t) - Vec3::Z * 0.25).normalize();
            let size = rng.vary(0.085, 0.08) * (1.0 - 0.04 * f as f32);
            flower(&mut flowers, p, p + facing * 0.018, facing, size, m);
        }
        let mut buds = Cluster::named("buds");
        for b in 0..2 {
            let p = path[16] + (path[16] - path[15]).normalize() * (0.01 + 0.014 * b as f32);
            sphere(&mut buds, p, 0.006 - 0.0015 * b as f32, 4, 6, m.stem);
        }
        spike.children = vec![stem, flowers, buds];
        spikes.children.push(spike);
    }

    let mut support = Cluster::named("support");
    cylinder(
        &mut support,
        Vec3::new(0.02, 0.0, soil_z - 0.05),
        Vec3::new(0.02, 0.0, 0.45),
        0.003,
        0.003,
        5,
        m.stem,
    );
    for k in 0..3 {
        let az = base_az + 1.0 + 2.1 * k as f32 + rng.range(-0.3, 0.3);
        let out = Vec3::new(az.cos(), az.sin(), 0.0);
        let path: Vec<Vec3> = (0..=5)
            .map(|j| {
                let t = j as f32 / 5.0;
                crown
                    + out * (0.075 * (t * 1.6).min(1.0))
                    + Vec3::Z * (0.02 * (t * PI).sin() - 0.06 * t * t)
            })
            .collect();
        tube(&mut support, &path, &[0.003; 6], 4, m.root);
    }

    Cluster {
        name: Some("orchid".into()),
        children: vec![pot, leaves, spikes, support],
        ..Cluster::default()
    }
}

/// An areca-like palm in a terracotta pot, about 1.7 m tall: 12 arching fronds, each a
/// rachis with 20 pairs of drooping leaflets; `rng` varies the fronds. About 2,800
/// polygons.
pub fn palm(m: &PlantMaterials, rng: &mut Rng) -> Cluster {
    let soil_z = 0.40;
    let pot = pot(
        &[
            (0.0, 0.17),
            (0.01, 0.18),
            (0.36, 0.215),
            (0.37, 0.235),
            (0.42, 0.235),
            (0.42, 0.21),
            (soil_z, 0.205),
        ],
        soil_z,
        28,
        m.terracotta,
        m.soil,
    );
    let mut fronds = Cluster::named("fronds");
    let golden = PI * (3.0 - 5f32.sqrt());
    for k in 0..12 {
        let mut frond = Cluster::named(&format!("frond{k}"));
        // Young fronds (high k) stand up in the middle; old ones spread out.
        let age = 1.0 - k as f32 / 11.0;
        let az = golden * k as f32 + rng.range(-0.2, 0.2);
        let out = Vec3::new(az.cos(), az.sin(), 0.0);
        let base = Vec3::new(0.0, 0.0, soil_z) + out * rng.range(0.0, 0.04);
        let len = rng.vary(1.1 + 0.25 * age, 0.08);
        let theta0 = 0.05 + 0.2 * age + rng.range(-0.03, 0.03);
        let rachis = arch(base, az, len, theta0, theta0 + 0.45 + 0.3 * age, 2.0, 10);
        let mut stalk = Cluster::named("rachis");
        let radii: Vec<f32> = (0..=10).map(|i| 0.009 - 0.006 * i as f32 / 10.0).collect();
        tube(&mut stalk, &rachis, &radii, 5, m.stem);
        let mut leaflets = Cluster::named("leaflets");
        for j in 0..20 {
            // Position along the rachis: from 25% to 97% of its length.
            let u = 0.25 + 0.72 * j as f32 / 19.0;
            let x = u * 10.0;
            let i = (x as usize).min(9);
            let p = rachis[i].lerp(rachis[i + 1], x - i as f32);
            let t = (rachis[i + 1] - rachis[i]).normalize();
            let lateral = t.cross(Vec3::Z).try_normalize().unwrap_or(across(az));
            let l = 0.3 * (PI * (0.15 + 0.8 * u)).sin() * rng.vary(1.0, 0.1);
            for sign in [-1.0f32, 1.0] {
                let d = (lateral * sign * 0.82 + t * 0.57).normalize();
                let side = Vec3::Z.cross(d).try_normalize().unwrap_or(t);
                let droop = rng.range(0.25, 0.6);
                let spine: Vec<Vec3> = (0..=4)
                    .map(|s| {
                        let f = s as f32 / 4.0;
                        p + d * (l * f) - Vec3::Z * (droop * l * f * f)
                    })
                    .collect();
                let w = 0.024;
                ribbon(
                    &mut leaflets,
                    &spine,
                    &[0.3 * w, 0.9 * w, w, 0.7 * w, 0.0],
                    side,
                    Vec3::Z,
                    m.leaf,
                );
            }
        }
        frond.children = vec![stalk, leaflets];
        fronds.children.push(frond);
    }
    Cluster {
        name: Some("palm".into()),
        children: vec![pot, fronds],
        ..Cluster::default()
    }
}

#[cfg(test)]
mod tests {
    use super::super::mesh;
    use super::*;

    const M: PlantMaterials = PlantMaterials {
        ceramic: 0,
        terracotta: 1,
        soil: 2,
        bark: 3,
        leaf: 4,
        stem: 5,
        petal: 6,
        lip: 7,
        root: 8,
    };

    #[test]
    fn plants_have_parts_size_and_two_sided_leaves() {
        let o = orchid(&M, &mut Rng::new(3));
        let n = mesh::polygon_count(&o);
        assert!((900..1800).contains(&n), "{n}");
        let b = mesh::bounds(&o);
        assert!((0.4..0.8).contains(&b.max.z) && b.min.z > -0.01, "{b:?}");
        assert!(
            b.min.x > -0.35 && b.min.y > -0.35 && b.max.x < 0.35 && b.max.y < 0.35,
            "{b:?}"
        );
        let p = palm(&M, &mut Rng::new(3));
        let n = mesh::polygon_count(&p);
        assert!((2000..3500).contains(&n), "{n}");
        let b = mesh::bounds(&p);
        assert!((1.4..2.0).contains(&b.max.z), "{b:?}");
        assert!(
            b.min.x > -0.75 && b.min.y > -0.75 && b.max.x < 0.75 && b.max.y < 0.75,
            "{b:?}"
        );
        // Same seed, same plant.
        assert_eq!(orchid(&M, &mut Rng::new(3)), o);
    }
}
