//! Crop plant originals for `hirad gen canopy`: a maize plant (a stem with about twelve long
//! arching leaves, an ear and a tassel) and a wheat plant (a clump of thin tillers, each with
//! narrow leaves and an ear). Leaves are two-sided translucent ribbons whose pieces are
//! planar trapezoids (see `mesh::ribbon`); stems and ears are one-sided closed surfaces.
//!
//! Local frame: metres, z up, the origin where the stem leaves the soil.
//!
//! Node attributes: `axis` is the organ kind — 0 plant or main stem, 1 leaf, 2 ear, 3 tassel,
//! 4 wheat tiller — and `age` is in days: the plant's days since emergence, an organ's days
//! since it appeared (one leaf every [`PHYLLOCHRON`] days, from the bottom up).

use crate::generate::mesh::{lathe, ribbon, tube};
use crate::generate::rng::Rng;
use crate::scene::Cluster;
use glam::Vec3;
use std::f32::consts::{PI, TAU};

/// Materials of the crop plants (indices into the scene's materials).
#[derive(Clone, Copy, Debug)]
pub struct CropMaterials {
    /// Leaves (two-sided).
    pub leaf: u32,
    /// Stems.
    pub stem: u32,
    /// Ears.
    pub ear: u32,
    /// Maize tassels.
    pub tassel: u32,
}

/// Organ kinds stored in `axis`.
pub mod axis {
    /// The plant, or a main stem.
    pub const STEM: u32 = 0;
    /// A leaf.
    pub const LEAF: u32 = 1;
    /// An ear.
    pub const EAR: u32 = 2;
    /// A maize tassel.
    pub const TASSEL: u32 = 3;
    /// A wheat tiller.
    pub const TILLER: u32 = 4;
}

/// Days between the appearance of two successive leaves.
pub const PHYLLOCHRON: f32 = 4.5;

/// A named cluster with an organ kind and an age (days).
fn organ(name: &str, kind: u32, age: f32) -> Cluster {
    Cluster {
        name: Some(name.to_string()),
        axis: Some(kind),
        age: Some(age.max(0.0)),
        ..Cluster::default()
    }
}

/// Unit direction at `theta` radians from the vertical, towards azimuth `az`.
fn towards(theta: f32, az: f32) -> Vec3 {
    Vec3::new(theta.sin() * az.cos(), theta.sin() * az.sin(), theta.cos())
}

/// A blade from `base` towards azimuth `az`, `length` m long, `segments` pieces, its angle
/// from the vertical bending from `theta0` to `theta1` (radians) as `(s / length)^1.3`;
/// `shape` gives the width (m) at each station.
#[allow(clippy::too_many_arguments)]
fn blade(
    c: &mut Cluster,
    base: Vec3,
    az: f32,
    length: f32,
    theta0: f32,
    theta1: f32,
    widths: &[f32],
    material: u32,
) -> usize {
    let segments = widths.len() - 1;
    let ds = length / segments as f32;
    let mut spine = vec![base];
    for i in 0..segments {
        let t = (i as f32 + 0.5) / segments as f32;
        let d = towards(theta0 + (theta1 - theta0) * t.powf(1.3), az);
        spine.push(spine[i] + d * ds);
    }
    let side = Vec3::new(-az.sin(), az.cos(), 0.0);
    ribbon(c, &spine, widths, side, Vec3::Z, material)
}

