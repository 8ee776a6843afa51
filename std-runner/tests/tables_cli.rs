//! `hirad tables` end to end on a small plant: the report, the CSV files and the stats agree
//! with each other, the exit status says whether the targets were met, and bad requests get
//! usage errors.

mod common;

use common::{fails_with, fixture, hirad, s};

/// The number after `"key": ` in a JSON text (first occurrence).
fn number(json: &str, key: &str) -> f64 {
    let k = format!("\"{key}\": ");
    let at = json.find(&k).unwrap_or_else(|| panic!("{key} in {json}")) + k.len();
    let rest = &json[at..];
    let end = rest.find([',', '}', ']']).unwrap();
    rest[..end].trim().parse().unwrap()
}

#[test]
fn a_twigs_tables_are_written_and_judged() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("twig.csv");
    let stats = dir.path().join("twig.json");
    let plots = dir.path().join("plots");
    let plant = fixture("small_plant.hir");
    let out = hirad(&[
        "tables",
        s(&plant),
        "--original",
        "twig",
        "--max-side",
        "4",
        "--max-tau-side",
        "8",
        "--tau-target",
        "0.5",
        "--check",
        "2",
        "--export",
        s(&csv),
        "--stats",
        s(&stats),
        "--plot",
        s(&plots),
        "--no-cache",
        "-q",
    ]);
    let stdout = String::from_utf8(out.stdout).unwrap();
    let stderr = String::from_utf8(out.stderr).unwrap();
    // One picture per band, named after the original and the band, a real PNG.
    assert!(stdout.contains("plots: 2 pictures in"), "{stdout}");
    for band in ["par", "nir"] {
        let png = std::fs::read(plots.join(format!("twig_{band}.png"))).unwrap();
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "{band}");
        let (w, h) = (
            u32::from_be_bytes(png[16..20].try_into().unwrap()),
            u32::from_be_bytes(png[20..24].try_into().unwrap()),
        );
        assert!(w > 720 && h > 3 * 360, "{band}: {w} x {h}");
    }
    assert!(
        stdout.starts_with("twig: 4 polygons, tau grid "),
        "{stdout}"
    );
    assert!(stdout.contains("twig: checked at 2 directions"), "{stdout}");
    let json = std::fs::read_to_string(&stats).unwrap();
    // Exit 0 only when every target was met and every check passed; otherwise 1, saying so.
    let met = json.contains("\"met\": true");
    let checked = number(&json, "scattered") <= 0.02
        && number(&json, "tau") <= 0.01
        && number(&json, "intensity") <= 0.05
        && number(&json, "energy") <= 0.005;
    if met && checked {
        assert!(out.status.success(), "{stderr}");
    } else {
        assert_eq!(out.status.code(), Some(1), "{stderr}");
        assert!(stderr.contains("twig"), "{stderr}");
    }
    // Energy per sun: the solve's and the table's accounts close within half a percent.
    assert!(number(&json, "energy") < 0.005, "{json}");
    let residual = json.split("\"energy_residual\": [").nth(1).unwrap();
    for r in residual[..residual.find(']').unwrap()].split(',') {
        assert!(r.trim().parse::<f64>().unwrap().abs() < 0.01, "{json}");
    }
    // The twig's 4 polygons keep their first scattering apart, on a grid of their own.
    assert_eq!(number(&json, "scatterers"), 4.0, "{json}");
    assert!(number(&json, "single_side") >= 32.0, "{json}");
    assert!(
        stdout.contains("first scattering of its 4 polygons kept apart"),
        "{stdout}"
    );
    // One row per band and incoming cell; the bidirectional file per outgoing cell too.
    let side_in = number(&json, "incoming_side") as usize;
    let side_out = number(&json, "outgoing_side") as usize;
    let rows = std::fs::read_to_string(&csv).unwrap();
    assert!(rows.starts_with("original,band,cell,x,y,z,solid_angle_sr,tau,area_m2"));
    assert_eq!(rows.lines().count(), 1 + 2 * side_in * side_in);
    let mut solid = 0.0;
    for line in rows.lines().skip(1).filter(|l| l.contains(",par,")) {
        let f: Vec<f64> = line
            .split(',')
            .skip(3)
            .map(|x| x.parse().unwrap())
            .collect();
        let (d, sr, tau, area, shadow, albedo, scattered) =
            ((f[0], f[1], f[2]), f[3], f[4], f[5], f[6], f[7], f[8]);
        assert!(((d.0 * d.0 + d.1 * d.1 + d.2 * d.2) - 1.0).abs() < 1e-5);
        assert!((0.0..=1.0).contains(&tau) && (0.0..=1.0).contains(&albedo));
        assert!((shadow - (1.0 - tau) * area).abs() < 1e-6 + 1e-4 * shadow);
        assert!((scattered - albedo * shadow).abs() < 1e-6 + 1e-3 * scattered);
        solid += sr;
    }
    assert!((solid - 4.0 * std::f64::consts::PI).abs() < 1e-4);
    let bi = std::fs::read_to_string(dir.path().join("twig_bidirectional.csv")).unwrap();
    assert_eq!(
        bi.lines().count(),
        1 + 2 * side_in * side_in * side_out * side_out
    );
}

