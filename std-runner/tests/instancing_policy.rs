//! `--instancing`: originals expanded in place in their parent's level (the paper's skipped
//! levels) instead of closed. On the small plant (5 approximate branches of 4 approximate
//! twigs), every choice of originals to expand hands out every polygon once, in global-id
//! order, solves as many levels as it leaves closed instances (plus the top), and agrees
//! with hr as the all-closed solve does; `every:N` and `auto` from the command line; a
//! policy that would close an emitting original is refused, `auto` expands it and originals
//! too small for a level of their own, and `hirad tables` makes no tables for either.

mod common;

use common::{COARSE_TABLES, fails_with, fixture, hirad, s};
use hirad::output::ResultsTable;
use hirad::solve::RayonExecutor;
use hirad_core::hr::{Inline, NoProgress, Settings, Stats};
use hirad_core::image::{SceneView, SliceSource};

/// The plant with coarse tables of both originals (twig 0, branch 1), as an image.
fn plant_image(dir: &std::path::Path) -> Vec<u8> {
    let image = dir.join("plant.hirb");
    let plant = fixture("small_plant.hir");
    let mut args = vec![
        "tables",
        s(&plant),
        "-o",
        s(&image),
        "--instancing",
        "all",
        "--no-cache",
        "-q",
    ];
    args.extend(COARSE_TABLES);
    let out = hirad(&args);
    // Coarse tables miss their targets (exit 1) and are written all the same.
    assert!(image.exists(), "{}", String::from_utf8_lossy(&out.stderr));
    std::fs::read(&image).unwrap()
}

/// Absorbed power per polygon (W, both sides, per band) of a results table.
fn absorbed(t: &ResultsTable) -> Vec<[f64; 2]> {
    (0..t.len())
        .map(|p| {
            let mut a = [0.0f64; 2];
            for side in 0..2 {
                let (e, b) = (t.irradiance(p, side), t.radiosity(p, side));
                for (k, v) in a.iter_mut().enumerate() {
                    *v += t.areas[p] as f64
                        * (e.get(k).copied().unwrap_or(0.0) - b.get(k).copied().unwrap_or(0.0))
                            as f64;
                }
            }
            a
        })
        .collect()
}

#[test]
fn originals_expanded_in_place_solve_as_the_closed_ones_do() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = plant_image(dir.path());
    let view = SceneView::open(SliceSource(&bytes[..])).unwrap();
    let settings = Settings::default();
    let mut ws = vec![0u8; 64 << 20];
    let mut exec = RayonExecutor::new(2).unwrap();
    let mut hr = ResultsTable::new(2, true);
    hirad_core::hr::solve(
        &view,
        &settings,
        &mut ws,
        None::<&hirad_core::visibility::Unoccluded>,
        &mut exec,
        &mut NoProgress,
        &mut hr,
    )
    .unwrap();
    let want = absorbed(&hr);
    let total = |a: &[[f64; 2]], b: usize| a.iter().map(|x| x[b]).sum::<f64>();
    // (bits: twig 1, branch 2; levels solved, deepest level, closed instances)
    for (bits, levels, deepest, closed) in [
        (0b00u8, 26u64, 2u32, 25u64),
        (0b01, 6, 1, 5),
        (0b10, 21, 1, 20),
        (0b11, 1, 0, 0),
    ] {
        let mut hi = ResultsTable::new(2, true);
        let stats: Stats = hirad_core::hr::solve_hi(
            &view,
            &settings,
            Inline::new(&[bits]),
            &mut ws,
            &mut exec,
            &mut NoProgress,
            &mut hi,
        )
        .unwrap();
        let case = format!("expanded in place {bits:02b}");
        assert_eq!(hi.ids, (0..105).collect::<Vec<u64>>(), "{case}");
        assert_eq!(
            (stats.levels, stats.level_depth, stats.closed_instances),
            (levels, deepest, closed),
            "{case}"
        );
        let got = absorbed(&hi);
        for b in 0..2 {
            let (g, w) = (total(&got, b), total(&want, b));
            assert!((g / w - 1.0).abs() < 0.02, "{case} band {b}: {g} vs {w}");
        }
        // Per polygon, on the polygons that absorb a share worth comparing.
        let big = total(&want, 1) / 105.0 * 0.1;
        let mut errs: Vec<f64> = (0..105)
            .filter(|&p| want[p][1] > big)
            .map(|p| (got[p][1] / want[p][1] - 1.0).abs())
            .collect();
        errs.sort_by(f64::total_cmp);
        let median = errs[errs.len() / 2];
        let p90 = errs[errs.len() * 9 / 10];
        let worst = errs[errs.len() - 1];
        let imbalance = stats.balance.relative_imbalance(1);
        eprintln!(
            "{case}: NIR per polygon median {median:.4} p90 {p90:.4} worst {worst:.4}; balance {imbalance:.5}"
        );
        assert!(
            median < 0.03 && p90 < 0.12,
            "{case}: median {median} p90 {p90}"
        );
        if bits == 0b11 {
            // Nothing closed: one level, the whole scene, solved as hr solves it.
            assert!(hi == hr, "{case}: not hr's results");
        }
    }
}

