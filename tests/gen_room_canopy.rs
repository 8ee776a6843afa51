//! `hirad gen room` and `hirad gen canopy` end to end: deterministic and valid scenes, the
//! counts asked for, exact instances that do not overlap, walls that face in, two-sided
//! leaves, and a hierarchical solve that lights the room's floor and shades the soil under
//! a canopy.

use anyhow::Result;
use glam::Vec3;
use hirad::generate::canopy;
use hirad::generate::{mesh, room};
use hirad::output::Progress;
use hirad::scene::{Cluster, Scene, compile, read_image};
use hirad::solve::{HrRun, VisibilityChoice, solve_hr};
use hirad_core::geometry::{Aabb, Similarity, polygon_shape};
use hirad_core::hr::Settings;
use hirad_core::sink::{PolygonResult, Sink};
use std::path::Path;

/// Output path argument (generation never writes it).
const OUT: [&str; 2] = ["-o", "unused.hirb"];

fn room_scene(extra: &[&str]) -> Scene {
    let words: Vec<&str> = OUT.iter().chain(extra).copied().collect();
    room::generate(&room::Args::from_words(words).unwrap()).unwrap()
}

fn canopy_scene(extra: &[&str]) -> Scene {
    let words: Vec<&str> = OUT.iter().chain(extra).copied().collect();
    canopy::generate(&canopy::Args::from_words(words).unwrap()).unwrap()
}

/// The .hirb bytes `hirad gen` writes for `scene`.
fn hirb(scene: &Scene, dir: &Path, name: &str) -> Vec<u8> {
    let path = dir.join(name);
    hirad::generate::write(scene, &path).unwrap();
    std::fs::read(path).unwrap()
}

/// Every instance node of a tree, with its transform to the tree's root frame.
fn instances<'a>(c: &'a Cluster, to_root: Similarity, out: &mut Vec<(&'a Cluster, Similarity)>) {
    let here = match &c.instance {
        Some(i) => to_root.compose(&i.transform),
        None => to_root,
    };
    if c.instance.is_some() {
        out.push((c, here));
    }
    for ch in &c.children {
        instances(ch, here, out);
    }
}

/// Corners of a polygon of `c` in `c`'s frame.
fn corners(c: &Cluster, k: usize) -> Vec<Vec3> {
    let p = &c.polygons[k];
    p.corners[..p.corner_count()]
        .iter()
        .map(|&i| c.vertices[i as usize])
        .collect()
}

/// The child of `c` called `name`.
fn child<'a>(c: &'a Cluster, name: &str) -> &'a Cluster {
    c.children
        .iter()
        .find(|k| k.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no cluster '{name}'"))
}

/// Front radiosity of every polygon, by global id.
#[derive(Default)]
struct Radiosity(Vec<Vec<f32>>);

impl Sink for Radiosity {
    type Error = anyhow::Error;
    fn polygon(&mut self, p: &PolygonResult<'_>) -> Result<()> {
        let id = p.id as usize;
        if self.0.len() <= id {
            self.0.resize(id + 1, Vec::new());
        }
        self.0[id] = p.radiosity[0].to_vec();
        Ok(())
    }
}

fn solve(scene: &Scene, epsilon: f32) -> Radiosity {
    let settings = Settings {
        epsilon,
        ..Settings::default()
    };
    solve_with(scene, &settings).0
}

/// hr on 2 threads with obvhs: every polygon's front radiosity, and the run.
fn solve_with(scene: &Scene, settings: &Settings) -> (Radiosity, HrRun) {
    let mut out = Radiosity::default();
    let run = solve_hr(
        scene,
        settings,
        2,
        None,
        VisibilityChoice::Obvhs,
        &Progress::new(true),
        &mut out,
    )
    .unwrap();
    (out, run)
}

