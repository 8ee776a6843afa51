//! Every example of README.md and docs/*.md runs, warns of nothing and lights what it lights.
//!
//! The examples are read from the Markdown at test time. Conventions of the docs:
//!
//! * A fenced block whose info string carries `title=NAME` (```` ```hir title=first.hir ````)
//!   is a file: it is written to `NAME` in the working folder of that Markdown file before its
//!   commands run, and some command of the page must name it. A `hir`, `obj` or `mtl` block
//!   without a title fails the test (nothing would check it). Other blocks (grammar, output
//!   shown) are text.
//! * The command lines of `sh`, `bash` and `console` blocks run, in the order of the file, in
//!   one temporary folder per Markdown file that also holds a link `fixtures` to the
//!   repository's fixtures. In a `console` block only the lines after a `$ ` prompt are
//!   commands. `#` starts a comment, `\` at the end of a line continues it, `&&` and `;`
//!   separate commands, `NAME=VALUE` before a command sets its environment.
//! * Comments on the lines just before a fence mark its commands. `<!-- slow: REASON -->`:
//!   slow (over about 20 s): they are listed as skipped with the reason,
//!   and run only when `HIRAD_DOCS_SLOW=1`. `<!-- warns: TEXT -->` (repeatable): the docs say
//!   the commands print a warning containing TEXT, as `hirad flatten` does for what OBJ cannot
//!   hold; each such warning must appear.
//!
//! Which commands run ([`classify`]): `hirad ARGS` and `cargo run [...] -p hirad -- ARGS` run
//! the `hirad` this test was built with. Skipped by rule, and listed: any other `cargo`
//! command (`cargo test`, `cargo bench`, `cargo run --example ...`: they build or test the
//! workspace this test is part of), and repository scripts (`*.sh`: the gallery script builds
//! in release and runs for many minutes; it has its own `--quick` mode). Any other command is
//! a failure, so that a new kind of example cannot go unchecked.
//!
//! A command fails the test when it exits non-zero, when its stderr has a line containing
//! `warning` (other than those its `warns` marks name), and, for `hirad solve`, when nothing
//! is lit: the irradiance columns (`irr...`, whatever the bands are called) of its results
//! table are zero on every polygon. A solve without `--results` is given one in a side file
//! for this check.
//!
//! The test belongs to the `hirad` package, not to the root's `tests/`, because only the
//! package that owns the `hirad` binary gets `CARGO_BIN_EXE_hirad`. The test profile builds
//! hirad at opt-level 3, so the times it prints are close to a release build's.
//! `cargo test -p hirad --test docs_examples -- --nocapture` shows them and the skipped list.

mod docs_markdown;

use docs_markdown::{Run, blocks, classify, commands};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// Whether a results table lights nothing: every value of its irradiance columns (a header
/// starting with `irr`, whatever the band names) is zero. An error when it has none.
fn dark(csv: &str) -> Result<bool, String> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines
        .next()
        .ok_or("empty results table")?
        .split(',')
        .collect();
    let irr: Vec<usize> = (0..header.len())
        .filter(|&i| header[i].trim().starts_with("irr"))
        .collect();
    if irr.is_empty() {
        return Err(format!("no irradiance column in {header:?}"));
    }
    for line in lines {
        let fields: Vec<&str> = line.split(',').collect();
        for &i in &irr {
            let v: f64 = fields
                .get(i)
                .ok_or_else(|| format!("short row {line:?}"))?
                .trim()
                .parse()
                .map_err(|e| format!("{line:?}: {e}"))?;
            if v > 0.0 {
                return Ok(false);
            }
        }
    }
    Ok(true)
}

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Languages of fenced blocks that are files a command reads: each must have a title.
const SCENE_LANGS: [&str; 3] = ["hir", "obj", "mtl"];

