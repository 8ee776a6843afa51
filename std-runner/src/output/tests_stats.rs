//! The stats report: JSON round trip with every field, and the summary text.

use super::reference::{Comparison, WorstPolygon};
use super::stats::{
    BandPower, ImageSettings, OutputFile, PhaseTime, RaysByPhase, RunSettings, SolveReport,
    Verdict, bytes,
};

fn report() -> SolveReport {
    SolveReport {
        hirad_version: "0.1.0".into(),
        scene: "maize.hirb".into(),
        settings: Some(RunSettings {
            method: "hr".into(),
            epsilon: Some(0.001),
            rays: Some(4),
            final_rays: Some("auto".into()),
            final_passes: Some("2".into()),
            min_area: Some(1e-6),
            tolerance: 1e-4,
            max_iterations: Some(20_000),
            max_imbalance_percent: Some(5.0),
            memory_bytes: None,
            visibility: Some("obvhs".into()),
            blocking_polygons: None,
            own_polygons: None,
            instancing: None,
            elements: None,
            threads: Some(4),
            image: Some(ImageSettings {
                size: [64, 48],
                camera: "0,0,5,0,0,0,0,1,0,40".into(),
                supersample: 2,
                display_bands: Some("par".into()),
                display: None,
                shading: "smooth".into(),
            }),
        }),
        outputs: vec![OutputFile {
            option: "--stats".into(),
            path: "s.json".into(),
        }],
        verdict: Some(Verdict {
            passed: false,
            reason: "the solution did not converge".into(),
        }),
        method: "hr".into(),
        epsilon: Some(0.001),
        threads: 4,
        polygons: 17,
        elements: 1234,
        links: 56789,
        iterations: 12,
        refinement_passes: 3,
        seconds: 1.5,
        peak_workspace_bytes: 3 << 20,
        workspace_bytes: 64 << 20,
        budget_limited: true,
        error_percent: None,
        error_per_band_percent: Vec::new(),
        max_abs_difference: None,
        worst_polygons: Vec::new(),
        converged: false,
        diverged: false,
        remaining_change: Some(3e-4),
        power: vec![BandPower {
            band: "nir".into(),
            emitted: 1.0,
            direct: 2.0,
            absorbed: 1.5,
            absorbed_backs: 0.25,
            escaped: 1.0,
            imbalance: 0.25,
            imbalance_percent: 8.333,
        }],
        phases: vec![
            PhaseTime {
                phase: "setup".into(),
                seconds: 0.25,
            },
            PhaseTime {
                phase: "solving".into(),
                seconds: 1.125,
            },
        ],
        rays: 123_456,
        rays_by_phase: Some(RaysByPhase {
            lighting: 100_000,
            links: 20_000,
            final_gather: 3_456,
        }),
        levels: Some(super::Levels {
            solved: 26,
            deepest: 2,
            closed_instances: 25,
            own_polygons: 131_072,
            blocking_polygons: 16_384,
            own_blocking_instances: 24,
            levels_together: 20,
            opened_again: 1,
            largest_level_leaves: 1652,
            leaf_histogram: vec![super::LeafBin {
                leaves_from: 8,
                leaves_to: 15,
                levels: 25,
            }],
            peak_workspace_bytes_by_depth: vec![1 << 20, 3 << 19, 7 << 18],
            top_level_bytes: super::TopLevelBytes {
                received_light: 4096,
                exchange_laid_out: 8192,
                exchange_written: 512,
                ..Default::default()
            },
        }),
        tables: Some(super::TablesMade {
            originals: vec!["twig".into(), "branch".into()],
            cache_hits: 1,
            targets_missed: vec!["twig".into()],
            seconds: 2.5,
        }),
        final_passes: Some(3),
        final_change_percent: Some(0.42),
        image_error_percent: Some(1.5),
    }
}