#[test]
fn every_n_and_auto_from_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = plant_image(dir.path());
    let image = dir.path().join("plant_tables.hirb");
    std::fs::write(&image, &bytes).unwrap();
    let run = |policy: &str, stats: &std::path::Path| {
        let out = hirad(&[
            "solve",
            s(&image),
            "--method",
            "hi",
            "--instancing",
            policy,
            "--stats",
            s(stats),
        ]);
        assert!(
            out.status.success(),
            "{policy}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(stats).unwrap()).unwrap();
        (String::from_utf8_lossy(&out.stderr).to_string(), v)
    };
    // every:2: the branches closed, the twigs (depth 2) expanded in the branches' levels.
    let (err, v) = run("every:2", &dir.path().join("every2.json"));
    assert!(
        err.contains("twig: expanded in place") && err.contains("branch: closed"),
        "{err}"
    );
    assert_eq!(v["settings"]["instancing"], "every:2", "{v}");
    assert_eq!(v["levels"]["solved"], 6, "{v}");
    assert_eq!(v["levels"]["closed_instances"], 5, "{v}");
    // auto: the twig (4 polygons) and the branch (20), tables or not, are cheaper in place
    // than as levels of their own: one level, hr's.
    let (err, v) = run("auto", &dir.path().join("auto.json"));
    for name in ["twig: expanded in place", "branch: expanded in place"] {
        assert!(err.contains(name), "{err}");
    }
    assert!(err.contains("(fewer than 64)"), "{err}");
    assert_eq!(v["levels"]["solved"], 1, "{v}");
    assert_eq!(v["levels"]["closed_instances"], 0, "{v}");
    let bad = fails_with(
        2,
        &[
            "solve",
            s(&image),
            "--method",
            "hi",
            "--instancing",
            "every:0",
        ],
    );
    assert!(bad.contains("every:N"), "{bad}");
}

#[test]
fn expand_opens_named_originals_in_their_parents_level() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = plant_image(dir.path());
    let image = dir.path().join("plant_tables.hirb");
    std::fs::write(&image, &bytes).unwrap();
    let run = |policy: &str, extra: &[&str], name: &str| {
        let stats = dir.path().join(format!("{name}.json"));
        let results = dir.path().join(format!("{name}.csv"));
        let mut args = vec![
            "solve",
            s(&image),
            "--method",
            "hi",
            "--instancing",
            policy,
            "--stats",
            s(&stats),
            "--results",
            s(&results),
        ];
        args.extend_from_slice(extra);
        let out = hirad(&args);
        assert!(
            out.status.success(),
            "{extra:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
        (
            String::from_utf8_lossy(&out.stderr).to_string(),
            v,
            std::fs::read(&results).unwrap(),
        )
    };
    // `all` with the twigs named: the same as every:2 (branches closed, twigs in them).
    let (err, v, named) = run("all", &["--expand", "twig"], "named");
    assert!(
        err.contains("twig: expanded in place") && err.contains("--expand names it"),
        "{err}"
    );
    assert!(err.contains("branch: closed"), "{err}");
    assert_eq!(v["levels"]["solved"], 6, "{v}");
    assert_eq!(v["levels"]["closed_instances"], 5, "{v}");
    let (_, _, every2) = run("every:2", &[], "every2");
    assert!(named == every2, "--expand twig and every:2 differ");
    // Both named (repeated or by commas): one level, hr's.
    for extra in [
        &["--expand", "twig,branch"][..],
        &["--expand", "branch", "--expand", "twig"][..],
    ] {
        let (_, v, _) = run("all", extra, "both");
        assert_eq!(v["levels"]["solved"], 1, "{extra:?}: {v}");
        assert_eq!(v["levels"]["closed_instances"], 0, "{extra:?}: {v}");
    }
    // A name the scene does not have: a usage error that lists those it has.
    let bad = fails_with(
        2,
        &["solve", s(&image), "--method", "hi", "--expand", "trunk"],
    );
    assert!(
        bad.contains("--expand trunk") && bad.contains("twig, branch"),
        "{bad}"
    );
}

