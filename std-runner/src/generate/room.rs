//! `hirad gen room`: the furnished room of the paper's section 5.1 — about 55,000 polygons
//! once expanded, in which every object is an exact instance of one of four originals: 24
//! chairs, 3 tables, 3 orchids and 4 palms (the defaults).
//!
//! The room is 10.8 x 7.8 x 3 m (z up, floor at z = 0 from the origin), in three bands (red,
//! green, blue): a parquet floor, plaster walls facing in, a suspended ceiling with 18
//! recessed light panels, and two windows in the back wall whose panes glow with diffuse
//! daylight. Tables stand on a grid that fits the room, eight chairs around each, an orchid
//! on each table and a palm in each corner, all placed with random but deterministic
//! variation and no two instances' boxes overlapping. Polygons with the defaults (seed 1):
//! chair 1,488, table 1,326, orchid 1,221, palm 2,744, the room itself 930; expanded
//! 24 x 1,488 + 3 x 1,326 + 3 x 1,221 + 4 x 2,744 + 930 = 55,259 (0.5% from the paper's
//! 55,000; the tests hold it within 5%).
//!
//! Units: metres, W/m^2. The light panels are 0.3 m squares emitting 2,500 W/m^2 (warm
//! white; small and bright, so that they cover little of a picture and the automatic
//! exposure settles on the lit room); the window panes emit 50 W/m^2 of bluish daylight.

use super::Common;
use super::rng::Rng;
use super::{furniture, houseplants, mesh, palette, room_layout, room_shell};
use crate::scene::{Camera, Cluster, InstanceOf, Original, Scene};
use anyhow::{Result, bail};
use furniture::FurnitureMaterials;
use glam::Vec3;
use houseplants::PlantMaterials;
use palette::{diffuse, emitter, two_sided};
use room_layout::{Item, Kind, Request};
use room_shell::ShellMaterials;

/// Arguments of `hirad gen room`.
#[derive(clap::Args, Debug, Clone)]
#[command(
    after_help = "Examples:\n  hirad gen room -o room.hirb\n  hirad gen room -o room.hirb && hirad solve room.hirb --image room.png"
)]
pub struct Args {
    /// Chairs (eight around each table, the rest along the walls).
    #[arg(long, default_value_t = 24)]
    pub chairs: u32,
    /// Tables.
    #[arg(long, default_value_t = 3)]
    pub tables: u32,
    /// Orchids (one on each table, the rest along the walls).
    #[arg(long, default_value_t = 3)]
    pub orchids: u32,
    /// Potted palms (in the corners, then along the walls).
    #[arg(long, default_value_t = 4)]
    pub plants: u32,
    /// Room length along x (m).
    #[arg(long, default_value_t = 10.8)]
    pub length: f32,
    /// Room width along y (m).
    #[arg(long, default_value_t = 7.8)]
    pub width: f32,
    /// Room height (m).
    #[arg(long, default_value_t = 3.0)]
    pub height: f32,
    /// Seed, output and summary.
    #[command(flatten)]
    pub common: Common,
}

/// Names of the originals, in index order (the order of [`Kind`]).
pub const ORIGINALS: [&str; 4] = ["chair", "table", "orchid", "palm"];

/// Materials of every part of the room.
struct Materials {
    shell: ShellMaterials,
    furniture: FurnitureMaterials,
    plants: PlantMaterials,
}

/// Adds the room's materials (red, green, blue reflectances; exitances in W/m^2).
fn materials(s: &mut Scene) -> Materials {
    let shell = ShellMaterials {
        plaster: diffuse(s, "plaster", &[0.78, 0.75, 0.7]),
        ceiling: diffuse(s, "ceiling", &[0.82, 0.82, 0.8]),
        parquet: [
            diffuse(s, "oak", &[0.48, 0.32, 0.18]),
            diffuse(s, "walnut", &[0.4, 0.26, 0.14]),
        ],
        trim: diffuse(s, "trim", &[0.85, 0.85, 0.83]),
        lamp: emitter(s, "lamp", &[0.8, 0.8, 0.8], &[2600.0, 2500.0, 2200.0]),
        daylight: emitter(s, "daylight", &[0.1, 0.1, 0.1], &[42.0, 48.0, 58.0]),
    };
    let furniture = FurnitureMaterials {
        chair_wood: diffuse(s, "chair_wood", &[0.3, 0.17, 0.09]),
        fabric: diffuse(s, "fabric", &[0.55, 0.12, 0.1]),
        table_wood: diffuse(s, "table_wood", &[0.46, 0.29, 0.16]),
    };
    let plants = PlantMaterials {
        ceramic: diffuse(s, "ceramic", &[0.85, 0.85, 0.82]),
        terracotta: diffuse(s, "terracotta", &[0.6, 0.3, 0.18]),
        soil: diffuse(s, "potting_soil", &[0.12, 0.09, 0.07]),
        bark: diffuse(s, "bark", &[0.32, 0.2, 0.12]),
        leaf: two_sided(
            s,
            "leaf",
            &[0.07, 0.22, 0.05],
            &[0.1, 0.26, 0.08],
            &[0.04, 0.18, 0.03],
        ),
        stem: diffuse(s, "stem", &[0.16, 0.3, 0.1]),
        petal: two_sided(
            s,
            "petal",
            &[0.9, 0.74, 0.88],
            &[0.85, 0.7, 0.84],
            &[0.08, 0.08, 0.08],
        ),
        lip: diffuse(s, "lip", &[0.75, 0.2, 0.45]),
        root: diffuse(s, "root", &[0.55, 0.6, 0.5]),
    };
    Materials {
        shell,
        furniture,
        plants,
    }
}

