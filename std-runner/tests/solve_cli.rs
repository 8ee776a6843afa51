//! `hirad solve` end to end: the image shows the scene, results are identical for any thread
//! count, the reference error is printed, stats are complete, bad options are refused.

mod common;

use common::{fails, fixture, hirad, ok, s};

/// Mean of a channel over a block of pixels.
fn mean(f: &hirad::output::Frame, ch: usize, x0: u32, y0: u32, w: u32, h: u32) -> f32 {
    let mut sum = 0.0;
    for y in y0..y0 + h {
        for x in x0..x0 + w {
            sum += f.pixel(x, y)[ch];
        }
    }
    sum / (w * h) as f32
}

#[test]
fn the_cornell_box_image_shows_the_scene() {
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("box.exr");
    ok(&[
        "solve",
        "-q",
        s(&fixture("cornell_box.hir")),
        "--image",
        s(&exr),
        "--size",
        "128x128",
    ]);
    let f = hirad::output::read_exr(&exr).unwrap();
    assert_eq!((f.width, f.height), (128, 128));
    let (r, g, b) = (
        f.channel("R").unwrap(),
        f.channel("G").unwrap(),
        f.channel("B").unwrap(),
    );
    // The classic camera looks into the open side: light at the top centre, red wall on the
    // left, green wall on the right, white back wall in the middle.
    let light = (0..128 * 20)
        .map(|i| f.pixel(i % 128, i / 128)[r])
        .fold(0.0f32, f32::max);
    let left = [
        mean(&f, r, 4, 50, 8, 20),
        mean(&f, g, 4, 50, 8, 20),
        mean(&f, b, 4, 50, 8, 20),
    ];
    let right = [
        mean(&f, r, 116, 50, 8, 20),
        mean(&f, g, 116, 50, 8, 20),
        mean(&f, b, 116, 50, 8, 20),
    ];
    let back = mean(&f, r, 56, 30, 16, 10);
    assert!(
        left[0] > 2.0 * left[1] && left[0] > 2.0 * left[2],
        "left wall is red: {left:?}"
    );
    assert!(
        right[1] > 1.5 * right[0] && right[1] > 1.5 * right[2],
        "right wall is green: {right:?}"
    );
    assert!(back > 0.0 && left[0] > 0.0 && right[1] > 0.0);
    assert!(
        light > 10.0 * back.max(left[0]).max(right[1]),
        "the light ({light}) is far brighter than the walls"
    );
    assert!(
        (light - 53.4 / std::f32::consts::PI).abs() < 1.0,
        "light radiance is B/pi: {light}"
    );
}

#[test]
fn identical_bytes_with_one_and_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for scene in ["cornell_box.hir", "small_plant.hir", "chair_room.hir"] {
        let mut files = Vec::new();
        for t in ["1", "2"] {
            let csv = d.join(format!("{scene}.{t}.csv"));
            let exr = d.join(format!("{scene}.{t}.exr"));
            ok(&[
                "solve",
                "-q",
                s(&fixture(scene)),
                "--threads",
                t,
                "--results",
                s(&csv),
                "--image",
                s(&exr),
                "--size",
                "64x48",
            ]);
            files.push((std::fs::read(&csv).unwrap(), std::fs::read(&exr).unwrap()));
        }
        assert!(
            files[0].0 == files[1].0,
            "{scene}: results differ between 1 and 2 threads"
        );
        assert!(
            files[0].1 == files[1].1,
            "{scene}: images differ between 1 and 2 threads"
        );
    }
}

