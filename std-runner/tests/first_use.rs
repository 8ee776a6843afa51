//! A new user's first hour (issue 9), through the `hirad` binary: messages, values, help,
//! outputs that are never lost or clobbered, face numbers, progress. One test (or more) per
//! item of the issue; the pictures (items 1 and 9) are in `first_use_pictures.rs`.

mod common;
use common::{canopy, fails, fixture, hirad, ok, s, write};

/// Item 2: a run that succeeded says no line that starts with "error:".
#[test]
fn a_successful_run_reports_no_error() {
    let dir = tempfile::tempdir().unwrap();
    let results = dir.path().join("r.csv");
    let out = hirad(&[
        "solve",
        s(&fixture("cornell_box.hir")),
        "--results",
        s(&results),
    ]);
    assert!(out.status.success());
    let text =
        String::from_utf8_lossy(&out.stderr).to_string() + &String::from_utf8_lossy(&out.stdout);
    for line in text.lines() {
        assert!(
            !line.trim_start().starts_with("error"),
            "a successful run printed {line:?}:\n{text}"
        );
    }
}

/// Item 6: messages that say what is wrong.
#[test]
fn messages_name_the_real_problem() {
    let dir = tempfile::tempdir().unwrap();
    // A face-less OBJ, and one whose only face is degenerate.
    let empty = write(dir.path(), "empty.obj", "v 0 0 0\nv 1 0 0\n");
    let err = fails(&["solve", s(&empty)]);
    assert!(
        err.contains("has no polygons") && !err.contains("scratch"),
        "{err}"
    );
    let degenerate = write(
        dir.path(),
        "flat.obj",
        "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n",
    );
    let err = fails(&["solve", s(&degenerate)]);
    assert!(
        err.contains("no usable polygons (1 face skipped") && !err.contains("scratch"),
        "{err}"
    );
    // 10,000 skipped faces: the count of those not shown is right.
    let mut text = String::from("v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\n");
    for _ in 0..10_000 {
        text.push_str("f 1 2 3\n");
    }
    text.push_str("f 1 2 4\n");
    let many = write(dir.path(), "many.obj", &text);
    let out = hirad(&["info", s(&many)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("... and 9980 more warnings (10000 in all)"),
        "{err}"
    );
    // `info` says what its two polygon counts mean.
    let info = ok(&["info", s(&fixture("chair_room.hir"))]);
    assert!(info.contains("every instance expanded"), "{info}");
    assert!(info.contains("in the file"), "{info}");
    // A directory given as a scene.
    let d = dir.path().join("scene.hirb");
    std::fs::create_dir(&d).unwrap();
    for cmd in ["info", "solve"] {
        let err = fails(&[cmd, s(&d)]);
        assert!(
            err.contains("is a directory, not a scene file") && !err.contains("error code"),
            "{cmd}: {err}"
        );
    }
}

/// Item 5: absurd values are refused, or warned about, in the option's own words.
#[test]
fn absurd_values_get_a_clear_answer() {
    let cornell = fixture("cornell_box.hir");
    let scene = s(&cornell);
    let dir = tempfile::tempdir().unwrap();
    let err = |args: &[&str]| {
        let out = hirad(args);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(
            out.status.code() == Some(2),
            "{args:?}: status {:?}",
            out.status
        );
        String::from_utf8_lossy(&out.stderr).to_string()
    };
    // 100,000 threads aborted the process (status 134) setting up their stacks.
    let e = err(&["solve", scene, "--threads", "100000", "-q"]);
    assert!(e.contains("--threads") && e.contains("1..=1024"), "{e}");
    // A negative value meets the option's own check, not clap's advice to write `-- -1`.
    for (args, want) in [
        (
            vec!["solve", scene, "--epsilon", "-1"],
            "--epsilon must be a positive number",
        ),
        (
            vec!["solve", scene, "--tolerance", "-1e-3"],
            "--tolerance must be a positive number",
        ),
        (
            vec!["solve", scene, "--rays", "-3"],
            "-3 is not in 1..=1024",
        ),
        (
            vec!["solve", scene, "--threads", "-2"],
            "-2 is not in 1..=1024",
        ),
        (
            vec!["gen", "canopy", "--rows", "-1", "-o", "x.hirb"],
            "-1 is not in",
        ),
    ] {
        let e = err(&args);
        assert!(e.contains(want) && !e.contains("-- -"), "{args:?}: {e}");
    }
    // --size names itself once.
    let png = dir.path().join("x.png");
    let e = err(&["solve", scene, "--size", "0x0", "--image", s(&png), "-q"]);
    assert!(
        e.contains("--size: width `0`") && !e.contains("--size: --size"),
        "{e}"
    );
    assert!(!png.exists());
    // Image options without --image, and an epsilon that refines nothing, are said.
    let out = hirad(&[
        "solve",
        scene,
        "--size",
        "100x100",
        "--camera",
        "0.3,0.3,-1,0.3,0.3,0,0,1,0,40",
        "--supersample",
        "2",
    ]);
    let e = String::from_utf8_lossy(&out.stderr);
    for name in ["--size", "--camera", "--supersample"] {
        assert!(
            e.contains(&format!("warning: {name} has no effect without --image")),
            "{e}"
        );
    }
    let out = hirad(&["solve", scene, "--epsilon", "1e9", "--max-imbalance", "100"]);
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(e.contains("nothing is refined"), "{e}");
}

/// Item 10: every command's help ends with real examples; `hirad --help` lists the commands
/// one line each and points to the documentation.
#[test]
fn every_help_ends_with_examples() {
    let commands: &[&[&str]] = &[
        &[],
        &["info"],
        &["convert"],
        &["flatten"],
        &["solve"],
        &["gen"],
        &["gen", "poplar"],
        &["gen", "stand"],
        &["gen", "room"],
        &["gen", "forest"],
        &["gen", "canopy"],
    ];
    let names = ["info", "convert", "flatten", "solve", "gen"];
    for cmd in commands {
        let mut args = cmd.to_vec();
        args.push("--help");
        let help = ok(&args);
        let tail = &help[help
            .rfind("Examples:")
            .unwrap_or_else(|| panic!("{cmd:?}: no examples:\n{help}"))..];
        let examples: Vec<&str> = tail
            .lines()
            .skip(1)
            .filter(|l| !l.trim().is_empty())
            .collect();
        assert!(
            (2..=3).contains(&examples.len()),
            "{cmd:?}: {} example lines:\n{tail}",
            examples.len()
        );
        for e in &examples {
            let words: Vec<&str> = e.split_whitespace().collect();
            assert_eq!(words[0], "hirad", "{cmd:?}: {e}");
            assert!(names.contains(&words[1]), "{cmd:?}: no command in {e}");
            if !cmd.is_empty() {
                assert_eq!(
                    words[1], cmd[0],
                    "{cmd:?}: an example of another command: {e}"
                );
            }
        }
    }
    let top = ok(&["--help"]);
    assert!(top.contains("docs/") && top.contains("README.md"), "{top}");
    let list = &top[top.find("Commands:").unwrap()..top.find("Options:").unwrap()];
    for line in list.lines().skip(1).filter(|l| !l.trim().is_empty()) {
        assert!(line.len() <= 90, "a command's line is too long: {line:?}");
    }
    // The examples run: an info of a fixture, as its help shows.
    let info = ok(&["info", s(&fixture("chair_room.hir"))]);
    assert!(info.contains("polygons"));
}

/// Item 4: outputs are checked before any work: none may be a file the run reads, no two
/// may be the same file, and each must be writable where it is. Nothing is written then.
#[test]
fn outputs_never_clobber_inputs_or_each_other() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = d.join("scene.hir");
    std::fs::copy(fixture("cornell_box.hir"), &scene).unwrap();
    let original = std::fs::read(&scene).unwrap();
    let obj = d.join("cube.obj");
    std::fs::copy(fixture("obj/cube.obj"), &obj).unwrap();
    std::fs::copy(fixture("obj/cube.mtl"), d.join("cube.mtl")).unwrap();
    let reference = d.join("ref.csv");
    ok(&["solve", s(&scene), "--results", s(&reference), "-q"]);
    let p = |name: &str| d.join(name);
    let c = |args: &[&str], want: &'static str| -> (Vec<String>, &'static str) {
        (args.iter().map(|a| a.to_string()).collect(), want)
    };
    let (sc, ob, rf) = (s(&scene), s(&obj), s(&reference));
    let reads = "a file the run reads";
    let (same, absent) = ("name the same file", "does not exist");
    let (a, x, r) = (p("a.png"), p("x.json"), p("r.csv"));
    let (a_png, x_json, r_csv) = (s(&a), s(&x), s(&r));
    let x_json_too = format!("{}/./x.json", d.display());
    let (mp, mj, mh) = (p("nodir/x.png"), p("nodir/x.json"), p("nodir/room.hirb"));
    let (missing_png, missing_json, missing_hirb) = (s(&mp), s(&mj), s(&mh));
    let cases = [
        // The scene itself, the OBJ's material library, the reference.
        c(&["solve", sc, "--results", sc], reads),
        c(&["solve", sc, "--stats", sc], reads),
        c(&["solve", ob, "--image", s(&p("cube.mtl"))], reads),
        c(&["solve", sc, "--reference", rf, "--results", rf], reads),
        c(&["convert", sc, "-o", sc], reads),
        c(&["flatten", ob, "-o", ob], reads),
        // One output over another.
        c(&["solve", sc, "--results", a_png, "--image", a_png], same),
        c(
            &["solve", sc, "--results", x_json, "--stats", &x_json_too],
            same,
        ),
        // Folders that are not there, found before the solve.
        c(
            &["solve", sc, "--results", r_csv, "--image", missing_png],
            absent,
        ),
        c(
            &["solve", sc, "--results", r_csv, "--stats", missing_json],
            absent,
        ),
        c(&["gen", "room", "-o", missing_hirb], absent),
        c(&["solve", sc, "--results", s(d)], "is a directory"),
    ];
    for (args, want) in &cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let err = fails(&args);
        assert!(err.contains(want), "{args:?}: {err}");
    }
    assert_eq!(
        std::fs::read(&scene).unwrap(),
        original,
        "the scene was touched"
    );
    let mut left: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(
        left,
        ["cube.mtl", "cube.obj", "ref.csv", "scene.hir"],
        "files left behind"
    );
    // A device may take several outputs: it is written into, not replaced.
    ok(&[
        "solve",
        s(&scene),
        "--results",
        "/dev/null",
        "--stats",
        "/dev/null",
        "-q",
    ]);
}