/// The Markdown files with examples: README.md and docs/*.md.
fn markdown_files() -> Vec<PathBuf> {
    let mut files = vec![repo().join("README.md")];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(repo().join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    files.extend(docs);
    files
}

/// Runs `hirad args` in `dir` and checks it; `Err` says what is wrong. `warns`: texts of the
/// warnings the docs say it prints (each must appear; no other warning may).
fn check_hirad(
    dir: &Path,
    env: &[(String, String)],
    args: &[String],
    warns: &[String],
) -> Result<(), String> {
    let mut args = args.to_vec();
    let solve = args.first().is_some_and(|a| a == "solve");
    let results = if solve {
        match args.iter().position(|a| a == "--results") {
            Some(i) => args.get(i + 1).map(|r| dir.join(r)),
            None => {
                args.extend(["--results".into(), "docs-check-results.csv".into()]);
                Some(dir.join("docs-check-results.csv"))
            }
        }
    } else {
        None
    };
    let out = Command::new(env!("CARGO_BIN_EXE_hirad"))
        .args(&args)
        .envs(env.iter().map(|(k, v)| (k, v)))
        .env_remove("HIRAD_PROGRESS")
        .current_dir(dir)
        .output()
        .map_err(|e| format!("cannot run hirad: {e}"))?;
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        return Err(format!("failed ({}); stderr:\n{stderr}", out.status));
    }
    let warnings: Vec<&str> = stderr
        .lines()
        .filter(|l| l.to_lowercase().contains("warning"))
        .collect();
    let unexpected: Vec<&str> = warnings
        .iter()
        .copied()
        .filter(|l| !warns.iter().any(|w| l.contains(w.as_str())))
        .collect();
    if !unexpected.is_empty() {
        return Err(format!("warnings:\n{}", unexpected.join("\n")));
    }
    if let Some(w) = warns
        .iter()
        .find(|w| !warnings.iter().any(|l| l.contains(w.as_str())))
    {
        return Err(format!(
            "no warning containing {w:?} as the docs say; stderr:\n{stderr}"
        ));
    }
    if let Some(results) = results {
        let csv = std::fs::read_to_string(&results)
            .map_err(|e| format!("results {}: {e}", results.display()))?;
        if dark(&csv)? {
            return Err(format!(
                "nothing is lit: every irradiance in {} is zero; stderr:\n{stderr}",
                results.display()
            ));
        }
    }
    Ok(())
}

/// Runs the examples of one Markdown file; returns the failures and the skipped commands.
fn run_file(md: &Path, slow: bool) -> (Vec<String>, Vec<String>) {
    let name = md.strip_prefix(repo()).unwrap_or(md).display().to_string();
    let text = std::fs::read_to_string(md).unwrap();
    let (mut failures, mut skipped) = (Vec::new(), Vec::new());
    let blocks = match blocks(&text) {
        Ok(b) => b,
        Err(e) => return (vec![format!("{name}: {e}")], skipped),
    };
    let dir = tempfile::tempdir().unwrap();
    std::os::unix::fs::symlink(repo().join("fixtures"), dir.path().join("fixtures")).unwrap();
    for b in &blocks {
        if let Some(title) = &b.title {
            let path = dir.path().join(title);
            if path.exists() {
                failures.push(format!("{name}:{}: a second file named {title}", b.line));
            }
            std::fs::write(path, &b.text).unwrap();
        }
    }
    // Every scene block is a file that some command of the page uses.
    let words: Vec<String> = blocks
        .iter()
        .filter_map(|b| commands(b).ok().flatten())
        .flatten()
        .flat_map(|(_, w)| w)
        .collect();
    for b in &blocks {
        match (&b.title, SCENE_LANGS.contains(&b.lang.as_str())) {
            (None, true) => failures.push(format!(
                "{name}:{}: a {} block without title=NAME: nothing runs it",
                b.line, b.lang
            )),
            (Some(t), _) if !words.contains(t) => failures.push(format!(
                "{name}:{}: no command of the page uses {t}",
                b.line
            )),
            _ => {}
        }
    }
    for b in &blocks {
        let cmds = match commands(b) {
            Ok(Some(c)) => c,
            Ok(None) => continue,
            Err(e) => {
                failures.push(format!("{name}:{}: {e}", b.line));
                continue;
            }
        };
        for (env, words) in cmds {
            let shown = words.join(" ");
            let run = match classify(&words) {
                Ok(r) => r,
                Err(e) => {
                    failures.push(format!("{name}:{}: {e}", b.line));
                    continue;
                }
            };
            let args = match run {
                Run::Skip(why) => {
                    skipped.push(format!("{name}:{}: `{shown}`: {why}", b.line));
                    continue;
                }
                Run::Hirad(args) => args,
            };
            if let (Some(why), false) = (&b.slow, slow) {
                skipped.push(format!(
                    "{name}:{}: `{shown}`: slow ({why}); HIRAD_DOCS_SLOW=1 runs it",
                    b.line
                ));
                continue;
            }
            let start = Instant::now();
            let result = check_hirad(dir.path(), &env, &args, &b.warns);
            eprintln!(
                "{name}:{}: {:.1} s `{shown}`",
                b.line,
                start.elapsed().as_secs_f64()
            );
            if let Err(e) = result {
                failures.push(format!("{name}:{}: `{shown}`: {e}", b.line));
            }
        }
    }
    (failures, skipped)
}

