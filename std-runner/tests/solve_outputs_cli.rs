//! What a solve tells whoever reads its outputs without the docs: exit statuses by class,
//! results tables that join to the scene's groups and materials, and a picture's error
//! against a reference picture.

mod common;

use common::{fails_with, fixture, ok, s, write};

/// Every error class ends with its own status, whatever the command: usage 2, input 3, not
/// right 1 (with the outputs written); documented in README.md and `hirad::exit`.
#[test]
fn exit_statuses_by_class() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cornell = fixture("cornell_box.hir");
    let bad = write(d, "bad.hir", "hirad 1\nbands 1\nmaterial m { rho 2 }\n");
    let missing = d.join("missing.hir");
    // Usage: the command line.
    for args in [
        vec!["solve", s(&cornell), "--epsilon", "-1"],
        vec!["solve", s(&cornell), "--tolerance", "0"],
        vec!["solve", s(&cornell), "--frobnicate"],
        vec!["solve", s(&cornell), "--results", "/nonexistent-dir/r.csv"],
        vec!["solve", s(&cornell), "--image", "x.bmp"],
        vec!["solve", s(&cornell), "--memory", "1K"],
        vec!["gen", "room", "-o", "room.txt"],
        vec!["flatten", s(&cornell), "-o", "x.hir"],
    ] {
        let e = fails_with(2, &args);
        assert!(e.contains("error"), "{args:?}: {e}");
    }
    // Input: a file the run reads.
    for args in [
        vec!["solve", s(&bad)],
        vec!["solve", s(&missing)],
        vec!["info", s(&bad)],
        vec!["convert", s(&bad), "-o", "x.hirb"],
        vec!["solve", s(&cornell), "--reference", s(&bad)],
    ] {
        let e = fails_with(3, &args);
        assert!(
            e.contains(s(&bad)) || e.contains(s(&missing)),
            "{args:?}: {e}"
        );
    }
    // Not right: the run finished, wrote its outputs, and says why it failed; the stats
    // record the verdict.
    let (r, j) = (d.join("r.csv"), d.join("s.json"));
    let e = fails_with(
        1,
        &[
            "solve",
            s(&cornell),
            "--max-imbalance",
            "0",
            "--results",
            s(&r),
            "--stats",
            s(&j),
        ],
    );
    assert!(e.contains("--max-imbalance"), "{e}");
    assert!(r.exists());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&j).unwrap()).unwrap();
    assert_eq!(json["verdict"]["passed"], false, "{json}");
    assert!(
        json["verdict"]["reason"]
            .as_str()
            .unwrap()
            .contains("power balance"),
        "{json}"
    );
}

/// The scene of `results_join_to_groups_and_materials`: a soil and two exact instances of a
/// plant (a stem cluster and a leaves cluster of two-sided leaves), the second scaled by 1.5;
/// `glass` is two-sided and used by nothing.
const FIELD: &str = "hirad 1
bands par nir

material soil rho 0.1 0.2
material stem rho 0.08 0.3
material leaf rho 0.1 0.45 tau 0.05 0.45
material glass rho 0.1 0.1 tau 0.5 0.5

sun from 0.3 0.2 0.93 irradiance 400 450

original plant {
  cluster stem {
    quad stem -0.01 0 0  0.01 0 0  0.01 0 0.5  -0.01 0 0.5
  }
  cluster leaves {
    quad leaf 0 0 0.3  0.2 -0.05 0.3666667  0.3 0 0.4  0.2 0.05 0.3666667
    tri leaf 0 0 0.45  -0.2 -0.05 0.5  -0.2 0.05 0.5
  }
}

scene field {
  cluster soil {
    quad soil -1 -1 0  1 -1 0  1 1 0  -1 1 0
  }
  instance plant exact name plant_a translate -0.4 0 0
  instance plant exact name plant_b translate 0.4 0 0 scale 1.5
}
";

/// Reads a results table into its header and rows (no quoted fields in these scenes).
fn table(path: &std::path::Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text
        .lines()
        .map(|l| l.split(',').map(String::from).collect());
    (lines.next().unwrap(), lines.collect())
}

