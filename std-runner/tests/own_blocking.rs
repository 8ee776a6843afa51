//! Closed approximate instances cast the shadows of the polygons they really hold (issue 18):
//! an approximate instance's own geometry is in the file and its original only stands in
//! for it through the tables, so `hi` must block the sun with the instance's own polygons,
//! not its original's placed where it stands. Panels over a ground grid under a vertical
//! sun: each panel's own quad lies exactly over one ground cell, its original's quad two
//! cells away; every ground cell is then either fully lit or fully shaded, which an exact
//! count of the panels above it tells, sharing no code with the solver.

mod common;

use common::{coarse_tables, hirad, s, write};

/// A deterministic hash of `k` to [0, 1).
fn unit(k: u32) -> f64 {
    let mut x = k.wrapping_mul(0x9E37_79B9) ^ 0x85EB_CA6B;
    x ^= x >> 15;
    x = x.wrapping_mul(0x2C1B_3C6D);
    x ^= x >> 12;
    (x % 10_000) as f64 / 10_000.0
}

/// A ground of `n` x `n` unit cells (z = 0) and `panels` approximate instances of a panel,
/// each over a cell of its own, turned by a multiple of 90 degrees about z: its own quad
/// covers its cell 1 m up, its original's quad lies 2 to 3 m along the instance's x. Returns
/// the scene text and the shaded cells (`i * n + j`: cell `x in [i, i+1], y in [j, j+1]`).
fn panels(n: u32, panels: u32, seed: u32) -> (String, Vec<bool>) {
    let mut t = String::from(
        "hirad 1\nbands par nir\nmaterial soil rho 0.2 0.3\nmaterial panel rho 0.05 0.05\n\
         sun from 0 0 1 irradiance 400 300\n\
         original panel {\n  v 2 -0.5 1\n  v 3 -0.5 1\n  v 3 0.5 1\n  v 2 0.5 1\n  quad panel 0 1 2 3\n}\nscene panels {\n",
    );
    let mut v = 0;
    for i in 0..n {
        for j in 0..n {
            t += &format!(
                "v {i} {j} 0\nv {} {j} 0\nv {} {} 0\nv {i} {} 0\nquad soil {} {} {} {}\n",
                i + 1,
                i + 1,
                j + 1,
                j + 1,
                v,
                v + 1,
                v + 2,
                v + 3
            );
            v += 4;
        }
    }
    let mut shaded = vec![false; (n * n) as usize];
    let mut placed = 0;
    let mut k = seed.wrapping_mul(977);
    while placed < panels {
        k += 1;
        let cell = ((unit(k) * (n * n) as f64) as u32).min(n * n - 1);
        if shaded[cell as usize] {
            continue;
        }
        shaded[cell as usize] = true;
        placed += 1;
        let (i, j) = (cell / n, cell % n);
        let turn = 90 * ((unit(k + 7919) * 4.0) as u32 % 4);
        t += &format!(
            "instance panel approx translate {}.5 {}.5 0 rotate 0 0 1 {turn} {{\n  v -0.5 -0.5 1\n  v 0.5 -0.5 1\n  v 0.5 0.5 1\n  v -0.5 0.5 1\n  quad panel 0 1 2 3\n}}\n",
            i, j
        );
    }
    t += "}\n";
    (t, shaded)
}

/// Each ground cell's front irradiance in band `band` (W/m^2), by cell, from a results CSV
/// (the ground's polygons are the scene's first, in cell order).
fn ground(csv: &str, cells: usize, band: &str) -> Vec<f64> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = header
        .iter()
        .position(|h| *h == format!("irr_{band}_W_m2"))
        .unwrap();
    let mut out = vec![f64::NAN; cells];
    for line in lines {
        let f: Vec<&str> = line.split(',').collect();
        let id: usize = f[0].parse().unwrap();
        if id < cells {
            out[id] = f[col].parse().unwrap();
        }
    }
    out
}

