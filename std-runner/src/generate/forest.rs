//! `hirad gen forest`: poplars standing on a terrain of gentle hills, under a sun and a sky.
//!
//! To stay small whatever its size, a forest is *exact* instances all the way down: a few
//! variants of each class of axis (leafy shoot, order-3 twig, order-2 and order-1 branches)
//! are built once, each made of exact instances of the variants below it, and a few tree
//! originals of different ages are made of those. Each tree of the forest is an exact
//! instance of a tree original, turned and slightly scaled, its base at the lowest point of
//! the ground under its trunk. A forest tree is denser than `gen poplar`'s (about a million
//! polygons), so that `--trees 1000` expands to about a billion polygons in a file of a few
//! megabytes. Units: metres, years, W/m^2.

use super::Common;
use super::poplar::{check_age, check_sun};
use super::rng::Rng;
use super::terrain;
use super::tree::materials::{Bands, add_soil, add_tree_materials};
use super::tree::site::{bounds, framing_camera, sun_and_sky};
use super::tree::{Species, TRUNK, exact_variants, grow};
use crate::scene::{Cluster, InstanceOf, Original, Scene, Similarity};
use anyhow::{Result, bail};
use glam::{Quat, Vec3};
use terrain::Terrain;

/// Arguments of `hirad gen forest`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  hirad gen forest --trees 1000 -o forest.hirb  # ~1 billion polygons, 1.5 MB\n  hirad gen forest --trees 10 -o grove.hirb && hirad info grove.hirb"
)]
pub struct Args {
    /// Seed, output and summary.
    #[command(flatten)]
    pub common: Common,
    /// Number of trees.
    #[arg(long, default_value_t = 100)]
    pub trees: u32,
    /// Side of the square terrain (m); default 7 m per tree along a side (7 sqrt(N)).
    #[arg(long)]
    pub size: Option<f32>,
    /// Height of the hills, crest to mean (m); default 3% of the side.
    #[arg(long)]
    pub relief: Option<f32>,
    /// Terrain cells per side (two triangles each); default one per 2 m, 8 to 1024.
    #[arg(long)]
    pub cells: Option<u32>,
    /// Ages of the tree originals (years, comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "25,30,35")]
    pub ages: Vec<f32>,
    /// Variants of each class of axis (shoots, twigs, branches).
    #[arg(long, default_value_t = 3)]
    pub variants: u32,
    /// Branching density relative to `gen poplar`'s tree (laterals per metre of every
    /// order multiply by it): 2.1 gives about a million polygons per tree.
    #[arg(long, default_value_t = 2.1)]
    pub detail: f32,
    /// Spectral bands.
    #[arg(long, value_enum, default_value_t = Bands::ParNir)]
    pub bands: Bands,
    /// Sun elevation above the horizon (degrees).
    #[arg(long, default_value_t = 50.0)]
    pub sun_elevation: f32,
    /// Sun azimuth, from +x towards +y (degrees).
    #[arg(long, default_value_t = -120.0, allow_hyphen_values = true)]
    pub sun_azimuth: f32,
}

fn check(a: &Args, size: f32, relief: f32, cells: u32) -> Result<()> {
    if !(1..=1_000_000).contains(&a.trees) {
        bail!("--trees must lie in 1..=1000000, got {}", a.trees);
    }
    if !(size.is_finite() && (1.0..=100_000.0).contains(&size)) {
        bail!("--size must lie in 1..=100000 m, got {size}");
    }
    if !(relief.is_finite() && (0.0..=0.5 * size).contains(&relief)) {
        bail!("--relief must lie in 0..=size/2 m, got {relief}");
    }
    if !(1..=4096).contains(&cells) {
        bail!("--cells must lie in 1..=4096, got {cells}");
    }
    if a.ages.is_empty() || a.ages.len() > 16 {
        bail!("--ages must list 1 to 16 ages");
    }
    for &age in &a.ages {
        check_age(age)?;
    }
    if !(1..=16).contains(&a.variants) {
        bail!("--variants must lie in 1..=16, got {}", a.variants);
    }
    if !(a.detail.is_finite() && (0.1..=4.0).contains(&a.detail)) {
        bail!("--detail must lie in 0.1..=4, got {}", a.detail);
    }
    check_sun(a.sun_elevation, a.sun_azimuth)
}

