//! `hirad gen poplar`, `gen stand` and `gen forest` end to end: the files they write are
//! identical for the same seed, differ for another, read back as valid scenes, and unusable
//! options are refused before anything is written.

use hirad::files::open_image;
use hirad::generate::tree::Bands;
use hirad::generate::{Args, Common, Kind, forest, poplar, stand};
use std::path::Path;

/// What a test asks for: a generator, its preset and a few options.
#[derive(Clone, Copy)]
enum Gen {
    Poplar {
        age: Option<f32>,
        height: Option<f32>,
        sun_elevation: f32,
    },
    Stand {
        ages: Option<&'static [f32]>,
        counts: Option<&'static [u32]>,
        bulb_polygons: u32,
    },
    Forest {
        trees: u32,
        cells: Option<u32>,
        variants: u32,
    },
}

const POPLAR: Gen = Gen::Poplar {
    age: None,
    height: None,
    sun_elevation: 55.0,
};
const STAND: Gen = Gen::Stand {
    ages: None,
    counts: None,
    bulb_polygons: 1000,
};
const FOREST: Gen = Gen::Forest {
    trees: 9,
    cells: Some(12),
    variants: 3,
};

/// Runs `hirad gen` for `g` with `seed` and `bands`, writing `out` (quietly).
fn gen_to(g: Gen, seed: u64, bands: Bands, out: &Path) -> anyhow::Result<()> {
    let common = Common {
        seed,
        output: out.to_path_buf(),
        quiet: true,
    };
    let kind = match g {
        Gen::Poplar {
            age,
            height,
            sun_elevation,
        } => Kind::Poplar(poplar::Args {
            common,
            preset: poplar::Preset::Young,
            age,
            height,
            leaves: None,
            bands,
            sun_elevation,
            sun_azimuth: -120.0,
        }),
        Gen::Stand {
            ages,
            counts,
            bulb_polygons,
        } => Kind::Stand(stand::Args {
            common,
            preset: stand::Preset::Small,
            ages: ages.map(|a| a.to_vec()),
            counts: counts.map(|c| c.to_vec()),
            trees: None,
            spacing: 7.0,
            bulbs: None,
            bulb_polygons,
            bulb_radius: 0.5,
            bulb_irradiance: 10.0,
            bands,
        }),
        Gen::Forest {
            trees,
            cells,
            variants,
        } => Kind::Forest(forest::Args {
            common,
            trees,
            size: None,
            relief: None,
            cells,
            ages: vec![25.0, 30.0, 35.0],
            variants,
            detail: 2.1,
            bands,
            sun_elevation: 50.0,
            sun_azimuth: -120.0,
        }),
    };
    hirad::generate::run(Args { kind })
}

fn bytes(g: Gen, seed: u64, dir: &Path, name: &str) -> Vec<u8> {
    let path = dir.join(name);
    gen_to(g, seed, Bands::ParNir, &path).unwrap();
    std::fs::read(path).unwrap()
}

#[test]
fn same_seed_same_bytes_other_seed_other_bytes() {
    let dir = tempfile::tempdir().unwrap();
    for (k, g) in [POPLAR, STAND, FOREST].into_iter().enumerate() {
        let a = bytes(g, 5, dir.path(), "a.hirb");
        let b = bytes(g, 5, dir.path(), "b.hirb");
        let c = bytes(g, 6, dir.path(), "c.hirb");
        assert_eq!(a, b, "generator {k}");
        assert_ne!(a, c, "generator {k}");
    }
}

#[test]
fn written_scenes_read_back() {
    let dir = tempfile::tempdir().unwrap();
    let poplar = dir.path().join("poplar.hirb");
    gen_to(POPLAR, 1, Bands::Rgb, &poplar).unwrap();
    let view = open_image(&poplar).unwrap();
    let info = view.info();
    assert_eq!(
        (info.bands, info.originals, info.instancing_depth),
        (3, 5, 4)
    );
    // The text form parses back to the same scene.
    let text = dir.path().join("poplar.hir");
    gen_to(POPLAR, 1, Bands::Rgb, &text).unwrap();
    let parsed = hirad::text::parse(&std::fs::read(&text).unwrap()).unwrap();
    assert_eq!(
        hirad::scene::compile(&parsed).unwrap(),
        std::fs::read(&poplar).unwrap()
    );
    let forest = dir.path().join("forest.hirb");
    let many = Gen::Forest {
        trees: 25,
        cells: None,
        variants: 3,
    };
    gen_to(many, 1, Bands::ParNir, &forest).unwrap();
    let info = *open_image(&forest).unwrap().info();
    assert!(info.expanded_polygons > 10_000_000, "{info:?}");
    assert_eq!(info.approximate_instances, 0);
}

#[test]
fn unusable_options_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.hirb");
    let refused = [
        Gen::Poplar {
            age: Some(0.0),
            height: None,
            sun_elevation: 55.0,
        },
        Gen::Poplar {
            age: None,
            height: Some(-3.0),
            sun_elevation: 55.0,
        },
        Gen::Poplar {
            age: None,
            height: None,
            sun_elevation: 95.0,
        },
        Gen::Stand {
            ages: Some(&[30.0, 20.0]),
            counts: Some(&[1]),
            bulb_polygons: 1000,
        },
        Gen::Stand {
            ages: None,
            counts: None,
            bulb_polygons: 3,
        },
        Gen::Forest {
            trees: 0,
            cells: None,
            variants: 3,
        },
        Gen::Forest {
            trees: 4,
            cells: None,
            variants: 0,
        },
    ];
    for (k, g) in refused.into_iter().enumerate() {
        assert!(gen_to(g, 1, Bands::ParNir, &out).is_err(), "case {k}");
    }
    assert!(!out.exists());
}