#[test]
fn summary_tells_power_and_convergence() {
    let mut text = Vec::new();
    report().print_summary(&mut text).unwrap();
    let text = String::from_utf8(text).unwrap();
    assert!(text.contains("nir: in 3.000000 (emitted 1.000000, direct 2.000000), absorbed 1.500000 + 0.250000 by backs, escaped 1.000000, imbalance +8.333 %"), "{text}");
    assert!(text.contains("NOT converged"), "{text}");
    assert!(text.contains("3.0e-4"), "{text}");
    assert!(
        text.contains("phases: setup 0.250 s, solving 1.125 s; 123456 rays (lighting 100000, links 20000, final gather 3456)"),
        "{text}"
    );
    assert!(
        text.contains("final gather: 3 passes (the last relighting pass moved the leaving light by 0.42% of what enters)"),
        "{text}"
    );
    // Old JSON without the new fields reads as converged, with no balance.
    let old = SolveReport::from_json(r#"{"method":"hr","epsilon":0.001,"threads":1,"polygons":1,"elements":1,"links":1,"iterations":1,"refinement_passes":1,"seconds":0.1,"peak_workspace_bytes":1,"workspace_bytes":1,"budget_limited":false,"error_percent":null}"#).unwrap();
    assert!(old.converged && old.power.is_empty() && old.remaining_change.is_none());
    assert!(old.verdict.is_none() && old.settings.is_none() && old.scene.is_empty());
    // The exact solver names no epsilon and no workspace.
    let mut exact = report();
    exact.method = "exact".into();
    exact.epsilon = None;
    exact.budget_limited = false;
    exact.levels = None;
    exact.tables = None;
    let mut text = Vec::new();
    exact.print_summary(&mut text).unwrap();
    let text = String::from_utf8(text).unwrap();
    assert!(
        text.starts_with("solve: method exact, 4 threads, form factor matrix"),
        "{text}"
    );
    assert!(
        !text.contains("epsilon") && !text.contains("workspace"),
        "{text}"
    );
}

#[test]
fn json_round_trip_holds_every_field() {
    let mut r = report();
    let text = r.to_json();
    for field in [
        "hirad_version",
        "scene",
        "settings",
        "final_rays",
        "max_imbalance_percent",
        "image",
        "outputs",
        "verdict",
        "passed",
        "reason",
        "method",
        "epsilon",
        "threads",
        "polygons",
        "elements",
        "links",
        "iterations",
        "refinement_passes",
        "seconds",
        "peak_workspace_bytes",
        "workspace_bytes",
        "budget_limited",
        "error_percent",
        "error_per_band_percent",
        "max_abs_difference",
        "worst_polygons",
        "converged",
        "remaining_change",
        "power",
        "phases",
        "rays",
        "rays_by_phase",
        "final_passes",
        "final_change_percent",
        "image_error_percent",
    ] {
        assert!(
            text.contains(&format!("\"{field}\":")),
            "{field} missing in {text}"
        );
    }
    assert!(text.contains("\"error_percent\": null"), "{text}");
    assert_eq!(SolveReport::from_json(&text).unwrap(), r);

    r.set_comparison(&Comparison {
        error_percent: 1.25,
        per_band_percent: vec![1.0, 1.5],
        max_abs_difference: 0.5,
        reference_max: 10.0,
        polygons: 17,
        back_compared: false,
        worst: vec![WorstPolygon {
            id: 17,
            band: 1,
            back: true,
            reference: 0.02618,
            result: 0.02795,
            relative_error_percent: 6.76,
        }],
        relative_floor: 0.01,
    });
    let text = r.to_json();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["error_percent"], 1.25);
    let w = &v["worst_polygons"][0];
    assert_eq!(w["id"], 17);
    assert_eq!(w["band"], 1);
    assert_eq!(w["back"], true);
    assert_eq!(w["reference"], 0.02618);
    assert_eq!(w["result"], 0.02795);
    assert_eq!(w["relative_error_percent"], 6.76);
    // JSON written before the field existed still parses (to an empty list).
    let mut old: serde_json::Value = serde_json::from_str(&text).unwrap();
    old.as_object_mut().unwrap().remove("worst_polygons");
    let back = SolveReport::from_json(&old.to_string()).unwrap();
    assert!(back.worst_polygons.is_empty());
    assert_eq!(v["links"], 56789);
    assert_eq!(v["budget_limited"], true);
    assert_eq!(SolveReport::from_json(&text).unwrap(), r);
}

#[test]
fn json_file_is_written_atomically() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("stats.json");
    report().write_json(&path).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert_eq!(SolveReport::from_json(&text).unwrap(), report());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn summary_names_settings_cost_and_error() {
    let mut r = report();
    let mut out = Vec::new();
    r.print_summary(&mut out).unwrap();
    let text = String::from_utf8(out).unwrap();
    for word in [
        "method hr",
        "epsilon 0.001",
        "4 threads",
        "64.0 MiB",
        "time 1.500 s",
        "peak memory 3.0 MiB",
        "1234 elements",
        "56789 links",
        "budget limited",
        "accuracy: not measured",
    ] {
        assert!(text.contains(word), "`{word}` missing in {text}");
    }
    r.error_percent = Some(0.5);
    r.error_per_band_percent = vec![0.25, 0.75];
    let mut out = Vec::new();
    r.print_summary(&mut out).unwrap();
    let text = String::from_utf8(out).unwrap();
    assert!(text.contains("error 0.5000 %"), "{text}");
    assert!(text.contains("per band 0.2500, 0.7500 %"), "{text}");
}

#[test]
fn byte_counts() {
    assert_eq!(bytes(0), "0 B");
    assert_eq!(bytes(1023), "1023 B");
    assert_eq!(bytes(1536), "1.5 KiB");
    assert_eq!(bytes(5 << 30), "5.0 GiB");
}