#[test]
fn reference_error_and_stats() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let exact = d.join("exact.csv");
    ok(&[
        "solve",
        "-q",
        s(&fixture("parallel_squares.hir")),
        "--method",
        "exact",
        "--results",
        s(&exact),
    ]);
    let table = std::fs::read_to_string(&exact).unwrap();
    assert!(
        table.starts_with("id,area_m2,rad_0_W_m2,irr_0_W_m2,material,group\n"),
        "{table}"
    );
    let stats = d.join("stats.json");
    let out = ok(&[
        "solve",
        "-q",
        s(&fixture("parallel_squares.hir")),
        "--reference",
        s(&exact),
        "--stats",
        s(&stats),
    ]);
    assert!(out.starts_with("error "), "{out}");
    let pct: f64 = out.split_whitespace().nth(1).unwrap().parse().unwrap();
    assert!(pct < 1.0, "{out}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    for key in [
        "method",
        "epsilon",
        "threads",
        "polygons",
        "elements",
        "links",
        "iterations",
        "seconds",
        "peak_workspace_bytes",
        "budget_limited",
        "error_percent",
    ] {
        assert!(json.get(key).is_some(), "stats lack {key}: {json}");
    }
    assert_eq!(json["method"], "hr");
    assert_eq!(json["polygons"], 2);
    assert_eq!(json["epsilon"], 0.001);
    assert!((json["error_percent"].as_f64().unwrap() - pct).abs() < 1e-3);
    // The price per phase: named, in the order they first ran, adding up to the run's time
    // (the rest is reading the scene and writing the report), and the rays cast.
    let phases = json["phases"].as_array().expect("phases");
    let names: Vec<&str> = phases
        .iter()
        .map(|p| p["phase"].as_str().unwrap())
        .collect();
    for want in [
        "setup",
        "lighting patches",
        "evaluating links",
        "solving",
        "final gather: relighting patches",
        "final gather: polygons and output",
    ] {
        assert!(names.contains(&want), "no phase {want}: {names:?}");
    }
    assert_eq!(names[0], "setup");
    let sum: f64 = phases.iter().map(|p| p["seconds"].as_f64().unwrap()).sum();
    let total = json["seconds"].as_f64().unwrap();
    assert!(sum > 0.0 && sum <= total, "phases {sum} s of {total} s");
    assert!(json["rays"].as_u64().unwrap() > 0, "{json}");
}

#[test]
fn the_budget_shows_in_the_summary() {
    let err = String::from_utf8(
        hirad(&[
            "solve",
            s(&fixture("cornell_box.hir")),
            "--epsilon",
            "1e-5",
            "--memory",
            "300K",
        ])
        .stderr,
    )
    .unwrap();
    assert!(
        err.contains("budget limited") || err.contains("limited refinement"),
        "{err}"
    );
}

#[test]
fn bad_options_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let box_ = fixture("cornell_box.hir");
    assert!(fails(&["solve", s(&box_), "--epsilon", "0"]).contains("--epsilon"));
    assert!(fails(&["solve", s(&box_), "--epsilon", "nan"]).contains("--epsilon"));
    // Counts out of range are usage errors (status 2), named with their range.
    for (opt, bad) in [
        ("--threads", "0"),
        ("--rays", "0"),
        ("--max-iterations", "0"),
    ] {
        let out = hirad(&["solve", s(&box_), opt, bad]);
        let e = String::from_utf8(out.stderr).unwrap();
        assert_eq!(out.status.code(), Some(2), "{opt} {bad}: {e}");
        assert!(
            e.contains(opt) && e.contains("is not in"),
            "{opt} {bad}: {e}"
        );
    }
    for (opt, bad) in [
        ("--final-rays", "lots"),
        ("--final-rays", "2000000"),
        ("--final-rays", "1.5"),
        ("--final-passes", "0"),
        ("--final-passes", "5"),
        ("--final-passes", "many"),
    ] {
        let out = hirad(&["solve", s(&box_), opt, bad]);
        let e = String::from_utf8(out.stderr).unwrap();
        assert_eq!(out.status.code(), Some(2), "{opt} {bad}: {e}");
        assert!(e.contains(opt) && e.contains("auto"), "{opt} {bad}: {e}");
    }
    assert!(fails(&["solve", s(&box_), "--memory", "1K"]).contains("needs"));
    assert!(fails(&["solve", s(&box_), "--memory", "9000T"]).contains("cannot allocate"));
    let e = String::from_utf8(hirad(&["solve", s(&box_), "--memory", "lots"]).stderr).unwrap();
    assert!(e.contains("not a size"), "{e}");
    assert!(fails(&["solve", s(&box_), "--image", s(&d.join("x.bmp"))]).contains("x.bmp"));
    assert!(
        fails(&[
            "solve",
            s(&box_),
            "--image",
            s(&d.join("x.png")),
            "--camera",
            "1,2,3"
        ])
        .contains("--camera")
    );
    assert!(
        fails(&[
            "solve",
            s(&box_),
            "--image",
            s(&d.join("x.png")),
            "--size",
            "0x10"
        ])
        .contains("--size")
    );
    assert!(
        fails(&["solve", s(&box_), "--reference", s(&d.join("none.csv"))]).contains("none.csv")
    );
    // A reference of another scene.
    let other = d.join("other.csv");
    ok(&[
        "solve",
        "-q",
        s(&fixture("parallel_squares.hir")),
        "--results",
        s(&other),
    ]);
    assert!(fails(&["solve", s(&box_), "--reference", s(&other)]).contains("polygons"));
    // Nothing was left behind by the failed runs.
    let left: Vec<_> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left, ["other.csv"]);
}

