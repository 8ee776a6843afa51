//! Tests of the tree generators: `gen poplar`, `gen stand`, `gen forest` (structure, counts,
//! attributes, lights, and a solve of a small tree).

use crate::generate::Common;
use crate::generate::forest;
use crate::generate::poplar::{self, Preset};
use crate::generate::stand;
use crate::generate::tree::site::bounds;
use crate::generate::tree::{Bands, SHOOT, Species, TRUNK};
use crate::scene::{Cluster, ExpandVisitor, ExpandedNode, Scene, compile, expand, read_image};
use hirad_core::image::SceneInfo;
use std::path::PathBuf;

fn common(seed: u64) -> Common {
    Common {
        seed,
        output: PathBuf::from("unused.hirb"),
        quiet: true,
    }
}

fn poplar_args(seed: u64, preset: Preset) -> poplar::Args {
    poplar::Args {
        common: common(seed),
        preset,
        age: None,
        height: None,
        leaves: None,
        bands: Bands::ParNir,
        sun_elevation: 55.0,
        sun_azimuth: -120.0,
    }
}

fn stand_args(seed: u64, preset: stand::Preset) -> stand::Args {
    stand::Args {
        common: common(seed),
        preset,
        ages: None,
        counts: None,
        trees: None,
        spacing: 7.0,
        bulbs: None,
        bulb_polygons: 1000,
        bulb_radius: 0.5,
        bulb_irradiance: 10.0,
        bands: Bands::ParNir,
    }
}

fn forest_args(seed: u64, trees: u32) -> forest::Args {
    forest::Args {
        common: common(seed),
        trees,
        size: None,
        relief: None,
        cells: None,
        ages: vec![25.0, 30.0, 35.0],
        variants: 3,
        detail: 2.1,
        bands: Bands::ParNir,
        sun_elevation: 50.0,
        sun_azimuth: -120.0,
    }
}

/// The binary image and what it says about itself.
fn image(s: &Scene) -> (Vec<u8>, SceneInfo) {
    let bytes = compile(s).unwrap();
    let info = *read_image(&bytes).unwrap().info();
    (bytes, info)
}

/// Per instancing level of the stored scene tree (0 = the scene, 1 = instances directly in
/// it, ...): instances at that level, their own polygons and their child instances.
#[derive(Clone, Copy, Debug, Default)]
struct Level {
    nodes: u64,
    own: u64,
    instances: u64,
}

fn levels(c: &Cluster, level: usize, out: &mut Vec<Level>) {
    if out.len() <= level {
        out.resize(level + 1, Level::default());
    }
    let (mut own, mut inst) = (0, 0);
    // Plain sub-clusters belong to the same level.
    let mut stack: Vec<&Cluster> = vec![c];
    while let Some(n) = stack.pop() {
        own += n.polygons.len() as u64;
        for k in &n.children {
            if k.instance.is_some() {
                inst += 1;
                levels(k, level + 1, out);
            } else {
                stack.push(k);
            }
        }
    }
    out[level].nodes += 1;
    out[level].own += own;
    out[level].instances += inst;
}

/// Every node of a tree with its parent's kind and age.
fn walk<'a>(
    c: &'a Cluster,
    parent: Option<&'a Cluster>,
    f: &mut impl FnMut(&Cluster, Option<&Cluster>),
) {
    f(c, parent);
    for k in &c.children {
        walk(k, Some(c), f);
    }
}

fn find<'a>(c: &'a Cluster, name: &str) -> &'a Cluster {
    c.children
        .iter()
        .find(|k| k.name.as_deref() == Some(name))
        .unwrap()
}

#[test]
fn poplar_is_deterministic_per_seed() {
    let a = image(&poplar::generate(&poplar_args(7, Preset::Young)).unwrap()).0;
    let b = image(&poplar::generate(&poplar_args(7, Preset::Young)).unwrap()).0;
    let c = image(&poplar::generate(&poplar_args(8, Preset::Young)).unwrap()).0;
    assert_eq!(a, b);
    assert_ne!(a, c);
}

