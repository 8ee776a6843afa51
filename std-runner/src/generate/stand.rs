//! `hirad gen stand`: poplars of several ages on a ground plane, lit by bulbs, as in the
//! paper's figure 7 (1,210,925 polygons).
//!
//! Each age class is one tree original grown like `gen poplar` (its axes approximate
//! instances of the shared branch originals); the trees are *exact* instances of these,
//! turned about z and spaced on a jittered grid. The only light comes from bulbs: exact
//! instances of one bulb original of about 1,000 small emitting polygons in 8 clusters, hung
//! among the crowns. Units: metres, years, W/m^2.

use super::Common;
use super::bulb;
use super::poplar::{check_age, grow_tree};
use super::rng::Rng;
use super::tree::materials::{Bands, add_emitter, add_soil, add_tree_materials};
use super::tree::site::{bounds, framing_camera, ground};
use super::tree::{Species, TRUNK, approximate_originals};
use crate::scene::{Cluster, InstanceOf, Original, Scene, Similarity};
use anyhow::{Result, bail};
use bulb::{BulbShape, bulb};
use glam::{Quat, Vec3};

/// Stand presets.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Preset {
    /// 20 poplars of 30, 20 and 12 years (5, 10 and 5 trees) and 4 bulbs: about 1,210,000
    /// polygons, the paper's figure 7.
    Paper,
    /// 4 young poplars (8 and 5 years) and 1 bulb: quick solves and tests.
    Small,
}

impl Preset {
    fn ages(self) -> Vec<f32> {
        match self {
            Preset::Paper => vec![30.0, 20.0, 12.0],
            Preset::Small => vec![8.0, 5.0],
        }
    }

    fn counts(self) -> Vec<u32> {
        match self {
            Preset::Paper => vec![5, 10, 5],
            Preset::Small => vec![2, 2],
        }
    }

    fn bulbs(self) -> u32 {
        match self {
            Preset::Paper => 4,
            Preset::Small => 1,
        }
    }
}

/// Arguments of `hirad gen stand`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  hirad gen stand --preset paper -o stand.hirb   # ~1.2 million polygons\n  hirad gen stand --seed 3 -o stand3.hirb"
)]
pub struct Args {
    /// Seed, output and summary.
    #[command(flatten)]
    pub common: Common,
    /// The stand to start from; the options below override it.
    #[arg(long, value_enum, default_value_t = Preset::Paper)]
    pub preset: Preset,
    /// Ages of the tree classes (years, comma-separated); one tree original per age.
    #[arg(long, value_delimiter = ',')]
    pub ages: Option<Vec<f32>>,
    /// Trees of each age (comma-separated, one per age).
    #[arg(long, value_delimiter = ',')]
    pub counts: Option<Vec<u32>>,
    /// Total number of trees: scales the counts, keeping their proportions.
    #[arg(long)]
    pub trees: Option<u32>,
    /// Distance between neighbouring trees (m).
    #[arg(long, default_value_t = 7.0)]
    pub spacing: f32,
    /// Number of bulbs.
    #[arg(long)]
    pub bulbs: Option<u32>,
    /// Emitting polygons per bulb (about; in 8 clusters).
    #[arg(long, default_value_t = 1000)]
    pub bulb_polygons: u32,
    /// Bulb radius (m).
    #[arg(long, default_value_t = 0.5)]
    pub bulb_radius: f32,
    /// Irradiance a bulb gives the ground right below it, per unit of its band weights
    /// (W/m^2): sets the bulbs' exitance.
    #[arg(long, default_value_t = 10.0)]
    pub bulb_irradiance: f32,
    /// Spectral bands.
    #[arg(long, value_enum, default_value_t = Bands::ParNir)]
    pub bands: Bands,
}

/// Trees per class: `counts`, scaled to `total` by largest remainders when given.
fn class_counts(counts: &[u32], total: Option<u32>) -> Vec<u32> {
    let Some(total) = total else {
        return counts.to_vec();
    };
    let sum: u32 = counts.iter().sum();
    let exact: Vec<f64> = counts
        .iter()
        .map(|&c| c as f64 * total as f64 / sum.max(1) as f64)
        .collect();
    let mut out: Vec<u32> = exact.iter().map(|e| e.floor() as u32).collect();
    let mut order: Vec<usize> = (0..counts.len()).collect();
    order.sort_by(|&a, &b| (exact[b] - exact[b].floor()).total_cmp(&(exact[a] - exact[a].floor())));
    let mut left = total - out.iter().sum::<u32>();
    for &i in order.iter().cycle().take(counts.len() * 2) {
        if left == 0 {
            break;
        }
        out[i] += 1;
        left -= 1;
    }
    out
}