#[test]
fn reference_names_the_five_worst_polygons() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let box_ = fixture("cornell_box.hir");
    let solution = d.join("solution.csv");
    ok(&["solve", "-q", s(&box_), "--results", s(&solution)]);
    // The reference: the box's own solution (solves are deterministic) with seven values
    // changed so that the result is off by known fractions there.
    let text = std::fs::read_to_string(&solution).unwrap();
    let mut rows: Vec<Vec<String>> = text
        .lines()
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    assert_eq!(
        &rows[0][..5],
        [
            "id",
            "area_m2",
            "rad_red_W_m2",
            "rad_green_W_m2",
            "rad_blue_W_m2"
        ]
    );
    // (id, band, relative error of the result): the sixth is not among the five, and the
    // seventh is a dark column (below 0.1% of the largest radiosity, the light's) whose
    // relative error does not count.
    let off = [
        (2u64, 1usize, 0.10),
        (5, 0, -0.40),
        (0, 0, 0.50),
        (14, 1, 0.30),
        (12, 0, -0.20),
        (7, 2, 0.05),
        (9, 2, 10.0),
    ];
    let max = rows[1..]
        .iter()
        .flat_map(|r| r[2..5].iter().map(|v| v.parse::<f32>().unwrap()))
        .fold(0.0f32, f32::max);
    for &(id, band, e) in &off {
        let row = &mut rows[1 + id as usize];
        assert_eq!(row[0], id.to_string());
        let got: f32 = row[2 + band].parse().unwrap();
        // Well above the floor, or well below it for the dark one.
        let reference = f64::from(got) / (1.0 + e);
        let floor = 1e-3 * f64::from(max);
        assert!(
            if e > 1.0 {
                reference < 0.5 * floor
            } else {
                reference > 2.0 * floor
            },
            "polygon {id} band {band}: {got} of {max}"
        );
        row[2 + band] = format!("{}", (f64::from(got) / (1.0 + e)) as f32);
    }
    let reference = d.join("reference.csv");
    let table: Vec<String> = rows.iter().map(|r| r.join(",")).collect();
    std::fs::write(&reference, table.join("\n") + "\n").unwrap();
    let stats = d.join("stats.json");
    let out = ok(&[
        "solve",
        "-q",
        s(&box_),
        "--reference",
        s(&reference),
        "--stats",
        s(&stats),
    ]);
    let lines: Vec<&str> = out.lines().collect();
    assert!(lines[0].starts_with("error "), "{out}");
    assert!(
        lines[1].starts_with(
            "worst polygons (relative error of radiosity, where the reference is at least 0.1% \
             of its largest, "
        ),
        "{out}"
    );
    assert_eq!(lines.len(), 7, "{out}");
    let names = ["red", "green", "blue"];
    let want = [
        (0u64, 0usize, 50.0),
        (5, 0, -40.0),
        (14, 1, 30.0),
        (12, 0, -20.0),
        (2, 1, 10.0),
    ];
    for (line, &(id, band, pct)) in lines[2..].iter().zip(&want) {
        let head = format!("  id {id} front band {band} ({}): reference ", names[band]);
        assert!(
            line.starts_with(&head),
            "{line:?} should start with {head:?}\n{out}"
        );
        let printed: f64 = line
            .rsplit(", ")
            .next()
            .and_then(|p| p.strip_suffix(" %"))
            .unwrap()
            .parse()
            .unwrap();
        assert!((printed - pct).abs() < 0.015, "{line}");
        assert!(
            line.contains(if pct > 0.0 { ", +" } else { ", -" }),
            "{line}"
        );
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    let worst = json["worst_polygons"].as_array().unwrap();
    assert_eq!(worst.len(), 5, "{json}");
    for (w, &(id, band, pct)) in worst.iter().zip(&want) {
        assert_eq!(w["id"], id);
        assert_eq!(w["band"], band);
        assert_eq!(w["back"], false);
        let got = w["relative_error_percent"].as_f64().unwrap();
        assert!((got - pct).abs() < 1e-3, "{w}");
        let (r, g) = (
            w["reference"].as_f64().unwrap(),
            w["result"].as_f64().unwrap(),
        );
        assert!((100.0 * (g - r) / r - got).abs() < 1e-4, "{w}");
    }
}