#[test]
fn paper_poplar_matches_the_paper() {
    let s = poplar::generate(&poplar_args(1, Preset::Paper)).unwrap();
    s.check().unwrap();
    let (_, info) = image(&s);
    // n = 119,000 polygons, k = 4 instancing levels, r = 5 originals.
    let n = info.expanded_polygons as f64;
    assert!((n / 119_000.0 - 1.0).abs() < 0.05, "{n} polygons");
    assert_eq!(info.instancing_depth, 4);
    assert_eq!(info.originals, 5);
    assert_eq!(info.exact_instances, 0);
    // N ~ 30 elements per level of which p ~ 8 instances; the deepest level is leafy shoots
    // of ~30 polygons.
    let mut out = Vec::new();
    levels(&find(&s.root, "poplar").clone(), 0, &mut out);
    assert_eq!(out.len(), 5);
    for l in &out[1..4] {
        let (own, p) = (
            l.own as f64 / l.nodes as f64,
            l.instances as f64 / l.nodes as f64,
        );
        assert!((5.5..=10.5).contains(&p), "{out:?}");
        assert!((22.0..=38.0).contains(&(own + p)), "{out:?}");
    }
    let shoots = out[4];
    assert_eq!(shoots.instances, 0);
    assert!((20.0..=34.0).contains(&(shoots.own as f64 / shoots.nodes as f64)));
    assert!(!s.cameras.is_empty() && !s.suns.is_empty() && !s.sky.is_empty());
    assert_eq!(s.band_names, ["par", "nir"]);
}

#[test]
fn axes_carry_kind_and_age_and_instances_their_class() {
    let s = poplar::generate(&poplar_args(3, Preset::Young)).unwrap();
    let species = Species::poplar();
    let tree = find(&s.root, "poplar");
    assert_eq!((tree.axis, tree.instance.is_none()), (Some(TRUNK), true));
    let mut checked = 0;
    walk(tree, None, &mut |c, parent| {
        let (kind, age) = (c.axis.unwrap(), c.age.unwrap());
        let Some(parent) = parent else { return };
        let (pk, pa) = (parent.axis.unwrap(), parent.age.unwrap());
        // A lateral is one order up, or a leafy shoot; never older than its parent.
        assert!(kind == pk + 1 || kind == SHOOT, "{pk} -> {kind}");
        assert!(age <= pa + 1e-6 || kind == SHOOT);
        let inst = c.instance.unwrap();
        assert!(!inst.exact);
        // The original is the one of the axis's class, and of the same kind.
        let class = species.class_of(kind, age).unwrap();
        assert_eq!(s.originals[inst.original].name, species.classes[class].name);
        assert_eq!(s.originals[inst.original].root.axis, Some(kind));
        checked += 1;
    });
    assert!(checked > 50, "{checked}");
    // Older order-1 branches reuse the original of a medium age.
    let medium = &s.originals[s.original_index("branch1-medium").unwrap()].root;
    assert!(medium.age.unwrap() < 15.0);
}

#[test]
fn approximate_instances_carry_their_own_geometry_in_the_original_frame() {
    let s = poplar::generate(&poplar_args(4, Preset::Young)).unwrap();
    let tree = find(&s.root, "poplar");
    let mut seen = 0;
    walk(tree, None, &mut |c, _| {
        let Some(inst) = c.instance else { return };
        assert!(!c.polygons.is_empty() && !c.vertices.is_empty());
        // Base at the local origin, and about the size of the original (scale is length
        // over the original's length): same height within the length variation.
        let own = bounds(c, &s.originals);
        let orig = bounds(&s.originals[inst.original].root, &s.originals);
        let ratio = own.max.z / orig.max.z;
        assert!((0.6..1.6).contains(&ratio), "{ratio}");
        assert!(own.min.z.abs() < 0.1 * own.max.z);
        assert!(inst.transform.scale > 0.0);
        seen += 1;
    });
    assert!(seen > 50);
}

