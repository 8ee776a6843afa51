//! `hirad gen canopy`: a crop field — rows of maize-like or wheat-like plants on bare soil,
//! lit by a sun and a standard overcast sky, in two bands (`par nir`).
//!
//! Rows run along x, one every `--row-spacing` metres in y, with a plant every
//! `--plant-spacing` metres; each plant is an exact instance of one of a few originals
//! (`--variants`, see `crop`), turned to a random azimuth and moved by a small random jitter.
//! The soil is a grid of tiles reaching `--margin` metres beyond the plants, so that bare
//! soil in the open can be compared with soil under the canopy. Leaves reflect 0.08 (PAR)
//! and 0.45 (NIR) and transmit 0.05 and 0.45; the soil reflects 0.1 and 0.25.
//!
//! Defaults and polygons after expansion (seed 1): maize, 24 rows x 100 plants, 0.75 m by
//! 0.2 m (a 17 x 20 m field of 2,400 plants; variants of 210 to 218 polygons; 3,648 soil
//! tiles): 519,032 polygons. Wheat, 30 rows x 80 plants, 0.17 m by 0.05 m (a 4 x 5 m field
//! of 2,400 plants of 3 or 4 tillers, 198 to 264 polygons; 2,592 soil tiles): 571,710
//! polygons. The compact scenes hold under 5,000 polygons (about 0.6 MB as .hirb).
//!
//! Units: metres, W/m^2 (sun: 400 PAR and 420 NIR on a plane facing it; sky: 80 PAR and 60
//! NIR on the horizontal).

use super::Common;
use super::crop;
use super::palette::{diffuse, two_sided};
use super::rng::Rng;
use super::sky::{SkyModel, sky, sun};
use crate::scene::{Camera, Cluster, InstanceOf, Original, Scene, Similarity};
use anyhow::{Result, bail};
use crop::CropMaterials;
use glam::{Quat, Vec2, Vec3};
use std::f32::consts::TAU;

/// The crop species.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Crop {
    /// Maize: tall plants with a dozen long arching leaves, 0.75 m rows.
    Maize,
    /// Wheat: clumps of thin tillers with narrow leaves and ears, 0.17 m rows.
    Wheat,
}

/// Arguments of `hirad gen canopy`.
#[derive(clap::Args, Debug, Clone)]
#[command(
    after_help = "Examples:\n  hirad gen canopy -o maize.hirb                # 24 rows of 100 maize plants\n  hirad gen canopy --crop wheat --rows 6 --plants-per-row 20 -o wheat.hirb\n  hirad gen canopy --rows 2 --plants-per-row 2 -o small.hir"
)]
pub struct Args {
    /// The crop.
    #[arg(long, value_enum, default_value_t = Crop::Maize)]
    pub crop: Crop,
    /// Number of rows (default: 24 for maize, 30 for wheat).
    #[arg(long)]
    pub rows: Option<u32>,
    /// Plants in each row (default: 100 for maize, 80 for wheat).
    #[arg(long)]
    pub plants_per_row: Option<u32>,
    /// Distance between rows (m; default: 0.75 for maize, 0.17 for wheat).
    #[arg(long)]
    pub row_spacing: Option<f32>,
    /// Distance between plants in a row (m; default: 0.2 for maize, 0.05 for wheat).
    #[arg(long)]
    pub plant_spacing: Option<f32>,
    /// Number of different plant originals.
    #[arg(long, default_value_t = 5)]
    pub variants: u32,
    /// Bare soil beyond the outer plants (m).
    #[arg(long, default_value_t = 2.0)]
    pub margin: f32,
    /// Sun elevation above the horizon (degrees).
    #[arg(long, default_value_t = 45.0)]
    pub sun_elevation: f32,
    /// Sun azimuth, from +x (along the rows) towards +y (degrees).
    #[arg(long, default_value_t = 240.0)]
    pub sun_azimuth: f32,
    /// Rings of sky directions (about 2 n^2 + 2 n directions).
    #[arg(long, default_value_t = 6)]
    pub sky_rings: u32,
    /// Seed, output and summary.
    #[command(flatten)]
    pub common: Common,
}

/// The field's layout after defaults.
#[derive(Clone, Copy, Debug)]
struct Field {
    rows: u32,
    per_row: u32,
    row_spacing: f32,
    plant_spacing: f32,
}