/// A maize plant at about 85 days: 11 to 13 leaves (longest in the middle of the stem,
/// upper ones more erect), an ear at mid-height and a tassel on top; `rng` varies its
/// size, leaf angles and azimuths (leaves alternate in two ranks, within 20 degrees).
/// About 210 polygons.
pub fn maize(m: &CropMaterials, rng: &mut Rng) -> Cluster {
    let age = rng.range(80.0, 90.0);
    let n = rng.int(11, 13);
    let height = rng.vary(1.9, 0.08);
    let lean = towards(rng.range(0.0, 0.04), rng.range(0.0, TAU));
    let stem_top = lean * height;
    let axis_at = |z: f32| lean * (z / lean.z);

    let mut stem = organ("stem", axis::STEM, age);
    let path: Vec<Vec3> = (0..=8).map(|i| stem_top * (i as f32 / 8.0)).collect();
    let radii: Vec<f32> = (0..=8).map(|i| 0.014 - 0.008 * i as f32 / 8.0).collect();
    tube(&mut stem, &path, &radii, 6, m.stem);

    let mut leaves = Cluster::named("leaves");
    let az0 = rng.range(0.0, TAU);
    for i in 0..n {
        let f = (i as f32 + 0.5) / n as f32;
        // Internodes lengthen up the stem; the top leaf sits at 85% of the height.
        let z = stem_top.z * (0.04 + 0.81 * f.powf(1.3));
        let az = az0 + PI * i as f32 + rng.range(-0.35, 0.35);
        let length = rng.vary(0.35 + 0.6 * (PI * (0.15 + 0.8 * f)).sin(), 0.07);
        let width = 0.09 * (length / 0.95).sqrt();
        // Lower leaves open wider and droop further than the upper ones.
        let theta0 = rng.range(0.45, 0.7) - 0.25 * f;
        let theta1 = theta0 + rng.range(1.3, 1.8) - 0.6 * f;
        let base = axis_at(z) + Vec3::new(az.cos(), az.sin(), 0.0) * 0.01;
        let widths = [0.5, 0.75, 0.9, 1.0, 0.95, 0.8, 0.6, 0.35, 0.0].map(|k| k * width);
        let appeared = PHYLLOCHRON * (i + 1) as f32;
        let mut leaf = organ(&format!("leaf{i}"), axis::LEAF, age - appeared);
        blade(&mut leaf, base, az, length, theta0, theta1, &widths, m.leaf);
        leaves.children.push(leaf);
    }

    let mut ear = organ("ear", axis::EAR, age - 60.0);
    let ear_az = az0 + rng.range(-0.3, 0.3);
    let ear_base = axis_at(stem_top.z * 0.45) + Vec3::new(ear_az.cos(), ear_az.sin(), 0.0) * 0.015;
    lathe(
        &mut ear,
        ear_base,
        towards(0.45, ear_az),
        &[
            (0.0, 0.0),
            (0.03, 0.022),
            (0.08, 0.026),
            (0.14, 0.023),
            (0.18, 0.013),
            (0.2, 0.0),
        ],
        6,
        m.ear,
    );

    let mut tassel = organ("tassel", axis::TASSEL, age - 58.0);
    let top = stem_top + lean * 0.3;
    tube(
        &mut tassel,
        &[stem_top, stem_top.lerp(top, 0.5), top],
        &[0.006, 0.004, 0.002],
        3,
        m.tassel,
    );
    for b in 0..5 {
        let az = az0 + TAU * b as f32 / 5.0 + rng.range(-0.3, 0.3);
        let start = stem_top + lean * 0.06;
        let p1 = start + towards(0.7, az) * 0.1;
        let p2 = p1 + towards(1.6, az) * 0.12;
        tube(
            &mut tassel,
            &[start, p1, p2],
            &[0.0025, 0.002, 0.0015],
            3,
            m.tassel,
        );
    }

    let mut plant = organ("maize", axis::STEM, age);
    plant.children = vec![stem, leaves, ear, tassel];
    plant
}