#[test]
fn room_is_deterministic_valid_and_has_the_papers_counts() {
    let dir = tempfile::tempdir().unwrap();
    let a = room_scene(&[]);
    let b = room_scene(&[]);
    a.check().unwrap();
    assert_eq!(
        hirb(&a, dir.path(), "a.hirb"),
        hirb(&b, dir.path(), "b.hirb")
    );
    let other = room_scene(&["--seed", "2"]);
    assert_ne!(compile(&a).unwrap(), compile(&other).unwrap());

    let image = compile(&a).unwrap();
    let info = *read_image(&image).unwrap().info();
    let n = info.expanded_polygons as f64;
    assert!((n - 55_000.0).abs() <= 0.05 * 55_000.0, "{n} polygons");
    assert_eq!(info.originals, 4);
    assert_eq!((info.exact_instances, info.approximate_instances), (34, 0));
    assert_eq!(info.instancing_depth, 1);
    assert_eq!(a.band_names, ["red", "green", "blue"]);
    assert!(!a.cameras.is_empty());
    assert!(a.materials.iter().any(|m| m.data.emit_front[0] > 0.0));

    let mut found = Vec::new();
    instances(&a.root, Similarity::IDENTITY, &mut found);
    let mut per_original = [0; 4];
    for (c, _) in &found {
        let i = c.instance.unwrap();
        assert!(i.exact);
        assert!(c.vertices.is_empty() && c.polygons.is_empty() && c.children.is_empty());
        per_original[i.original] += 1;
    }
    assert_eq!(per_original, [24, 3, 3, 4]);
    assert_eq!(
        a.originals
            .iter()
            .map(|o| o.name.as_str())
            .collect::<Vec<_>>(),
        room::ORIGINALS
    );
    // Originals open level by level: parts are sub-clusters.
    for o in &a.originals {
        assert!(
            o.root.children.len() >= 2 && o.root.polygons.is_empty(),
            "{}",
            o.name
        );
    }
}

#[test]
fn room_walls_face_in_and_furniture_does_not_overlap() {
    let s = room_scene(&[]);
    let shell = child(&s.root, "room");
    let size = Vec3::new(10.8, 7.8, 3.0);
    for part in ["floor", "ceiling", "walls", "lights"] {
        let c = child(shell, part);
        assert!(!c.polygons.is_empty());
        for k in 0..c.polygons.len() {
            let p = corners(c, k);
            let n = polygon_shape(&p).unwrap().normal;
            for inside in [
                size * 0.5,
                Vec3::new(0.3, 0.4, 0.2),
                size - Vec3::splat(0.3),
            ] {
                assert!(n.dot(inside - p[0]) > 0.0, "{part} polygon {k} faces out");
            }
        }
    }

    let boxes: Vec<Aabb> = s.originals.iter().map(|o| mesh::bounds(&o.root)).collect();
    let mut found = Vec::new();
    instances(&s.root, Similarity::IDENTITY, &mut found);
    let world: Vec<Aabb> = found
        .iter()
        .map(|(c, t)| t.aabb(&boxes[c.instance.unwrap().original]))
        .collect();
    // Boxes of turned objects are rounded outwards a little: allow 0.1 mm below the floor.
    let room = Aabb::new(Vec3::new(0.0, 0.0, -1e-4), size);
    for (i, a) in world.iter().enumerate() {
        assert!(room.contains(a), "{:?} leaves the room", found[i].0.name);
        for (j, b) in world[..i].iter().enumerate() {
            let meet = a.min.cmplt(b.max).all() && b.min.cmplt(a.max).all();
            assert!(
                !meet,
                "{:?} and {:?} overlap",
                found[i].0.name, found[j].0.name
            );
        }
    }
}

#[test]
fn room_options_change_the_counts() {
    let s = room_scene(&[
        "--chairs",
        "10",
        "--tables",
        "1",
        "--orchids",
        "2",
        "--plants",
        "5",
    ]);
    s.check().unwrap();
    let mut found = Vec::new();
    instances(&s.root, Similarity::IDENTITY, &mut found);
    let mut per_original = [0; 4];
    for (c, _) in &found {
        per_original[c.instance.unwrap().original] += 1;
    }
    assert_eq!(per_original, [10, 1, 2, 5]);
    assert!(room::Args::from_words(["--chairs", "-1"]).is_err());
    let crowded = room::Args::from_words(["-o", "x.hirb", "--chairs", "500"]).unwrap();
    assert!(room::generate(&crowded).is_err());
}