fn check(a: &Args, ages: &[f32], counts: &[u32]) -> Result<()> {
    if ages.is_empty() || ages.len() != counts.len() {
        bail!(
            "--ages and --counts must list the same number of classes (got {} and {})",
            ages.len(),
            counts.len()
        );
    }
    let trees: u32 = counts.iter().sum();
    if !(1..=10_000).contains(&trees) {
        bail!("the stand must have 1 to 10000 trees, got {trees}");
    }
    if !(a.spacing.is_finite() && (0.5..=1000.0).contains(&a.spacing)) {
        bail!("--spacing must lie in 0.5..=1000 m, got {}", a.spacing);
    }
    if !(64..=100_000).contains(&a.bulb_polygons) {
        bail!(
            "--bulb-polygons must lie in 64..=100000, got {}",
            a.bulb_polygons
        );
    }
    if !(a.bulb_radius.is_finite() && (0.01..=10.0).contains(&a.bulb_radius)) {
        bail!(
            "--bulb-radius must lie in 0.01..=10 m, got {}",
            a.bulb_radius
        );
    }
    if !(a.bulb_irradiance.is_finite() && a.bulb_irradiance > 0.0) {
        bail!(
            "--bulb-irradiance must be positive, got {}",
            a.bulb_irradiance
        );
    }
    Ok(())
}

/// Builds the scene.
pub fn generate(a: &Args) -> Result<Scene> {
    let calibrate = a.preset == Preset::Paper
        && a.ages.is_none()
        && a.counts.is_none()
        && a.trees.is_none()
        && a.bulbs.is_none()
        && a.bulb_polygons == 1000;
    if !calibrate {
        return build(a, None);
    }
    // The paper preset holds for any seed: nudge the mean leaf count per shoot (22 first)
    // until the stand lands within 3% of the paper's 1.21 million polygons.
    let mut best: Option<(f64, Scene)> = None;
    for leaves in [22u32, 21, 23, 20, 24, 19, 25, 18, 26] {
        let scene = build(a, Some(leaves))?;
        let n = crate::scene::compile(&scene)
            .ok()
            .and_then(|b| {
                crate::scene::read_image(&b)
                    .ok()
                    .map(|v| v.info().expanded_polygons)
            })
            .unwrap_or(0) as f64;
        let off = (n / PAPER_POLYGONS as f64 - 1.0).abs();
        if off <= 0.03 {
            return Ok(scene);
        }
        if best.as_ref().is_none_or(|(o, _)| off < *o) {
            best = Some((off, scene));
        }
    }
    Ok(best
        .map(|(_, s)| s)
        .expect("at least one candidate was built"))
}

/// The paper's stand: polygons after expansion (its figure 7).
pub const PAPER_POLYGONS: u64 = 1_210_925;