/// Item 3: SIGINT or SIGTERM at any moment of a solve leaves no file but those there before
/// (an older results table among them, untouched), exits with 130 or 143, and says which
/// outputs were not written.
#[cfg(unix)]
#[test]
fn an_interrupted_solve_leaves_nothing_behind() {
    use std::process::{Command, Stdio};
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = canopy(d, 6, 10);
    let old = d.join("r.csv");
    std::fs::write(&old, "an older table\n").unwrap();
    let listing = || {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    };
    let before = listing();
    for (signal, after_ms, status) in [
        ("-INT", 50, 130),
        ("-INT", 400, 130),
        ("-INT", 1500, 130),
        ("-TERM", 800, 143),
        ("-INT", 3000, 130),
    ] {
        let child = Command::new(env!("CARGO_BIN_EXE_hirad"))
            .args([
                "solve",
                s(&scene),
                "--results",
                s(&old),
                "--image",
                s(&d.join("i.png")),
                "--stats",
                s(&d.join("s.json")),
                "-q",
            ])
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        std::thread::sleep(std::time::Duration::from_millis(after_ms));
        let _ = Command::new("kill")
            .args([signal, &child.id().to_string()])
            .status();
        let out = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        if out.status.success() {
            // Finished before the signal: every output is complete.
            assert!(d.join("i.png").exists() && d.join("s.json").exists());
            break;
        }
        assert_eq!(
            out.status.code(),
            Some(status),
            "{signal} after {after_ms} ms: {err}"
        );
        assert!(
            err.contains("interrupted by SIG")
                && err.contains("not written:")
                && err.contains("r.csv"),
            "{signal} after {after_ms} ms: {err}"
        );
        assert_eq!(listing(), before, "{signal} after {after_ms} ms left files");
        assert_eq!(std::fs::read_to_string(&old).unwrap(), "an older table\n");
    }
}