#[test]
fn leaves_are_two_sided_and_translucent() {
    let s = poplar::generate(&poplar_args(1, Preset::Young)).unwrap();
    let leaf = s.material_index("leaf").unwrap();
    let m = &s.materials[leaf].data;
    assert!(m.two_sided);
    assert!(m.tau[0] > 0.0 && m.tau[1] > 0.0);
    assert!((m.rho_front[0] - 0.08).abs() < 1e-6 && (m.rho_front[1] - 0.45).abs() < 1e-6);
    let shoot = &s.originals[s.original_index("shoot").unwrap()].root;
    let leaves = shoot
        .polygons
        .iter()
        .filter(|p| p.material as usize == leaf)
        .count();
    assert!((15..=30).contains(&leaves), "{leaves}");
    // Bark is one-sided.
    assert!(
        !s.materials[s.material_index("bark").unwrap()]
            .data
            .two_sided
    );
}

#[test]
fn options_change_the_tree() {
    let mut a = poplar_args(1, Preset::Young);
    a.age = Some(12.0);
    a.bands = Bands::Rgb;
    a.height = Some(10.0);
    let s = poplar::generate(&a).unwrap();
    assert_eq!(s.bands, 3);
    let small = image(&poplar::generate(&poplar_args(1, Preset::Young)).unwrap()).1;
    assert!(image(&s).1.expanded_polygons > small.expanded_polygons);
    let top = bounds(find(&s.root, "poplar"), &s.originals).max.z;
    assert!((9.5..11.5).contains(&top), "{top}");
    a.age = Some(0.0);
    assert!(poplar::generate(&a).is_err());
    a.age = Some(f32::NAN);
    assert!(poplar::generate(&a).is_err());
}

#[test]
fn small_stand_is_exact_trees_and_bulbs() {
    let s = stand::generate(&stand_args(1, stand::Preset::Small)).unwrap();
    let (bytes, info) = image(&s);
    assert_eq!(
        bytes,
        image(&stand::generate(&stand_args(1, stand::Preset::Small)).unwrap()).0
    );
    // 5 branch originals + 2 tree originals + the bulb.
    assert_eq!(info.originals, 8);
    assert_eq!(info.instancing_depth, 5);
    let trees = find(&s.root, "trees");
    assert_eq!(trees.children.len(), 4);
    assert!(
        trees
            .children
            .iter()
            .all(|t| t.instance.unwrap().exact && t.axis == Some(TRUNK))
    );
    // The bulb: about 1,000 emitting polygons in 8 clusters.
    let bulb = &s.originals[s.original_index("bulb").unwrap()].root;
    assert_eq!(bulb.children.len(), 8);
    let n: usize = bulb.children.iter().map(|c| c.polygons.len()).sum();
    assert!((950..=1050).contains(&n), "{n}");
    let lamp = &s.materials[bulb.children[0].polygons[0].material as usize].data;
    assert!(lamp.emit_front[0] > 1000.0 && lamp.emit_front[1] > lamp.emit_front[0]);
    // Only bulbs light the stand, from above the ground.
    assert!(s.suns.is_empty() && s.sky.is_empty());
    let b = bounds(find(&s.root, "bulbs"), &s.originals);
    assert!(b.min.z > 2.0);
}

#[test]
fn paper_stand_has_the_papers_polygon_count() {
    let s = stand::generate(&stand_args(1, stand::Preset::Paper)).unwrap();
    let (_, info) = image(&s);
    let n = info.expanded_polygons as f64;
    assert!((n / 1_210_000.0 - 1.0).abs() < 0.05, "{n} polygons");
    assert_eq!(info.exact_instances, 24);
}

#[test]
fn forest_counts_scale_with_the_trees() {
    let count = |trees| {
        let mut a = forest_args(1, trees);
        a.cells = Some(8);
        a.size = Some(60.0);
        let s = forest::generate(&a).unwrap();
        image(&s).1.expanded_polygons - 128
    };
    let (few, many) = (count(4), count(16));
    let ratio = many as f64 / few as f64;
    assert!((2.5..6.0).contains(&ratio), "{few} -> {many}");
}