#[test]
fn power_and_convergence_are_reported_and_a_capped_solve_fails() {
    let dir = tempfile::tempdir().unwrap();
    let stats = dir.path().join("s.json");
    let results = dir.path().join("r.csv");
    // A converged solve: the summary and the stats carry where the power went.
    let out = hirad(&[
        "solve",
        s(&fixture("small_plant.hir")),
        "--stats",
        s(&stats),
    ]);
    assert!(out.status.success());
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(
        err.contains("power (W)") && err.contains("par: in ") && err.contains("imbalance"),
        "{err}"
    );
    assert!(
        err.contains("converged (estimated change still to come"),
        "{err}"
    );
    let report =
        hirad::output::SolveReport::from_json(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    assert!(report.converged);
    assert_eq!(report.power.len(), 2);
    assert_eq!(report.power[0].band, "par");
    for p in &report.power {
        assert!(
            p.direct > 0.0 && p.absorbed > 0.0 && p.escaped > 0.0,
            "{p:?}"
        );
        assert!(p.imbalance_percent.abs() < 2.0, "{p:?}");
    }
    // Stopped at the iteration cap: outputs written, converged false, a non-zero exit that
    // says so.
    let err = fails(&[
        "solve",
        "-q",
        s(&fixture("furnace_099.hir")),
        "--max-iterations",
        "6",
        "--stats",
        s(&stats),
        "--results",
        s(&results),
    ]);
    assert!(
        err.contains("did not converge within 6 iterations"),
        "{err}"
    );
    assert!(results.exists());
    let report =
        hirad::output::SolveReport::from_json(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    assert!(!report.converged);
    assert!(
        report.remaining_change.is_some_and(|r| r > 0.0),
        "{:?}",
        report.remaining_change
    );
    // A solve whose power does not balance within --max-imbalance writes its outputs and
    // fails, naming the band and how much light the transport lost; within it, it succeeds
    // (without the final gather the room loses a few percent through its cluster links at
    // the default epsilon: a warning above 1%).
    std::fs::remove_file(&results).unwrap();
    let err = fails(&[
        "solve",
        "-q",
        s(&fixture("chair_room.hir")),
        "--final-rays",
        "0",
        "--max-imbalance",
        "0.5",
        "--results",
        s(&results),
    ]);
    assert!(
        err.contains("the power balance is off by +") && err.contains("above --max-imbalance 0.5%"),
        "{err}"
    );
    assert!(results.exists());
    let out = hirad(&[
        "solve",
        s(&fixture("chair_room.hir")),
        "--final-rays",
        "0",
        "--max-imbalance",
        "50",
    ]);
    assert!(out.status.success());
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(
        err.contains("warning: the power balance is off by"),
        "{err}"
    );
    // A limit below the 1% warning is enforced too (with the final gather the room is
    // within 1%, but not within 0.01%).
    let err = fails(&[
        "solve",
        "-q",
        s(&fixture("chair_room.hir")),
        "--max-imbalance",
        "0.01",
    ]);
    assert!(err.contains("above --max-imbalance 0.01%"), "{err}");
    let err = fails(&["solve", s(&fixture("chair_room.hir")), "--max-imbalance=-1"]);
    assert!(err.contains("--max-imbalance must be"), "{err}");
    // A closed lossless room with a lamp is refused before any work, with the reason.
    let lossless = dir.path().join("lossless.hir");
    std::fs::write(
        &lossless,
        std::fs::read_to_string(fixture("furnace.hir"))
            .unwrap()
            .replace("rho 0.5 emit 1", "rho 1 emit 1"),
    )
    .unwrap();
    let err = fails(&["solve", "-q", s(&lossless)]);
    assert!(err.contains("no steady state in band 0"), "{err}");
}

#[cfg(unix)]
#[test]
fn an_output_that_is_a_pipe_or_device_is_written_into_not_replaced() {
    use std::os::unix::fs::FileTypeExt;
    // `--results /dev/null` used to rename a file over the device: as root, /dev/null became
    // a regular file for every program on the machine. A FIFO stands in for it here.
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("results.fifo");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap();
    assert!(made.success());
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read_to_string(&fifo).unwrap())
    };
    let out = hirad(&[
        "solve",
        "-q",
        s(&fixture("parallel_squares.hir")),
        "--results",
        s(&fifo),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = reader.join().unwrap();
    assert!(text.starts_with("id,area_m2,"), "{text}");
    assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
}