/// A wheat plant at heading: 2 to 4 tillers splaying out from the base, each a thin stem of
/// about 0.85 m with four narrow drooping leaves (the flag leaf on top) and an ear; `rng`
/// varies heights, splay and azimuths. About 65 polygons per tiller.
pub fn wheat(m: &CropMaterials, rng: &mut Rng) -> Cluster {
    let age = rng.range(95.0, 105.0);
    let tillers = rng.int(2, 4);
    let mut plant = organ("wheat", axis::STEM, age);
    for k in 0..tillers {
        // Later tillers are younger, shorter and splay more.
        let t_age = age - 12.0 * k as f32;
        let mut tiller = organ(&format!("tiller{k}"), axis::TILLER, t_age);
        let height = rng.vary(0.85, 0.06) * (1.0 - 0.05 * k as f32);
        let az = rng.range(0.0, TAU);
        let splay = 0.04 + 0.09 * k as f32 + rng.range(0.0, 0.05);
        // A slight curve: the splay eases towards the vertical higher up.
        let path: Vec<Vec3> = (0..=5)
            .map(|i| {
                let s = i as f32 / 5.0;
                let th = splay * (1.0 - 0.5 * s);
                Vec3::new(0.0, 0.0, 0.0) + towards(th, az) * (height * s)
            })
            .collect();
        let mut stem = organ("stem", axis::STEM, t_age);
        tube(
            &mut stem,
            &path,
            &[0.0025, 0.0023, 0.0021, 0.0019, 0.0017, 0.0015],
            4,
            m.stem,
        );
        let at = |h: f32| {
            let x = h * 5.0;
            let i = (x as usize).min(4);
            path[i].lerp(path[i + 1], x - i as f32)
        };
        let mut leaves = Cluster::named("leaves");
        for (j, (h, len)) in [(0.12, 0.18), (0.28, 0.22), (0.45, 0.24), (0.62, 0.19)]
            .into_iter()
            .enumerate()
        {
            let leaf_az = az + PI * j as f32 + rng.range(-0.5, 0.5);
            let width = rng.vary(0.014, 0.1);
            let mut leaf = organ(
                &format!("leaf{j}"),
                axis::LEAF,
                t_age - PHYLLOCHRON * 2.0 * (j + 1) as f32,
            );
            let theta0 = rng.range(0.35, 0.6);
            blade(
                &mut leaf,
                at(h),
                leaf_az,
                rng.vary(len, 0.1),
                theta0,
                theta0 + rng.range(1.0, 1.6),
                &[0.7, 1.0, 0.85, 0.5, 0.0].map(|f| f * width),
                m.leaf,
            );
            leaves.children.push(leaf);
        }
        let mut ear = organ("ear", axis::EAR, t_age - 70.0);
        let dir = (path[5] - path[4]).normalize();
        lathe(
            &mut ear,
            path[5],
            dir,
            &[
                (0.0, 0.0),
                (0.01, 0.006),
                (0.04, 0.008),
                (0.07, 0.007),
                (0.09, 0.004),
                (0.1, 0.0),
            ],
            6,
            m.ear,
        );
        tiller.children = vec![stem, leaves, ear];
        plant.children.push(tiller);
    }
    plant
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate::mesh;

    const M: CropMaterials = CropMaterials {
        leaf: 0,
        stem: 1,
        ear: 2,
        tassel: 3,
    };

    /// Leaves of a plant, found by their axis kind.
    fn leaves(c: &Cluster, out: &mut Vec<usize>) {
        if c.axis == Some(axis::LEAF) {
            out.push(mesh::polygon_count(c));
        }
        for ch in &c.children {
            leaves(ch, out);
        }
    }

    #[test]
    fn maize_has_a_dozen_bent_leaves_an_ear_and_a_tassel() {
        for seed in 0..4 {
            let p = maize(&M, &mut Rng::new(seed));
            let mut l = Vec::new();
            leaves(&p, &mut l);
            assert!((11..=13).contains(&l.len()));
            assert!(l.iter().all(|&n| n == 8), "{l:?}");
            let b = mesh::bounds(&p);
            assert!((1.9..2.6).contains(&b.max.z), "{b:?}");
            assert!(b.half_extent().truncate().max_element() < 1.2, "{b:?}");
            let n = mesh::polygon_count(&p);
            assert!((180..260).contains(&n), "{n}");
            assert!(p.children.iter().all(
                |c| c.axis.is_some() && c.age.is_some() || c.name.as_deref() == Some("leaves")
            ));
        }
    }

    #[test]
    fn wheat_has_tillers_with_leaves_and_ears() {
        let p = wheat(&M, &mut Rng::new(2));
        assert!((2..=4).contains(&p.children.len()));
        for t in &p.children {
            assert_eq!(t.axis, Some(axis::TILLER));
            assert_eq!(t.children[2].axis, Some(axis::EAR));
        }
        let b = mesh::bounds(&p);
        assert!((0.75..1.05).contains(&b.max.z), "{b:?}");
        assert_eq!(wheat(&M, &mut Rng::new(2)), p);
    }
}