/// Faces of a box of `side` m standing on the origin, outwards, each cut into n x n quads.
fn box_quads(t: &mut String, material: &str, side: f64, n: usize) {
    let h = side / 2.0;
    let c = [
        [-h, -h, 0.0],
        [h, -h, 0.0],
        [h, h, 0.0],
        [-h, h, 0.0],
        [-h, -h, side],
        [h, -h, side],
        [h, h, side],
        [-h, h, side],
    ];
    let mut v = 0;
    for q in [
        [0, 3, 2, 1],
        [4, 5, 6, 7],
        [0, 1, 5, 4],
        [1, 2, 6, 5],
        [2, 3, 7, 6],
        [3, 0, 4, 7],
    ] {
        let (a, b, d) = (c[q[0]], c[q[1]], c[q[3]]);
        for j in 0..=n {
            for i in 0..=n {
                let (u, w) = (i as f64 / n as f64, j as f64 / n as f64);
                let p: Vec<f64> = (0..3)
                    .map(|k| a[k] + (b[k] - a[k]) * u + (d[k] - a[k]) * w)
                    .collect();
                t.push_str(&format!("  v {} {} {}\n", p[0], p[1], p[2]));
            }
        }
        let at = |i: usize, j: usize| v + j * (n + 1) + i;
        for j in 0..n {
            for i in 0..n {
                t.push_str(&format!(
                    "  quad {material} {} {} {} {}\n",
                    at(i, j),
                    at(i + 1, j),
                    at(i + 1, j + 1),
                    at(i, j + 1)
                ));
            }
        }
        v += (n + 1) * (n + 1);
    }
}

/// A floor under two instanced lamps (an emitting original), four instanced crates (96
/// polygons each) and two bricks (6).
fn lamp_room() -> String {
    let mut t = String::from(
        "hirad 1\nbands grey\nmaterial white rho 0.6\nmaterial bulb rho 0.5 emit 300\n\
         original lamp {\n  v -0.15 -0.15 0\n  v -0.15 0.15 0\n  v 0.15 0.15 0\n  v 0.15 -0.15 0\n  quad bulb 0 1 2 3\n}\n\
         original crate {\n",
    );
    box_quads(&mut t, "white", 0.4, 4);
    t.push_str("}\noriginal brick {\n");
    box_quads(&mut t, "white", 0.1, 1);
    t.push_str("}\n");
    t.push_str("scene {\n  v -2 -2 0\n  v 2 -2 0\n  v 2 2 0\n  v -2 2 0\n  quad white 0 1 2 3\n");
    for (x, y) in [(-0.8, 0.0), (0.8, 0.0)] {
        t.push_str(&format!("  instance lamp exact translate {x} {y} 1.5\n"));
    }
    for (x, y) in [(-0.9, -0.9), (0.9, -0.9), (-0.9, 0.9), (0.9, 0.9)] {
        t.push_str(&format!("  instance crate exact translate {x} {y} 0\n"));
    }
    for x in [-0.3, 0.3] {
        t.push_str(&format!("  instance brick exact translate {x} 0.5 0\n"));
    }
    t.push_str("}\n");
    t
}