/// Builds the scene.
pub fn generate(a: &Args) -> Result<Scene> {
    let size = a
        .size
        .unwrap_or(7.0 * (a.trees.max(1) as f32).sqrt().max(2.0));
    let relief = a.relief.unwrap_or(0.03 * size);
    let cells = a
        .cells
        .unwrap_or(((size / 2.0).round() as u32).clamp(8, 1024));
    check(a, size, relief, cells)?;
    let rng = Rng::new(a.common.seed);
    let mut scene = a.bands.scene();
    let mats = add_tree_materials(&mut scene, a.bands);
    let soil = add_soil(&mut scene, a.bands);
    let mut species = Species::poplar();
    species.densify(a.detail);
    let mut originals: Vec<Original> = Vec::new();
    let mut variants = exact_variants(&species, mats, a.variants, &rng.fork(1), &mut originals);
    // Tree originals, one per age, made of exact instances of the variants.
    let mut trees = Vec::new();
    let mut top: f32 = 0.0;
    for (k, &age) in a.ages.iter().enumerate() {
        let height = species.height(age);
        let root = grow(
            &species,
            TRUNK,
            age,
            height,
            mats,
            &rng.fork(100 + k as u64),
            &mut variants,
        );
        top = top.max(bounds(&root, &originals).max.z);
        // The trunk's base radius, widened a little: the footprint that must touch ground.
        trees.push((originals.len(), species.axes[0].radius_ratio * height * 1.2));
        originals.push(Original {
            name: format!("poplar-{k}-{age}y"),
            root,
        });
    }
    let terrain = Terrain::hills(size, cells, relief, &mut rng.fork(2));
    // Trees on a jittered grid over the terrain.
    let cols = (a.trees as f32).sqrt().ceil() as u32;
    let spacing = size / cols as f32;
    let mut forest = Cluster::named("trees");
    for i in 0..a.trees {
        let mut r = rng.fork(1000 + i as u64);
        let (cx, cy) = ((i % cols) as f32 + 0.5, (i / cols) as f32 + 0.5);
        let x = -0.5 * size + (cx + r.range(-0.3, 0.3)) * spacing;
        let y = -0.5 * size + (cy + r.range(-0.3, 0.3)) * spacing;
        let k = r.int(0, trees.len() as u32 - 1) as usize;
        let scale = r.vary(1.0, 0.08);
        let (original, footprint) = trees[k];
        let z = terrain.footing(x, y, footprint * scale);
        forest.children.push(Cluster {
            axis: Some(TRUNK),
            age: Some(a.ages[k]),
            instance: Some(InstanceOf {
                original,
                exact: true,
                transform: Similarity {
                    rotation: Quat::from_rotation_z(r.range(0.0, std::f32::consts::TAU)),
                    translation: Vec3::new(x, y, z),
                    scale,
                },
            }),
            ..Cluster::default()
        });
    }
    scene.originals = originals;
    let (lo, hi) = terrain.range();
    scene.root = Cluster {
        name: Some("forest".to_string()),
        children: vec![terrain.cluster(soil, 16), forest],
        ..Cluster::default()
    };
    sun_and_sky(&mut scene, a.bands, a.sun_elevation, a.sun_azimuth);
    let half = 0.5 * size;
    scene.cameras.push(framing_camera(
        "overview",
        Vec3::new(-half, -half, lo),
        Vec3::new(half, half, hi + top),
        30.0,
        -120.0,
        40.0,
    ));
    Ok(scene)
}