/// Item 7: when an OBJ's faces are skipped or split, the results keep each polygon's face
/// number, so a user's own table joins by it; and such a table reads back as a reference.
#[test]
fn results_keep_the_obj_face_number() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(
        d,
        "m.mtl",
        "newmtl lamp\nKd 0 0 0\nKe 10 10 10\nnewmtl grey\nKd 0.5 0.5 0.5\n",
    );
    // Face 1: a lamp facing down; face 2: a triangle; face 3: degenerate (skipped); face 4:
    // a concave pentagon (split in three); face 5: a quad.
    let obj = write(
        d,
        "m.obj",
        "mtllib m.mtl\nusemtl lamp\n\
         v 0 0 2\nv 1 0 2\nv 1 1 2\nv 0 1 2\n\
         f 4 3 2 1\n\
         usemtl grey\n\
         v 0 0 0\nv 3 0 0\nv 3 3 0\n\
         f 5 6 7\n\
         f 5 6 5\n\
         v 4 0 0\nv 8 0 0\nv 8 4 0\nv 6 1 0\nv 4 4 0\n\
         f 8 9 10 11 12\n\
         v 0 5 0\nv 3 5 0\nv 3 8 0\nv 0 8 0\n\
         f 13 14 15 16\n",
    );
    let csv = d.join("r.csv");
    let out = hirad(&["solve", s(&obj), "--results", s(&csv), "-q"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let at = header
        .iter()
        .position(|&c| c == "face")
        .expect("a face column");
    let faces: Vec<u64> = lines
        .map(|l| l.split(',').nth(at).unwrap().parse().unwrap())
        .collect();
    let pentagon = faces.iter().filter(|&&f| f == 4).count();
    assert!(pentagon >= 2, "the pentagon was not split: {faces:?}");
    let mut want = vec![1, 2];
    want.extend(std::iter::repeat_n(4, pentagon));
    want.push(5);
    assert_eq!(faces, want, "face numbers of the rows");
    // The table, face column and all, is a reference.
    let e = ok(&["solve", s(&obj), "--reference", s(&csv), "-q"]);
    assert!(e.contains("error 0.0000 %"), "{e}");
    // hirad's own scenes have no face numbers: no column.
    let hir = d.join("h.csv");
    ok(&[
        "solve",
        s(&fixture("cornell_box.hir")),
        "--results",
        s(&hir),
        "-q",
    ]);
    let h = std::fs::read_to_string(&hir).unwrap();
    assert!(!h.lines().next().unwrap().contains("face"));
}

/// Runs `hirad args` drawing every progress update (`HIRAD_PROGRESS=every`, terminal or
/// not) and checks that every phase with a total runs from its first count to all of it
/// without stepping back or changing its total; returns each stretch of one label with its
/// counts, in order.
fn progress_of(args: &[&str]) -> Vec<(String, Vec<u64>)> {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_hirad"))
        .args(args)
        .env("HIRAD_PROGRESS", "every")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let lines: Vec<&str> = err
        .split(['\r', '\n'])
        .map(|l| l.trim_start_matches("\x1b[2K"))
        .filter(|l| l.contains(" s") && (l.contains('[') || l.contains("): ")))
        .collect();
    // (label, done, total) of every drawn line, in order.
    let parse = |l: &str| -> (String, u64, Option<u64>) {
        if let Some(at) = l.find(" [") {
            let rest = &l[at + 2..];
            let counts = rest.split("] ").nth(1).unwrap().split(' ').next().unwrap();
            let (d, t) = counts.split_once('/').unwrap();
            (
                l[..at].to_string(),
                d.parse().unwrap(),
                Some(t.parse().unwrap()),
            )
        } else {
            let (label, rest) = l.split_once("): ").unwrap();
            let d = rest.split(',').next().unwrap().parse().unwrap();
            (format!("{label})"), d, None)
        }
    };
    let parsed: Vec<_> = lines.iter().map(|l| parse(l)).collect();
    let mut stretches = Vec::new();
    let mut i = 0;
    while i < parsed.len() {
        let label = &parsed[i].0;
        let mut j = i;
        while j < parsed.len() && &parsed[j].0 == label {
            j += 1;
        }
        let run = &parsed[i..j];
        for w in run.windows(2) {
            assert!(
                w[1].1 >= w[0].1,
                "{label} went back: {} -> {}",
                w[0].1,
                w[1].1
            );
            assert_eq!(w[1].2, w[0].2, "{label} changed its total");
        }
        let last = run.last().unwrap();
        if let Some(total) = last.2 {
            assert_eq!(last.1, total, "{label} ended at {}/{total}", last.1);
        }
        stretches.push((label.clone(), run.iter().map(|r| r.1).collect()));
        i = j;
    }
    stretches
}

/// Item 8: the progress line moves forward and ends at 100% (see [`progress_of`]), the
/// phases that each refinement pass runs again are named with their pass, open counts only
/// grow, and the load shows every polygon loaded. The exact solver's long phase, its form
/// factors, counts its elements (it showed one line that never moved).
#[test]
fn progress_moves_forward_to_the_end() {
    let dir = tempfile::tempdir().unwrap();
    let scene = canopy(dir.path(), 2, 4);
    let stretches = progress_of(&["solve", s(&scene), "--max-imbalance", "100"]);
    assert!(stretches.len() > 10, "{stretches:?}");
    let last = |label: &str| -> Vec<u64> {
        stretches
            .iter()
            .filter(|(l, _)| l.ends_with(label))
            .map(|(_, counts)| *counts.last().unwrap())
            .collect()
    };
    let refining = last("refining (links)");
    assert!(
        !refining.is_empty() && refining.iter().all(|&n| n > 0),
        "refining counts {refining:?}"
    );
    assert!(last("loaded (polygons)").iter().all(|&n| n > 0));
    assert!(
        stretches.iter().any(|(l, _)| l.starts_with("pass 2: ")),
        "passes are not named"
    );
    let iterations: Vec<u64> = stretches
        .iter()
        .filter(|(l, _)| l == "solving (iterations)")
        .flat_map(|(_, counts)| counts.iter().copied())
        .collect();
    assert!(
        iterations.windows(2).all(|w| w[1] >= w[0]) && iterations.last() > Some(&0),
        "iterations {iterations:?}"
    );
    let exact = progress_of(&[
        "solve",
        s(&fixture("cornell_box.hir")),
        "--method",
        "exact",
        "--elements",
        "300",
    ]);
    let labels: Vec<&str> = exact.iter().map(|(l, _)| l.as_str()).collect();
    assert!(
        labels.contains(&"form factors (elements)") && labels.contains(&"solving (iterations)"),
        "{exact:?}"
    );
    let ff = exact
        .iter()
        .find(|(l, _)| l == "form factors (elements)")
        .unwrap();
    assert!(*ff.1.last().unwrap() >= 250, "{exact:?}");
}