fn build(a: &Args, leaves: Option<u32>) -> Result<Scene> {
    let ages = a.ages.clone().unwrap_or_else(|| a.preset.ages());
    let counts = class_counts(
        &a.counts.clone().unwrap_or_else(|| a.preset.counts()),
        a.trees,
    );
    check(a, &ages, &counts)?;
    let bulbs = a.bulbs.unwrap_or(a.preset.bulbs());
    if !(1..=1000).contains(&bulbs) {
        bail!("--bulbs must lie in 1..=1000 (the bulbs are the stand's only light), got {bulbs}");
    }
    let rng = Rng::new(a.common.seed);
    let mut scene = a.bands.scene();
    let mats = add_tree_materials(&mut scene, a.bands);
    let soil = add_soil(&mut scene, a.bands);
    for &age in &ages {
        check_age(age)?;
    }
    let mut species = Species::poplar();
    if let Some(n) = leaves {
        species.shoot.leaves = n;
    }
    let mut originals: Vec<Original> = Vec::new();
    let mut model = approximate_originals(&species, mats, &rng.fork(1), &mut originals);
    // One tree original per age class.
    let mut tree_originals = Vec::new();
    let mut top: f32 = 0.0;
    let mut crown: f32 = 0.0;
    for (k, &age) in ages.iter().enumerate() {
        let mut t = grow_tree(&species, age, mats, &rng.fork(100 + k as u64), &mut model);
        t.name = Some(format!("poplar-{k}-{age}y"));
        let b = bounds(&t, &originals);
        top = top.max(b.max.z);
        crown = crown.max(b.min.x.abs().max(b.max.x).max(b.min.y.abs()).max(b.max.y));
        tree_originals.push(originals.len());
        originals.push(Original {
            name: format!("poplar-{k}-{age}y"),
            root: t,
        });
    }
    // Trees on a jittered grid, classes shuffled over it, each turned about z.
    let total: u32 = counts.iter().sum();
    let cols = (total as f32).sqrt().ceil() as u32;
    let rows = total.div_ceil(cols);
    let mut classes: Vec<usize> = counts
        .iter()
        .enumerate()
        .flat_map(|(k, &n)| std::iter::repeat_n(k, n as usize))
        .collect();
    let mut shuffle = rng.fork(2);
    for i in (1..classes.len()).rev() {
        classes.swap(i, shuffle.int(0, i as u32) as usize);
    }
    let half = Vec3::new(cols as f32 - 1.0, rows as f32 - 1.0, 0.0) * (0.5 * a.spacing);
    let mut trees = Cluster::named("trees");
    for (i, &class) in classes.iter().enumerate() {
        let mut r = rng.fork(1000 + i as u64);
        let (cx, cy) = ((i as u32 % cols) as f32, (i as u32 / cols) as f32);
        let jitter = 0.15 * a.spacing;
        let at = Vec3::new(
            cx * a.spacing + r.range(-jitter, jitter),
            cy * a.spacing + r.range(-jitter, jitter),
            0.0,
        ) - half;
        trees.children.push(Cluster {
            name: Some(format!("tree-{i}")),
            axis: Some(TRUNK),
            age: Some(ages[class]),
            instance: Some(InstanceOf {
                original: tree_originals[class],
                exact: true,
                transform: Similarity {
                    rotation: Quat::from_rotation_z(r.range(0.0, std::f32::consts::TAU)),
                    translation: at,
                    scale: r.vary(1.0, 0.05),
                },
            }),
            ..Cluster::default()
        });
    }
    // Bulbs: hung at 80% of the tallest crown, between trees, spread over the stand.
    let shape = BulbShape::with_polygons(a.bulb_radius, a.bulb_polygons);
    let hang = 0.8 * top;
    let weights = a.bands.pick([1.0, 1.5], [1.0, 0.85, 0.65]);
    let exitance: Vec<f32> = weights
        .iter()
        .map(|w| w * a.bulb_irradiance * (hang / a.bulb_radius).powi(2))
        .collect();
    let lamp = add_emitter(
        &mut scene,
        "bulb",
        &a.bands.pick([0.8; 2], [0.8; 3]),
        &exitance,
    );
    let bulb_original = originals.len();
    originals.push(Original {
        name: "bulb".to_string(),
        root: bulb(&shape, lamp),
    });
    let mut lights = Cluster::named("bulbs");
    let bc = ((bulbs as f32).sqrt().ceil() as u32).max(1);
    let br = bulbs.div_ceil(bc).max(1);
    // Grid coordinate of the gap between two rows of trees nearest to fraction `u`.
    let between = |u: f32, n: u32| {
        if n < 2 {
            0.5
        } else {
            (u * (n - 1) as f32).floor().min((n - 2) as f32) + 0.5
        }
    };
    for b in 0..bulbs {
        let u = ((b % bc) as f32 + 0.5) / bc as f32;
        let v = ((b / bc) as f32 + 0.5) / br as f32;
        let at = Vec3::new(
            between(u, cols) * a.spacing,
            between(v, rows) * a.spacing,
            hang,
        ) - half;
        lights.children.push(Cluster {
            name: Some(format!("bulb-{b}")),
            instance: Some(InstanceOf {
                original: bulb_original,
                exact: true,
                transform: Similarity {
                    translation: at,
                    ..Similarity::IDENTITY
                },
            }),
            ..Cluster::default()
        });
    }
    scene.originals = originals;
    let extent = half + Vec3::splat(crown + a.spacing);
    let side = 2.0 * extent.x.max(extent.y);
    let tiles = ((side / 2.5).round() as u32).clamp(8, 64) | 1;
    scene.root = Cluster {
        name: Some("stand".to_string()),
        children: vec![ground(side, tiles, soil), trees, lights],
        ..Cluster::default()
    };
    let lo = Vec3::new(-half.x - crown, -half.y - crown, 0.0);
    let hi = Vec3::new(half.x + crown, half.y + crown, top);
    scene
        .cameras
        .push(framing_camera("overview", lo, hi, 25.0, -110.0, 45.0));
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::class_counts;

    #[test]
    fn counts_keep_their_proportions() {
        assert_eq!(class_counts(&[5, 9, 6], None), vec![5, 9, 6]);
        assert_eq!(class_counts(&[5, 9, 6], Some(40)), vec![10, 18, 12]);
        assert_eq!(class_counts(&[5, 9, 6], Some(3)).iter().sum::<u32>(), 3);
        assert_eq!(class_counts(&[1, 1], Some(1)).iter().sum::<u32>(), 1);
    }
}