/// An exact instance of original `kind` placed by `item`.
fn instance(item: &Item, name: String) -> Cluster {
    Cluster {
        name: Some(name),
        instance: Some(InstanceOf {
            original: item.kind as usize,
            exact: true,
            transform: item.transform,
        }),
        ..Cluster::default()
    }
}

/// The furniture tree: one group per table (the table, its orchid, its chairs), then the
/// plants, then whatever stands along the walls.
fn furniture_tree(items: &[Item], tables: u32) -> Cluster {
    let mut groups: Vec<Cluster> = (0..tables)
        .map(|t| Cluster::named(&format!("table_group{t}")))
        .collect();
    let mut chairs: Vec<Cluster> = (0..tables).map(|_| Cluster::named("chairs")).collect();
    let mut plants = Cluster::named("plants");
    let mut along_walls = Cluster::named("along_walls");
    let mut counters = [0u32; 4];
    for item in items {
        let k = item.kind as usize;
        let name = format!("{}{}", ORIGINALS[k], counters[k]);
        counters[k] += 1;
        let node = instance(item, name);
        match (item.kind, item.table) {
            (Kind::Chair, Some(t)) => chairs[t].children.push(node),
            (_, Some(t)) => groups[t].children.push(node),
            (Kind::Plant, None) if plants.children.len() < 4 => plants.children.push(node),
            _ => along_walls.children.push(node),
        }
    }
    for (g, c) in groups.iter_mut().zip(chairs) {
        if !c.children.is_empty() {
            g.children.push(c);
        }
    }
    let mut root = Cluster::named("furniture");
    root.children = groups;
    for c in [plants, along_walls] {
        if !c.children.is_empty() {
            root.children.push(c);
        }
    }
    root
}

impl Args {
    /// Reads the options of `hirad gen room` from command-line words (without the command
    /// itself), with the same defaults as the command line, e.g. `["-o", "x.hirb"]`.
    pub fn from_words<I, T>(words: I) -> Result<Args>
    where
        I: IntoIterator<Item = T>,
        T: Into<std::ffi::OsString> + Clone,
    {
        super::args_from_words("room", words)
    }
}

/// Builds the scene.
pub fn generate(a: &Args) -> Result<Scene> {
    let size = Vec3::new(a.length, a.width, a.height);
    if !(size.is_finite() && size.min_element() >= 1.0 && size.max_element() <= 1000.0) {
        bail!("the room's length, width and height must lie between 1 and 1000 m");
    }
    if a.height < 2.2 {
        bail!("the room must be at least 2.2 m high for the palms and lights");
    }
    let rng = Rng::new(a.common.seed);
    let mut scene = Scene::new(3);
    scene.band_names = ["red", "green", "blue"].map(String::from).to_vec();
    let m = materials(&mut scene);

    let originals = [
        furniture::chair(m.furniture),
        furniture::table(m.furniture),
        houseplants::orchid(&m.plants, &mut rng.fork(1)),
        houseplants::palm(&m.plants, &mut rng.fork(2)),
    ];
    let boxes = originals.each_ref().map(mesh::bounds);
    for (name, root) in ORIGINALS.iter().zip(originals) {
        scene.originals.push(Original {
            name: name.to_string(),
            root,
        });
    }

    let request = Request {
        room: size,
        counts: [a.chairs, a.tables, a.orchids, a.plants],
        boxes,
    };
    let items = room_layout::arrange(&request, &mut rng.fork(3))?;
    scene.root = Cluster {
        name: Some("dining_room".into()),
        children: vec![
            room_shell::shell(size, m.shell),
            furniture_tree(&items, a.tables),
        ],
        ..Cluster::default()
    };
    scene.cameras = vec![
        Camera {
            name: Some("entrance".into()),
            position: Vec3::new(size.x * 0.76, 0.3, (size.z - 0.8).min(2.2)),
            target: Vec3::new(size.x * 0.37, size.y * 0.67, 0.2),
            up: Vec3::Z,
            fovy_deg: 62.0,
        },
        Camera {
            name: Some("side".into()),
            position: Vec3::new(0.3, size.y * 0.5, 1.7),
            target: Vec3::new(size.x * 0.75, size.y * 0.46, 0.5),
            up: Vec3::Z,
            fovy_deg: 60.0,
        },
    ];
    Ok(scene)
}