#[test]
fn a_thousand_tree_forest_is_a_billion_polygons_in_a_few_megabytes() {
    let s = forest::generate(&forest_args(1, 1000)).unwrap();
    let (bytes, info) = image(&s);
    let n = info.expanded_polygons as f64;
    assert!((5e8..2e9).contains(&n), "{n}");
    assert!(bytes.len() < 8 << 20, "{} bytes", bytes.len());
    assert_eq!(info.approximate_instances, 0);
    assert_eq!(
        bytes,
        image(&forest::generate(&forest_args(1, 1000)).unwrap()).0
    );
    assert_ne!(
        bytes,
        image(&forest::generate(&forest_args(2, 1000)).unwrap()).0
    );
}

#[test]
fn forest_trees_stand_on_the_terrain() {
    let mut a = forest_args(5, 30);
    a.relief = Some(6.0);
    let s = forest::generate(&a).unwrap();
    let terrain = find(&s.root, "terrain");
    // Heights of the terrain's vertices near each tree bound where its base may be.
    for t in &find(&s.root, "trees").children {
        let at = t.instance.unwrap().transform.translation;
        let near: Vec<f32> = terrain
            .children
            .iter()
            .flat_map(|b| b.vertices.iter())
            .filter(|v| (v.x - at.x).hypot(v.y - at.y) < 3.0)
            .map(|v| v.z)
            .collect();
        let (lo, hi) = near
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), &z| {
                (l.min(z), h.max(z))
            });
        assert!(at.z >= lo - 1e-3 && at.z <= hi + 1e-3, "{at} in {lo}..{hi}");
    }
}

/// Material of every polygon, in global-id order.
fn materials_by_id(s: &Scene) -> Vec<u32> {
    struct Collect(Vec<u32>);
    impl ExpandVisitor for Collect {
        type Error = std::convert::Infallible;
        fn node(&mut self, n: &ExpandedNode<'_>) -> Result<(), Self::Error> {
            self.0.extend(n.cluster.polygons.iter().map(|p| p.material));
            Ok(())
        }
    }
    let mut c = Collect(Vec::new());
    let _ = expand(s, &mut c);
    c.0
}

#[test]
fn a_small_poplar_solves_leaves_lit_ground_shaded() {
    use crate::output::{Progress, ResultsTable};
    use crate::solve::{VisibilityChoice, solve_hr};
    use hirad_core::hr::Settings;
    let mut a = poplar_args(1, Preset::Young);
    a.age = Some(6.0);
    let s = poplar::generate(&a).unwrap();
    let mut table = ResultsTable::new(2, true);
    let settings = Settings {
        epsilon: 5e-3,
        ..Settings::default()
    };
    solve_hr(
        &s,
        &settings,
        2,
        None,
        VisibilityChoice::Obvhs,
        &Progress::new(true),
        &mut table,
    )
    .unwrap();
    let mats = materials_by_id(&s);
    assert_eq!(table.len(), mats.len());
    let leaf = s.material_index("leaf").unwrap() as u32;
    let lit_leaves = (0..table.len())
        .filter(|&i| mats[i] == leaf)
        .filter(|&i| table.radiosity(i, 0)[0] > 0.0 || table.radiosity(i, 1)[0] > 0.0)
        .count();
    let leaves = mats.iter().filter(|&&m| m == leaf).count();
    assert!(lit_leaves * 10 >= leaves * 9, "{lit_leaves} of {leaves}");
    // The ground is the first 21 x 21 polygons; the trunk stands in the centre tile; the
    // first tile is the corner towards the sun, in the open.
    let under = table.radiosity(10 * 21 + 10, 0)[0];
    let open = table.radiosity(0, 0)[0];
    assert!(
        open > 0.0 && under < 0.9 * open,
        "under {under}, open {open}"
    );
}