#[test]
fn bad_requests_are_usage_errors() {
    let plant = fixture("small_plant.hir");
    let err = fails_with(
        2,
        &["tables", s(&plant), "--original", "nope", "--no-cache"],
    );
    assert!(
        err.contains("--original nope") && err.contains("twig, branch"),
        "{err}"
    );
    let err = fails_with(2, &["tables", s(&plant), "--max-side", "2", "--no-cache"]);
    assert!(err.contains("--max-side 2"), "{err}");
    let err = fails_with(
        2,
        &["tables", s(&plant), "--max-single-side", "2", "--no-cache"],
    );
    assert!(err.contains("--max-single-side 2"), "{err}");
    let err = fails_with(2, &["tables", s(&plant), "--epsilon", "0", "--no-cache"]);
    assert!(err.contains("--epsilon"), "{err}");
    // A scene without instances has no table to make, and says so.
    let out = hirad(&["tables", s(&fixture("cornell_box.hir")), "--no-cache"]);
    assert!(out.status.success());
    assert!(
        String::from_utf8(out.stderr)
            .unwrap()
            .contains("no instanced original")
    );
}

#[test]
fn a_second_run_takes_the_tables_from_the_cache_and_a_damaged_entry_is_made_again() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let plant = fixture("small_plant.hir");
    let run = |tag: &str, epsilon: &str| {
        let csv = dir.path().join(format!("{tag}.csv"));
        let stats = dir.path().join(format!("{tag}.json"));
        let out = hirad(&[
            "tables",
            s(&plant),
            "--original",
            "twig",
            "--max-side",
            "4",
            "--max-tau-side",
            "8",
            "--tau-target",
            "0.5",
            "--epsilon",
            epsilon,
            "--cache",
            s(&cache),
            "--export",
            s(&csv),
            "--stats",
            s(&stats),
            "-q",
        ]);
        let report = String::from_utf8(out.stdout).unwrap();
        let json = std::fs::read_to_string(&stats).unwrap();
        (
            report,
            number(&json, "cache_hits"),
            std::fs::read_to_string(csv).unwrap(),
        )
    };
    let (first, hits, csv) = run("first", "1e-4");
    assert_eq!(hits, 0.0);
    assert!(!first.contains("from the cache"), "{first}");
    let (second, hits, again) = run("second", "1e-4");
    assert_eq!(hits, 1.0, "{second}");
    assert!(
        second.contains("0 solves") && second.contains("from the cache"),
        "{second}"
    );
    assert_eq!(again, csv, "the cached tables are the computed ones");
    // Other settings are other tables.
    let (_, hits, _) = run("coarser", "1e-3");
    assert_eq!(hits, 0.0);
    // Damage every entry: each is made again, not used, then used.
    for e in std::fs::read_dir(&cache).unwrap() {
        let path = e.unwrap().path();
        let mut bytes = std::fs::read(&path).unwrap();
        let mid = bytes.len() / 2;
        bytes[mid] ^= 0x55;
        std::fs::write(&path, bytes).unwrap();
    }
    let (third, hits, redone) = run("third", "1e-4");
    assert_eq!(hits, 0.0, "{third}");
    assert_eq!(redone, csv);
    let (_, hits, _) = run("fourth", "1e-4");
    assert_eq!(hits, 1.0);
}