#[test]
fn room_solve_lights_every_floor_tile() {
    let s = room_scene(&[]);
    let r = solve(&s, 1e-2);
    // The floor is the first cluster of the expansion: its polygons have the first ids.
    let floor = child(child(&s.root, "room"), "floor").polygons.len();
    assert!(floor > 100);
    for (id, rad) in r.0[..floor].iter().enumerate() {
        assert!(rad.iter().all(|&v| v > 0.0), "floor polygon {id}: {rad:?}");
    }
}

#[test]
fn room_at_the_default_epsilon_converges_and_keeps_its_light() {
    // 55,000 polygons of furniture standing on a floor and against walls, lit by ceiling
    // panels: the solution must converge (one version diverged here: clusters that straddle
    // an emitter's plane got its light on both sides) and lose little light. Measured: 9.5%
    // of the red band lost through cluster links (20% before the fix of receiving clusters'
    // samples). With the final gather's automatic passes and the rays of large polygons
    // (2026-12-03): red +0.16%, green -0.20%, blue -0.37% (before: +0.44%, -0.29%, -0.81%).
    let s = room_scene(&[]);
    let (out, run) = solve_with(&s, &Settings::default());
    assert!(
        run.stats.converged && !run.stats.diverged,
        "{:?}",
        run.stats
    );
    for b in 0..s.bands as usize {
        let e = run.stats.balance.relative_imbalance(b);
        assert!(e.abs() < 0.01, "band {b}: imbalance {:+.2}%", 100.0 * e);
    }
    assert!(out.0.iter().flatten().all(|v| v.is_finite()));
}

#[test]
fn a_white_room_settles() {
    // Every surface of the furnished room at reflectance 0.8 (and 0.5): a linear operator
    // whose largest gain is below 1 converges geometrically. One version fitted its
    // clusters' emission to their power-weighted normals, which made the iteration depend
    // on the radiosities' own pattern: the 0.8 room was still moving by 1e-4 of its
    // brightest radiosity after 1,000 iterations (27 to 40 converge it).
    for rho in [0.8f32, 0.5] {
        let mut s = room_scene(&[]);
        for m in &mut s.materials {
            let d = &mut m.data;
            for b in 0..d.bands as usize {
                d.rho_front[b] = rho;
                if d.two_sided {
                    d.rho_back[b] = rho;
                    d.tau[b] = 0.0;
                }
            }
        }
        let settings = Settings {
            final_rays: 0,
            max_iterations: 200,
            ..Settings::default()
        };
        let (_, run) = solve_with(&s, &settings);
        assert!(
            run.stats.converged && !run.stats.diverged && run.stats.iterations < 120,
            "rho {rho}: converged {} after {} iterations (still to come {})",
            run.stats.converged,
            run.stats.iterations,
            run.stats.remaining_change
        );
    }
}