/// A results table names its bands and units and says each polygon's material and group,
/// so that it joins to the scene's structure without flattening it; back-side columns only
/// when a polygon uses a two-sided material.
#[test]
fn results_join_to_groups_and_materials() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = write(d, "field.hir", FIELD);
    let csv = d.join("r.csv");
    ok(&["solve", "-q", s(&scene), "--results", s(&csv)]);
    let (header, rows) = table(&csv);
    assert_eq!(
        header,
        [
            "id",
            "area_m2",
            "rad_par_W_m2",
            "rad_nir_W_m2",
            "irr_par_W_m2",
            "irr_nir_W_m2",
            "rad_back_par_W_m2",
            "rad_back_nir_W_m2",
            "irr_back_par_W_m2",
            "irr_back_nir_W_m2",
            "material",
            "group"
        ]
    );
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    // Join: polygons and area per group, as the scene was written.
    let leaf_quad = 0.3 * 0.1 / 2.0 * ((0.1f64 / 0.3).powi(2) + 1.0).sqrt(); // planar kite
    let leaf_tri = 0.5 * 0.2 * 0.1 * (1.0f64 + 0.25f64.powi(2)).sqrt();
    let stem = 0.02 * 0.5;
    let want: Vec<(&str, &str, usize, f64)> = vec![
        ("scene/soil", "soil", 1, 4.0),
        ("scene/plant_a/stem", "stem", 1, stem),
        ("scene/plant_a/leaves", "leaf", 2, leaf_quad + leaf_tri),
        ("scene/plant_b/stem", "stem", 1, 2.25 * stem),
        (
            "scene/plant_b/leaves",
            "leaf",
            2,
            2.25 * (leaf_quad + leaf_tri),
        ),
    ];
    for (group, material, count, area) in want {
        let mine: Vec<&Vec<String>> = rows.iter().filter(|r| r[col("group")] == group).collect();
        assert_eq!(mine.len(), count, "{group}: {rows:?}");
        assert!(
            mine.iter().all(|r| r[col("material")] == material),
            "{group}"
        );
        let sum: f64 = mine
            .iter()
            .map(|r| r[col("area_m2")].parse::<f64>().unwrap())
            .sum();
        assert!(
            (sum / area - 1.0).abs() < 1e-4,
            "{group}: area {sum}, want {area}"
        );
        // Leaves are two-sided and have back values; the rest leave them empty.
        for r in &mine {
            let back = &r[col("irr_back_nir_W_m2")];
            assert_eq!(back.is_empty(), material != "leaf", "{group}: {r:?}");
        }
        // Every lit group gathered some light.
        assert!(
            mine.iter()
                .all(|r| r[col("irr_par_W_m2")].parse::<f64>().unwrap() > 0.0)
        );
    }
    // The same field without leaves: `glass` is two-sided but unused, so no back columns.
    let bare = FIELD
        .replace("quad leaf", "quad stem")
        .replace("tri leaf", "tri stem");
    let scene = write(d, "bare.hir", &bare);
    ok(&["solve", "-q", s(&scene), "--results", s(&csv)]);
    let (header, _) = table(&csv);
    assert!(!header.iter().any(|h| h.contains("back")), "{header:?}");
    // A scene without band names: bands by index from 0, as --display-bands counts them.
    let plain = FIELD.replace("bands par nir", "bands 2");
    let scene = write(d, "plain.hir", &plain);
    ok(&["solve", "-q", s(&scene), "--results", s(&csv)]);
    let (header, _) = table(&csv);
    assert_eq!(header[2..4], ["rad_0_W_m2", "rad_1_W_m2"]);
}

/// `--reference-image` prints and records the picture's relative L2 error against another
/// EXR of the same view: 0 against itself, more than 0 for the flat picture against the
/// smooth one; refused for a PNG or another size.
#[test]
fn a_picture_is_compared_with_a_reference_picture() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = fixture("cornell_box.hir");
    let (a, b, j) = (d.join("a.exr"), d.join("b.exr"), d.join("s.json"));
    let size = ["--size", "48x36"];
    let run = |extra: &[&str]| {
        let mut args = vec!["solve", "-q", s(&scene)];
        args.extend_from_slice(&size);
        args.extend_from_slice(extra);
        ok(&args)
    };
    run(&["--image", s(&a)]);
    let out = run(&[
        "--image",
        s(&b),
        "--reference-image",
        s(&a),
        "--stats",
        s(&j),
    ]);
    assert!(out.contains("image error 0.000 %"), "{out}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&j).unwrap()).unwrap();
    assert_eq!(json["image_error_percent"], 0.0, "{json}");
    let flat = run(&[
        "--image",
        s(&b),
        "--shading",
        "flat",
        "--reference-image",
        s(&a),
    ]);
    let e: f64 = flat
        .split_whitespace()
        .nth(2)
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{flat}"));
    assert!(e > 0.0, "{flat}");
    fails_with(
        2,
        &[
            "solve",
            s(&scene),
            "--image",
            s(&d.join("x.png")),
            "--reference-image",
            s(&a),
        ],
    );
    fails_with(
        3,
        &[
            "solve",
            s(&scene),
            "--size",
            "10x10",
            "--image",
            s(&b),
            "--reference-image",
            s(&a),
        ],
    );
}