#[test]
fn closed_approximate_instances_shade_with_their_own_polygons() {
    let dir = tempfile::tempdir().unwrap();
    // Sizes, counts and turns swept: every ground cell lit or shaded as its panels say.
    for (n, count, seed) in [(6u32, 5u32, 1u32), (8, 11, 2), (7, 3, 3)] {
        let (text, shaded) = panels(n, count, seed);
        let scene = write(dir.path(), &format!("panels_{seed}.hir"), &text);
        let image = dir.path().join(format!("panels_{seed}.hirb"));
        // Coarse tables (their targets need not be met), written all the same.
        let out = coarse_tables(&scene, &image);
        assert!(image.exists(), "{}", String::from_utf8_lossy(&out.stderr));
        let cells = (n * n) as usize;
        let solve = |name: &str, extra: &[&str]| -> [Vec<f64>; 2] {
            let csv = dir.path().join(format!("{name}_{seed}.csv"));
            let mut args = vec!["solve", s(&image), "--results", s(&csv), "-q"];
            args.extend_from_slice(extra);
            let out = hirad(&args);
            assert!(
                out.status.success(),
                "{name}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
            let text = std::fs::read_to_string(&csv).unwrap();
            [ground(&text, cells, "par"), ground(&text, cells, "nir")]
        };
        let hi = solve("hi", &["--method", "hi", "--instancing", "all"]);
        let hr = solve("hr", &["--method", "hr"]);
        // Their originals' polygons instead (as before): some cell is then wrong, which
        // shows that the case tells the two apart.
        let as_original = solve(
            "original",
            &[
                "--method",
                "hi",
                "--instancing",
                "all",
                "--own-polygons",
                "0",
            ],
        );
        for (b, sun) in [400.0f64, 300.0].into_iter().enumerate() {
            for c in 0..cells {
                // Shaded: only the panels' undersides' light (a 5% albedo under a 20-30%
                // ground); lit: the sun and a little of it back from those undersides.
                let (lo, hi_bound) = if shaded[c] {
                    (0.0, 0.03 * sun)
                } else {
                    (sun, 1.03 * sun)
                };
                for (name, got) in [("hi", &hi[b][c]), ("hr", &hr[b][c])] {
                    assert!(
                        (lo..=hi_bound).contains(got),
                        "n {n}, {count} panels, band {b}, cell {c} (shaded: {}): {name} {got}",
                        shaded[c]
                    );
                }
                assert!(
                    (hi[b][c] - hr[b][c]).abs() <= 0.01 * sun,
                    "n {n}, band {b}, cell {c}: hi {} hr {}",
                    hi[b][c],
                    hr[b][c]
                );
            }
            let wrong = (0..cells)
                .filter(|&c| (as_original[b][c] < 0.5 * sun) != shaded[c])
                .count();
            assert!(
                wrong > 0,
                "n {n}, band {b}: the originals' quads shade the same cells"
            );
        }
    }
}

/// [`panels`] with coarse tables as `NAME.hirb` in `dir`: its path and bytes.
fn panels_image(
    dir: &std::path::Path,
    name: &str,
    n: u32,
    count: u32,
    seed: u32,
) -> (std::path::PathBuf, Vec<u8>) {
    let (text, _) = panels(n, count, seed);
    let scene = write(dir, &format!("{name}.hir"), &text);
    let image = dir.join(format!("{name}.hirb"));
    let out = coarse_tables(&scene, &image);
    assert!(image.exists(), "{}", String::from_utf8_lossy(&out.stderr));
    let bytes = std::fs::read(&image).unwrap();
    (image, bytes)
}

/// A `--memory` budget between hi's least without the approximate instances' own polygons
/// and its least with them turns them off (a note says so; the stats say so and count no
/// instance blocking with them) rather than risking a level that does not fit; at the least
/// with them they stay on. Two sizes of the panels' scene.
#[test]
fn a_budget_below_the_least_with_own_polygons_turns_them_off() {
    use hirad_core::hr::{Inline, Settings, plan_hi, plan_hi_scratch_bytes};
    use hirad_core::image::{SceneView, SliceSource};
    let dir = tempfile::tempdir().unwrap();
    for (n, count, seed) in [(6u32, 5u32, 1u32), (9, 14, 4)] {
        let (image, bytes) = panels_image(dir.path(), &format!("budget_{seed}"), n, count, seed);
        let view = SceneView::open(SliceSource(&bytes[..])).unwrap();
        let mut scratch = vec![0u8; plan_hi_scratch_bytes(&view)];
        let on = Settings::default();
        let off = Settings {
            own_polygons: 0,
            ..on
        };
        let least = |s: &Settings, scratch: &mut [u8]| {
            plan_hi(&view, s, Inline::NONE, scratch).unwrap().min_bytes
        };
        let (with, without) = (least(&on, &mut scratch), least(&off, &mut scratch));
        assert!(without < with, "n {n}: {without} vs {with}");
        let run = |memory: u64| -> (String, serde_json::Value) {
            let stats = dir.path().join(format!("budget_{seed}_{memory}.json"));
            let m = memory.to_string();
            let out = hirad(&[
                "solve",
                s(&image),
                "--method",
                "hi",
                "--instancing",
                "all",
                "--threads",
                "2",
                "--memory",
                &m,
                "--stats",
                s(&stats),
            ]);
            let err = String::from_utf8_lossy(&out.stderr).into_owned();
            assert!(out.status.success(), "n {n}, --memory {m}: {err}");
            let json = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
            (err, json)
        };
        let (err, json) = run((with + without) / 2);
        assert!(
            err.contains("they block as their originals do"),
            "n {n}: no note: {err}"
        );
        assert_eq!(
            json["levels"]["own_polygons"], 0,
            "n {n}: {}",
            json["levels"]
        );
        assert_eq!(json["levels"]["own_blocking_instances"], 0, "n {n}");
        assert_eq!(
            json["settings"]["own_polygons"],
            Settings::OWN_POLYGONS,
            "n {n}"
        );
        let (err, json) = run(with);
        assert!(
            !err.contains("they block as their originals do"),
            "n {n}: {err}"
        );
        assert_eq!(
            json["levels"]["own_polygons"],
            Settings::OWN_POLYGONS,
            "n {n}"
        );
        assert_eq!(json["levels"]["own_blocking_instances"], count, "n {n}");
    }
}

/// A `--memory` budget below what surely fails even without the approximate instances' own
/// polygons, but at hi's least with closed instances blocking by their tables alone
/// (`--blocking-polygons 0`: no light between them by rays, whose region keeps about 10 KB
/// per closed instance), turns the blocking polygons off too: a note, the stats, and the
/// results of the same settings given by name.
#[test]
fn a_budget_below_the_least_with_blocking_polygons_turns_them_off() {
    use hirad_core::hr::{Inline, Settings, plan_hi, plan_hi_scratch_bytes};
    use hirad_core::image::{SceneView, SliceSource};
    let dir = tempfile::tempdir().unwrap();
    for (n, count, seed) in [(10u32, 60u32, 2u32), (14, 150, 5)] {
        let (image, bytes) = panels_image(dir.path(), &format!("tau_{seed}"), n, count, seed);
        let view = SceneView::open(SliceSource(&bytes[..])).unwrap();
        let mut scratch = vec![0u8; plan_hi_scratch_bytes(&view)];
        let own_off = Settings {
            own_polygons: 0,
            ..Settings::default()
        };
        let all_off = Settings {
            blocking_polygons: 0,
            ..own_off
        };
        let with = plan_hi(&view, &own_off, Inline::NONE, &mut scratch).unwrap();
        let without = plan_hi(&view, &all_off, Inline::NONE, &mut scratch).unwrap();
        assert!(
            with.bare_min_bytes - without.bare_min_bytes >= count as u64 * 9_000,
            "n {n}: {without:?} vs {with:?} for {count} closed instances"
        );
        // A budget that surely fails with the blocking polygons and surely opens every
        // level without them.
        let budget = without.min_bytes;
        assert!(
            budget < with.bare_min_bytes,
            "n {n}: {without:?} vs {with:?}"
        );
        let run = |extra: &[&str], tag: &str| -> (String, serde_json::Value, Vec<u8>) {
            let (stats, csv) = (
                dir.path().join(format!("tau_{seed}_{tag}.json")),
                dir.path().join(format!("tau_{seed}_{tag}.csv")),
            );
            let m = budget.to_string();
            let mut args = vec![
                "solve",
                s(&image),
                "--method",
                "hi",
                "--instancing",
                "all",
                "--threads",
                "2",
                "--memory",
                &m,
                "--stats",
                s(&stats),
                "--results",
                s(&csv),
            ];
            args.extend(extra);
            let out = hirad(&args);
            let err = String::from_utf8_lossy(&out.stderr).into_owned();
            assert!(out.status.success(), "n {n}, {tag}: {err}");
            let json = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
            (err, json, std::fs::read(&csv).unwrap())
        };
        let (err, json, fallen) = run(&[], "budget");
        assert!(
            err.contains("take each other's light through links"),
            "n {n}: no note: {err}"
        );
        assert_eq!(json["levels"]["blocking_polygons"], 0, "n {n}");
        assert_eq!(json["levels"]["own_polygons"], 0, "n {n}");
        assert_eq!(
            json["settings"]["blocking_polygons"],
            Settings::BLOCKING_POLYGONS,
            "n {n}"
        );
        let (err, json, named) = run(
            &["--blocking-polygons", "0", "--own-polygons", "0"],
            "named",
        );
        assert!(!err.contains("through links"), "n {n}: {err}");
        assert_eq!(json["levels"]["blocking_polygons"], 0, "n {n}");
        assert!(fallen == named, "n {n}: the fallback solved otherwise");
    }
}