#[test]
fn canopy_is_deterministic_valid_and_as_asked() {
    let dir = tempfile::tempdir().unwrap();
    let a = canopy_scene(&[]);
    a.check().unwrap();
    assert_eq!(
        hirb(&a, dir.path(), "a.hirb"),
        hirb(&canopy_scene(&[]), dir.path(), "b.hirb")
    );
    assert_eq!(a.band_names, ["par", "nir"]);
    assert_eq!(a.suns.len(), 1);
    assert!(a.sky.len() > 20);
    assert!(!a.cameras.is_empty());
    let rows = &child(&a.root, "crop").children;
    assert_eq!(rows.len(), 24);
    assert!(rows.iter().all(|r| r.children.len() == 100));
    let info = *read_image(&compile(&a).unwrap()).unwrap().info();
    assert_eq!((info.originals, info.exact_instances), (5, 2400));
    assert!(
        info.expanded_polygons > 400_000,
        "{}",
        info.expanded_polygons
    );

    // Leaves are two-sided; leaf clusters (axis 1) hold only leaf polygons.
    let leaf = a.material_index("leaf").unwrap();
    assert!(a.materials[leaf].data.two_sided);
    assert_eq!(a.materials[leaf].data.tau[..2], [0.05, 0.45]);
    fn leaves_only(c: &Cluster, leaf: u32, count: &mut usize) {
        if c.axis == Some(1) {
            assert!(c.polygons.iter().all(|p| p.material == leaf));
            *count += c.polygons.len();
        }
        for ch in &c.children {
            leaves_only(ch, leaf, count);
        }
    }
    let mut count = 0;
    for o in &a.originals {
        leaves_only(&o.root, leaf as u32, &mut count);
    }
    assert!(count > 5 * 11 * 7);

    let w = canopy_scene(&["--crop", "wheat", "--rows", "3", "--plants-per-row", "7"]);
    w.check().unwrap();
    let rows = &child(&w.root, "crop").children;
    assert_eq!(rows.len(), 3);
    for (r, row) in rows.iter().enumerate() {
        assert_eq!(row.children.len(), 7);
        for p in &row.children {
            let i = p.instance.unwrap();
            assert!(i.exact);
            let y = i.transform.translation.y;
            assert!((y - 0.17 * r as f32).abs() < 0.03, "row {r} at {y}");
        }
    }
    assert!(
        w.materials[w.material_index("leaf").unwrap()]
            .data
            .two_sided
    );
}

#[test]
fn canopy_soil_is_darker_under_the_leaves_than_in_the_open() {
    let (rows, per_row, rs, ps) = (5, 12, 0.75, 0.2);
    let s = canopy_scene(&[
        "--rows",
        "5",
        "--plants-per-row",
        "12",
        "--variants",
        "3",
        "--sky-rings",
        "4",
    ]);
    let r = solve(&s, 1e-3);
    // The soil is the first cluster of the expansion: its tiles have the first ids.
    let soil = child(&s.root, "soil");
    let mut centres = Vec::new();
    for strip in &soil.children {
        for k in 0..strip.polygons.len() {
            let c = corners(strip, k);
            centres.push(c.iter().copied().sum::<Vec3>() / c.len() as f32);
        }
    }
    let (length, width) = ((per_row - 1) as f32 * ps, (rows - 1) as f32 * rs);
    let (mut under, mut open) = (Vec::new(), Vec::new());
    for (id, c) in centres.iter().enumerate() {
        let between_rows = ((c.y / rs).fract() - 0.5).abs() < 0.01;
        if between_rows && c.y > rs && c.y < width - rs && c.x > 0.5 && c.x < length - 0.5 {
            under.push(r.0[id][0]);
        }
        // The sun shines from -x, -y: soil beyond those edges is in the open.
        if c.x < -1.0 || c.y < -1.0 {
            open.push(r.0[id][0]);
        }
    }
    assert!(
        under.len() >= 4 && open.len() >= 20,
        "{} {}",
        under.len(),
        open.len()
    );
    let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len() as f32;
    let (u, o) = (mean(&under), mean(&open));
    assert!(
        u < 0.8 * o,
        "soil under the canopy {u} W/m^2, in the open {o} W/m^2"
    );
}

/// Radiosity and area of every polygon, by id.
#[derive(Default)]
struct Lit(Vec<(f32, Vec<f32>)>);

impl Sink for Lit {
    type Error = anyhow::Error;
    fn polygon(&mut self, p: &PolygonResult<'_>) -> Result<()> {
        assert_eq!(p.id as usize, self.0.len());
        self.0.push((p.area, p.radiosity[0].to_vec()));
        Ok(())
    }
}