#[test]
fn an_emitting_original_is_expanded_in_place_never_closed() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("lamps.hir");
    std::fs::write(&scene, lamp_room()).unwrap();
    let cache = dir.path().join("cache");
    for policy in ["all", "every:1"] {
        let err = fails_with(
            2,
            &["solve", s(&scene), "--method", "hi", "--instancing", policy],
        );
        assert!(err.contains("'lamp', which emit light"), "{policy}: {err}");
    }
    // `hirad tables` makes the tables of what the policy closes: the crate's, not the lamp's.
    let made = dir.path().join("lamps.hirb");
    let mut args = vec!["tables", s(&scene), "-o", s(&made), "--no-cache"];
    args.extend(COARSE_TABLES);
    let out = hirad(&args);
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(made.exists(), "{stderr}");
    assert!(stderr.contains("lamp: expanded in place"), "{stderr}");
    assert!(stderr.contains("brick: expanded in place"), "{stderr}");
    assert!(
        stdout.contains("crate: 96 polygons") && !stdout.contains("lamp:"),
        "{stdout}"
    );
    assert!(!stdout.contains("brick:"), "{stdout}");
    let (hi, hr) = (dir.path().join("hi.csv"), dir.path().join("hr.csv"));
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_hirad"))
        .args([
            "solve",
            s(&scene),
            "--method",
            "hi",
            "--table-max-side",
            "8",
            "--results",
            s(&hi),
        ])
        .env("HIRAD_CACHE", &cache)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    // Coarse tables miss their targets: a warning, the solve goes on.
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("lamp: expanded in place") && err.contains("emits light"),
        "{err}"
    );
    assert!(err.contains("crate: closed"), "{err}");
    assert!(err.contains("brick: expanded in place"), "{err}");
    let out = hirad(&["solve", s(&scene), "--results", s(&hr), "-q"]);
    assert!(out.status.success());
    // The floor (id 0) and the lamps (ids 1, 2) against hr: the lamps' light is all there.
    let rows = |p: &std::path::Path| -> Vec<Vec<f64>> {
        std::fs::read_to_string(p)
            .unwrap()
            .lines()
            .skip(1)
            .map(|l| l.split(',').filter_map(|f| f.parse::<f64>().ok()).collect())
            .collect()
    };
    let (a, b) = (rows(&hi), rows(&hr));
    assert_eq!(a.len(), b.len());
    assert_eq!(a.len(), 3 + 4 * 96 + 2 * 6);
    // Columns: id, area, irradiance, radiosity (one band, one-sided).
    for p in 0..3 {
        let (g, w) = (a[p][2], b[p][2]);
        assert!(
            w > 0.0 && (g / w - 1.0).abs() < 0.03,
            "polygon {p}: {g} vs {w}"
        );
    }
    // A budget the floor under the lamps would fill alone at this epsilon (it failed to
    // open the crates before the levels left room for their children): every level
    // opened, refinement limited and said so, the floor and lamps as hr's.
    let tight = dir.path().join("tight.csv");
    let args = [
        "solve",
        s(&made),
        "--method",
        "hi",
        "--epsilon",
        "1e-4",
        "--memory",
        "1M",
        "--results",
        s(&tight),
    ];
    let out = hirad(&args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("budget limited refinement"), "{err}");
    let a = rows(&tight);
    assert_eq!(a.len(), b.len());
    for p in 0..3 {
        let (g, w) = (a[p][2], b[p][2]);
        assert!((g / w - 1.0).abs() < 0.03, "1M, polygon {p}: {g} vs {w}");
    }
    // Less than the top level and one path of levels need at their least: refused, with
    // at least the bytes it lacks, more than were given.
    let mut small = args;
    small[7] = "200K";
    let err = fails_with(2, &small);
    let needed: u64 = err
        .split("it needs ")
        .nth(1)
        .and_then(|t| t.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{err}"));
    assert!(needed > 200 * 1024, "{err}");
    // Warned before the solve started, with the least that surely opens every level.
    assert!(
        err.contains("warning: --memory 0.2 MiB is less than the"),
        "{err}"
    );
}

/// Without `--method`: hr on a scene without tables (with a note that hi could close some
/// of its instances), hi on one that carries the tables of an original `auto` closes; each
/// gives the results of the method named. A scene without instances says nothing of hi.
#[test]
fn the_default_method_is_hi_where_the_scene_carries_its_tables() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("lamps.hir");
    std::fs::write(&scene, lamp_room()).unwrap();
    let made = dir.path().join("lamps.hirb");
    let mut args = vec!["tables", s(&scene), "-o", s(&made), "--no-cache", "-q"];
    args.extend(COARSE_TABLES);
    hirad(&args);
    assert!(made.exists());
    // (method in the stats, stderr, results table) of a solve of `scene` with `extra`.
    let solve = |scene: &std::path::Path, extra: &[&str], tag: &str| {
        let (csv, json) = (
            dir.path().join(format!("{tag}.csv")),
            dir.path().join(format!("{tag}.json")),
        );
        let mut args = vec!["solve", s(scene), "--results", s(&csv), "--stats", s(&json)];
        args.extend(extra);
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_hirad"))
            .args(&args)
            .env("HIRAD_CACHE", dir.path().join("cache"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(out.status.success(), "{tag}: {err}");
        let stats: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        let method = stats["method"].as_str().unwrap().to_string();
        (method, err, std::fs::read(&csv).unwrap())
    };
    let (method, err, default_text) = solve(&scene, &[], "text");
    assert_eq!(method, "hr", "{err}");
    assert!(
        err.contains("note: solving with --method hr") && err.contains("hirad tables"),
        "{err}"
    );
    assert!(!err.contains("instancing auto:"), "{err}");
    let (method, _, hr) = solve(&scene, &["--method", "hr"], "hr");
    assert_eq!(method, "hr");
    assert!(default_text == hr, "the default differs from --method hr");

    let (method, err, default_image) = solve(&made, &[], "image");
    assert_eq!(method, "hi", "{err}");
    assert!(
        err.contains("note: solving with --method hi") && err.contains("crate: closed"),
        "{err}"
    );
    let (method, _, hi) = solve(&made, &["--method", "hi"], "hi");
    assert_eq!(method, "hi");
    assert!(default_image == hi, "the default differs from --method hi");
    // A policy given alone asks for hi, on the scene without tables too (made, cached).
    let (method, err, _) = solve(
        &scene,
        &["--instancing", "auto", "--table-max-side", "8"],
        "auto",
    );
    assert_eq!(method, "hi", "{err}");

    let (method, err, _) = solve(&fixture("cornell_box.hir"), &[], "box");
    assert_eq!(method, "hr");
    assert!(!err.contains("note: solving with"), "{err}");
}