impl Field {
    fn of(a: &Args) -> Result<Field> {
        let (rows, per_row, rs, ps) = match a.crop {
            Crop::Maize => (24, 100, 0.75, 0.2),
            Crop::Wheat => (30, 80, 0.17, 0.05),
        };
        let f = Field {
            rows: a.rows.unwrap_or(rows),
            per_row: a.plants_per_row.unwrap_or(per_row),
            row_spacing: a.row_spacing.unwrap_or(rs),
            plant_spacing: a.plant_spacing.unwrap_or(ps),
        };
        if f.rows == 0 || f.per_row == 0 {
            bail!("--rows and --plants-per-row must be at least 1");
        }
        if u64::from(f.rows) * u64::from(f.per_row) > 10_000_000 {
            bail!("at most 10,000,000 plants");
        }
        for (v, what) in [
            (f.row_spacing, "--row-spacing"),
            (f.plant_spacing, "--plant-spacing"),
        ] {
            if !(v.is_finite() && (0.01..=100.0).contains(&v)) {
                bail!("{what} must lie between 0.01 and 100 m, got {v}");
            }
        }
        Ok(f)
    }

    /// Extent of the plant positions: (length along x, width along y) (m).
    fn size(&self) -> Vec2 {
        Vec2::new(
            (self.per_row - 1) as f32 * self.plant_spacing,
            (self.rows - 1) as f32 * self.row_spacing,
        )
    }
}

/// Boundaries of tiles of side `t` covering [lo, hi], aligned so that `anchor` is a
/// tile's centre.
fn tile_cuts(lo: f32, hi: f32, t: f32, anchor: f32) -> Vec<f32> {
    let first = ((lo - anchor) / t + 0.5).floor();
    let last = ((hi - anchor) / t + 0.5).ceil();
    (first as i64..=last as i64)
        .map(|k| anchor + (k as f32 - 0.5) * t)
        .collect()
}

/// The soil: square tiles in strips along the rows, facing up. Tiles are half a row
/// spacing wide (one on each row, one between rows) when that is at least 0.2 m, else a
/// row spacing wide.
fn soil(field: &Field, margin: f32, material: u32) -> Cluster {
    let size = field.size();
    let rs = field.row_spacing;
    let t = if rs * 0.5 >= 0.2 { rs * 0.5 } else { rs };
    let ys = tile_cuts(-margin, size.y + margin, t, 0.0);
    let xs = tile_cuts(-margin, size.x + margin, t, 0.0);
    let mut soil = Cluster::named("soil");
    for (k, yw) in ys.windows(2).enumerate() {
        let mut strip = Cluster::named(&format!("strip{k}"));
        for xw in xs.windows(2) {
            let c = |x: f32, y: f32| Vec3::new(x, y, 0.0);
            super::shapes::add_quad(
                &mut strip,
                [
                    c(xw[0], yw[0]),
                    c(xw[1], yw[0]),
                    c(xw[1], yw[1]),
                    c(xw[0], yw[1]),
                ],
                material,
            );
        }
        soil.children.push(strip);
    }
    soil
}

impl Args {
    /// Reads the options of `hirad gen canopy` from command-line words (without the command
    /// itself), with the same defaults as the command line, e.g. `["-o", "x.hirb"]`.
    pub fn from_words<I, T>(words: I) -> Result<Args>
    where
        I: IntoIterator<Item = T>,
        T: Into<std::ffi::OsString> + Clone,
    {
        super::args_from_words("canopy", words)
    }
}