#[test]
fn every_example_in_the_docs_runs() {
    let slow = std::env::var("HIRAD_DOCS_SLOW").is_ok_and(|v| v == "1");
    let (mut failures, mut skipped) = (Vec::new(), Vec::new());
    let mut ran_any = false;
    for md in markdown_files() {
        let (f, s) = run_file(&md, slow);
        ran_any |= !f.is_empty() || !s.is_empty();
        failures.extend(f);
        skipped.extend(s);
    }
    for s in &skipped {
        eprintln!("skipped {s}");
    }
    assert!(ran_any, "no examples found");
    assert!(
        failures.is_empty(),
        "{} failing examples:\n{}",
        failures.len(),
        failures.join("\n\n")
    );
}

#[test]
fn dark_reads_irradiance_columns_by_prefix() {
    assert!(dark("id,area,rad_0,irr_0\n0,1,100,0\n1,1,0,0\n").unwrap());
    assert!(!dark("id,area,rad_0,irr_0\n0,1,100,0\n1,1,0,2.5\n").unwrap());
    assert!(!dark("id,area,rad_par,rad_nir,irr_par,irr_nir\n0,1,0,0,0,1e-3\n").unwrap());
    assert!(
        dark("id,area,rad_0\n0,1,1\n").is_err(),
        "no irradiance column"
    );
}

/// The check catches a lamp that faces away from what it should light (the first example
/// of format.md once did): run on a scene written here, not on the docs.
#[test]
fn a_lamp_facing_away_is_dark() {
    let dir = tempfile::tempdir().unwrap();
    let scene = |lamp: &str| {
        format!(
            "hirad 1\nbands 1\nmaterial white rho 0.7\nmaterial lamp rho 0 emit 100\n\
             scene {{\n  quad white 0 0 0  1 0 0  1 1 0  0 1 0\n  tri lamp {lamp}\n}}\n"
        )
    };
    let args = |f: &str| vec!["solve".to_string(), f.to_string()];
    std::fs::write(dir.path().join("up.hir"), scene("0 0 2  1 0 2  0 1 2")).unwrap();
    std::fs::write(dir.path().join("down.hir"), scene("0 0 2  0 1 2  1 0 2")).unwrap();
    let e = check_hirad(dir.path(), &[], &args("up.hir"), &[]).unwrap_err();
    assert!(e.contains("nothing is lit"), "{e}");
    check_hirad(dir.path(), &[], &args("down.hir"), &[]).unwrap();
}

/// A page's checks on a small page written here: a scene block without a title, a titled file
/// no command uses, a command that fails, a slow command skipped, a good one passing.
#[test]
fn run_file_reports_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let md = dir.path().join("page.md");
    let scene = "hirad 1\nbands 1\nmaterial w rho 0.5\nmaterial l rho 0 emit 10\n\
                 scene {\n  quad w 0 0 0  1 0 0  1 1 0  0 1 0\n  tri l 0 0 1  0 1 1  1 0 1\n}\n";
    std::fs::write(
        &md,
        format!(
            "```hir title=lit.hir\n{scene}```\n\n```hir\n{scene}```\n\n\
             ```hir title=unused.hir\n{scene}```\n\n\
             ```sh\nhirad solve lit.hir\nhirad info missing.hir\n```\n\n\
             <!-- slow: a test of the mark -->\n```sh\nhirad solve lit.hir --size 9x9\n```\n"
        ),
    )
    .unwrap();
    let (failures, skipped) = run_file(&md, false);
    assert_eq!(failures.len(), 3, "{failures:#?}");
    assert!(
        failures[0].contains(":12: a hir block without title"),
        "{failures:#?}"
    );
    assert!(failures[1].contains(":23: no command of the page uses unused.hir"));
    assert!(failures[2].contains("`hirad info missing.hir`: failed (exit status: 3)"));
    assert_eq!(skipped.len(), 1, "{skipped:#?}");
    assert!(
        skipped[0].contains("slow (a test of the mark)"),
        "{skipped:#?}"
    );
}