#[test]
fn a_room_is_lit_the_same_whichever_axis_is_up() {
    // A room with a potted palm and the skirting along its walls, as generated (z up) and
    // turned so that y, then -x, is up (as an OBJ of it is read). The generated one diverged:
    // a point of the skirting near the floor's edge, seen almost edge-on from the floor's
    // centre, had the floor cluster's kernel divided by its nearly empty shadow that way
    // (a link coefficient of 45; at most 1 is possible). The turned ones must agree with it
    // polygon by polygon: only rounding and the order of rays differ.
    let s = room_scene(&[
        "--chairs",
        "0",
        "--tables",
        "0",
        "--orchids",
        "0",
        "--plants",
        "1",
    ]);
    let lit = |scene: &Scene| {
        let mut out = Lit::default();
        let run = solve_hr(
            scene,
            &Settings::default(),
            2,
            None,
            VisibilityChoice::Obvhs,
            &Progress::new(true),
            &mut out,
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert!(run.stats.converged, "{:?}", run.stats);
        for b in 0..scene.bands as usize {
            let e = run.stats.balance.relative_imbalance(b);
            assert!(e.abs() < 0.06, "band {b}: imbalance {:+.2}%", 100.0 * e);
        }
        out.0
    };
    let upright = lit(&s);
    let largest = upright
        .iter()
        .flat_map(|(_, r)| r.iter().copied())
        .fold(0.0f32, f32::max);
    assert!(largest.is_finite() && largest > 0.0);
    for up in ["y", "-x"] {
        let mut turned = s.clone();
        // The scene's z becomes `up`: the inverse of the quarter turn from `up` to z is that
        // turn three times.
        let up = hirad::scene::Up::parse(up).unwrap();
        for _ in 0..3 {
            up.rotate_scene_to_z_up(&mut turned);
        }
        let other = lit(&turned);
        assert_eq!(other.len(), upright.len());
        let (mut num, mut den) = (0.0f64, 0.0f64);
        for (id, ((area, a), (_, b))) in upright.iter().zip(&other).enumerate() {
            for (band, (&x, &y)) in a.iter().zip(b).enumerate() {
                assert!(
                    y.is_finite(),
                    "up {}: polygon {id} band {band}: {y}",
                    up.name()
                );
                num += f64::from(*area) * f64::from(x - y).powi(2);
                den += f64::from(*area) * f64::from(x).powi(2);
                // Faces with a tenth of the largest radiosity or more, within the gather's
                // noise (measured: at most 4.3% over six orientations).
                if x > 0.1 * largest {
                    assert!(
                        (y - x).abs() <= 0.1 * x,
                        "up {}: polygon {id} band {band}: {y} against {x}",
                        up.name()
                    );
                }
            }
        }
        let l2 = (num / den).sqrt();
        // Measured: 0.02% to 0.17%.
        assert!(l2 < 0.01, "up {}: L2 {:.3}%", up.name(), 100.0 * l2);
    }
}

#[test]
fn furnished_rooms_keep_their_light_with_the_hierarchy_alone() {
    // Coarse links into and out of the furniture lost light: the default room 4.5% of its
    // red (3.0% of green, 1.6% of blue) before shots from small emitters, bounded draws,
    // gathered large clusters and merged light that keeps its power. Rooms of other sizes,
    // seeds and furniture counts; measured on 2026-12-03 (red, the worst band): default
    // +1.18%, seed 2 +0.82%, small -1.84% (made), large +2.01%.
    for extra in [&[][..], &["--seed", "2"][..], SMALL_ROOM, LARGE_ROOM] {
        let s = room_scene(extra);
        let settings = Settings {
            final_rays: 0,
            ..Settings::default()
        };
        let (_, run) = solve_with(&s, &settings);
        assert_balanced(&s, &run, 0.025, &format!("{extra:?}"));
    }
}

/// A small room (6 x 5 m, 8 chairs) and a large, crowded one (40 chairs, 4 m high).
const SMALL_ROOM: &[&str] = &[
    "--chairs",
    "8",
    "--tables",
    "1",
    "--orchids",
    "1",
    "--plants",
    "1",
    "--length",
    "6",
    "--width",
    "5",
];
const LARGE_ROOM: &[&str] = &[
    "--chairs", "40", "--tables", "5", "--height", "4", "--seed", "3",
];

/// Every band of `run` (a solve of `s`) within `limit` (a fraction of what enters) of the
/// power balance.
fn assert_balanced(s: &Scene, run: &HrRun, limit: f64, what: &str) {
    for b in 0..s.band_names.len() {
        let imbalance = run.stats.balance.relative_imbalance(b);
        assert!(
            imbalance.abs() < limit,
            "{what}, band {b}: imbalance {:+.2}%",
            100.0 * imbalance
        );
    }
}

#[test]
fn the_final_gathers_passes_keep_a_canopys_light_at_any_ray_count() {
    // Each pass of the gather took its ray counts from the previous pass's own estimate: a
    // leaf side whose few rays all escaped got none in the next pass and kept its zero.
    // Measured on 2026-12-03 (NIR, + lost), before -> after: 2 x 3 canopy +1.14 -> -0.31%
    // (4 rays, 2 passes), +1.49 -> -0.05% (9, 3), +1.15 -> -0.07% (16, 2), +1.30 -> -0.08%
    // (16, 4), +1.01 -> -0.31% (36, 3); 3 x 2 canopy of seed 2 +0.94 -> -0.30% (16, 2),
    // +0.86 -> -0.33% (36, 3). At 4 rays the small canopies' balance is noisy (seed 2:
    // -0.76% after), so the other canopy is held from 16 rays up.
    // (generator words, (rays per side, passes) to run)
    type Case<'a> = (&'a [&'a str], &'a [(u32, u32)]);
    let cases: [Case; 2] = [
        (
            &["--rows", "2", "--plants-per-row", "3"],
            &[(4, 2), (9, 3), (16, 2), (16, 4), (36, 3)],
        ),
        (
            &["--rows", "3", "--plants-per-row", "2", "--seed", "2"],
            &[(16, 2), (36, 3)],
        ),
    ];
    for (extra, runs) in cases {
        let s = canopy_scene(extra);
        for &(rays, passes) in runs {
            let settings = Settings {
                final_rays: rays,
                final_passes: passes,
                ..Settings::default()
            };
            let (_, run) = solve_with(&s, &settings);
            let what = format!("{extra:?}, {rays} rays, {passes} passes");
            assert_balanced(&s, &run, 0.005, &what);
        }
    }
}

#[test]
fn more_gather_passes_bring_a_room_nearer_its_balance() {
    // Every relighting pass cast the same rays, so the passes iterated one sampled transport
    // towards its fixed point, whose inverse turns the samples' errors into light no lamp
    // sent. Measured on 2026-12-03, the small room below at 16 rays per side (red, - made):
    // 1 pass -1.37%, 2 passes -2.04%, 4 passes -3.17% with the same samples in every pass;
    // 4 passes +0.06% (green +0.44%, blue +0.78%) with each pass's own.
    let s = room_scene(SMALL_ROOM);
    let settings = Settings {
        final_rays: 16,
        final_passes: 4,
        ..Settings::default()
    };
    let (_, four) = solve_with(&s, &settings);
    assert_eq!(four.stats.final_passes, 4);
    assert_balanced(&s, &four, 0.01, "small room, 16 rays, 4 passes");
}

#[test]
fn rooms_of_any_size_keep_their_light_at_the_defaults() {
    // At the defaults (64 rays per side in a room), every side cast the same rays, so the
    // few walls and floor, far larger than the chairs' polygons, set the noise of the
    // room's power: the passes of the gather moved the small room's light by 1% to 3%
    // apiece without settling (8 passes: -0.70% red). Now a large polygon casts more rays
    // (as the square root of its area over the typical polygon's, at most 16 times) and the
    // passes go on (at most 4) until one moves the light by less than 0.5% of what enters.
    // Measured on 2026-12-03 (red, green, blue; + lost), before (2 passes, the same rays
    // for every side) and after: small -1.95/-1.65/-1.34% -> -0.32/-0.27/-0.32% (4 passes);
    // large, with the automatic passes, without and with the large polygons' rays:
    // +0.10/-0.13/-0.42% -> +0.20/-0.18/-0.48%.
    // The default room is held in `room_at_the_default_epsilon_converges_and_keeps_its_light`.
    for extra in [SMALL_ROOM, LARGE_ROOM] {
        let s = room_scene(extra);
        let (_, run) = solve_with(&s, &Settings::default());
        assert!((2..=4).contains(&run.stats.final_passes), "{:?}", run.stats);
        assert_balanced(&s, &run, 0.01, &format!("{extra:?}"));
    }
}