/// Builds the scene.
pub fn generate(a: &Args) -> Result<Scene> {
    let field = Field::of(a)?;
    if !(1..=16).contains(&a.variants) {
        bail!("--variants must lie in 1..=16");
    }
    if !(a.margin.is_finite() && (0.0..=1000.0).contains(&a.margin)) {
        bail!("--margin must lie between 0 and 1000 m");
    }
    let sun_ok = a.sun_elevation > 0.0 && a.sun_elevation <= 90.0 && a.sun_azimuth.is_finite();
    if !sun_ok {
        bail!("--sun-elevation must lie in (0, 90] degrees and --sun-azimuth be a number");
    }
    if !(1..=32).contains(&a.sky_rings) {
        bail!("--sky-rings must lie in 1..=32");
    }
    let rng = Rng::new(a.common.seed);
    let mut scene = Scene::new(2);
    scene.band_names = ["par", "nir"].map(String::from).to_vec();
    let soil_m = diffuse(&mut scene, "soil", &[0.1, 0.25]);
    let m = CropMaterials {
        leaf: two_sided(
            &mut scene,
            "leaf",
            &[0.08, 0.45],
            &[0.1, 0.45],
            &[0.05, 0.45],
        ),
        stem: diffuse(&mut scene, "stem", &[0.1, 0.4]),
        ear: match a.crop {
            Crop::Maize => diffuse(&mut scene, "ear", &[0.12, 0.45]),
            Crop::Wheat => diffuse(&mut scene, "ear", &[0.2, 0.5]),
        },
        tassel: diffuse(&mut scene, "tassel", &[0.25, 0.5]),
    };

    let (name, build): (&str, fn(&CropMaterials, &mut Rng) -> Cluster) = match a.crop {
        Crop::Maize => ("maize", crop::maize),
        Crop::Wheat => ("wheat", crop::wheat),
    };
    let mut height = 0.0f32;
    for v in 0..a.variants {
        let root = build(&m, &mut rng.fork(1 + u64::from(v)));
        height = height.max(super::mesh::bounds(&root).max.z);
        scene.originals.push(Original {
            name: format!("{name}{v}"),
            root,
        });
    }

    let mut place = rng.fork(100);
    let mut crop_rows = Cluster::named("crop");
    for r in 0..field.rows {
        let mut row = Cluster::named(&format!("row{r}"));
        for j in 0..field.per_row {
            let along = place.range(-0.15, 0.15) * field.plant_spacing;
            let across = place.range(-0.1, 0.1) * field.row_spacing.min(0.3);
            let original = place.int(0, a.variants - 1) as usize;
            let turn = Quat::from_rotation_z(place.range(0.0, TAU));
            row.children.push(Cluster {
                name: Some(format!("r{r}p{j}")),
                instance: Some(InstanceOf {
                    original,
                    exact: true,
                    transform: Similarity {
                        rotation: turn,
                        translation: Vec3::new(
                            j as f32 * field.plant_spacing + along,
                            r as f32 * field.row_spacing + across,
                            0.0,
                        ),
                        scale: 1.0,
                    },
                }),
                ..Cluster::default()
            });
        }
        crop_rows.children.push(row);
    }
    scene.root = Cluster {
        name: Some("field".into()),
        children: vec![soil(&field, a.margin, soil_m), crop_rows],
        ..Cluster::default()
    };

    scene.suns = vec![sun(a.sun_elevation, a.sun_azimuth, &[400.0, 420.0])];
    scene.sky = sky(a.sky_rings, SkyModel::StandardOvercast, &[80.0, 60.0]);

    let size = field.size();
    let mid = size * 0.5;
    scene.cameras = vec![
        Camera {
            name: Some("across".into()),
            position: Vec3::new(mid.x, -a.margin - 1.5 * height, 2.4 * height),
            target: Vec3::new(mid.x, mid.y * 0.5, 0.0),
            up: Vec3::Z,
            fovy_deg: 50.0,
        },
        Camera {
            name: Some("along".into()),
            position: Vec3::new(
                -a.margin,
                (field.rows / 2) as f32 * field.row_spacing - 0.5 * field.row_spacing,
                1.3 * height,
            ),
            target: Vec3::new(
                size.x,
                (field.rows / 2) as f32 * field.row_spacing - 0.5 * field.row_spacing,
                0.2 * height,
            ),
            up: Vec3::Z,
            fovy_deg: 50.0,
        },
    ];
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn soil_tiles_centre_on_rows_and_between_them() {
        let cuts = tile_cuts(-1.0, 3.0, 0.375, 0.0);
        assert!(cuts[0] <= -1.0 && *cuts.last().unwrap() >= 3.0);
        for w in cuts.windows(2) {
            let centre = 0.5 * (w[0] + w[1]);
            assert!(((centre / 0.375) - (centre / 0.375).round()).abs() < 1e-4);
        }
        let field = Field {
            rows: 3,
            per_row: 4,
            row_spacing: 0.75,
            plant_spacing: 0.2,
        };
        let s = soil(&field, 1.0, 0);
        let tiles: usize = s.children.iter().map(|c| c.polygons.len()).sum();
        // Tiles of 0.375 m centred on multiples of 0.375 m, covering at least -1..2.5 m
        // across (-1.3125..2.8125: 11 strips) and -1..1.6 m along (-1.3125..1.6875: 8).
        assert_eq!(s.children.len(), 11);
        assert_eq!(tiles, 11 * 8);
    }

    #[test]
    fn bad_options_are_refused() {
        for words in [
            &["--rows", "0"][..],
            &["--row-spacing", "0"],
            &["--variants", "0"],
            &["--sun-elevation=-5"],
            &["--sky-rings", "0"],
            &["--margin", "nan"],
        ] {
            let a = Args::from_words(["-o", "x.hirb"].iter().chain(words)).unwrap();
            assert!(generate(&a).is_err(), "{words:?}");
        }
    }
}
