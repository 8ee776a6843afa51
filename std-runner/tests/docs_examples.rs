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

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// A fenced code block of a Markdown file.
#[derive(Debug, Clone, PartialEq)]
struct Block {
    /// 1-based line of the opening fence.
    line: usize,
    /// First word of the info string (`sh`, `hir`, ...), empty when none.
    lang: String,
    /// `title=NAME` of the info string.
    title: Option<String>,
    /// Reason of a `<!-- slow: REASON -->` comment on the lines just before the fence.
    slow: Option<String>,
    /// Texts of `<!-- warns: TEXT -->` comments on the lines just before the fence.
    warns: Vec<String>,
    /// The block's lines, without the fences.
    text: String,
}

/// The fenced code blocks of `markdown` (``` or ~~~ fences, up to 3 spaces of indentation).
fn blocks(markdown: &str) -> Result<Vec<Block>, String> {
    let mut out = Vec::new();
    let mut lines = markdown.lines().enumerate();
    // The `<!-- KEY: VALUE -->` comments on the lines just before the current one.
    let mut comments: Vec<(String, String)> = Vec::new();
    while let Some((i, line)) = lines.next() {
        let trimmed = line.trim_start();
        let fence_char = trimmed.chars().next().filter(|c| matches!(c, '`' | '~'));
        let fence_len = fence_char.map_or(0, |f| trimmed.chars().take_while(|&c| c == f).count());
        let (Some(fence_char), true) = (
            fence_char,
            fence_len >= 3 && line.len() - trimmed.len() <= 3,
        ) else {
            match trimmed
                .trim_end()
                .strip_prefix("<!--")
                .and_then(|r| r.strip_suffix("-->"))
                .and_then(|r| r.split_once(':'))
            {
                Some((k, v)) => comments.push((k.trim().to_string(), v.trim().to_string())),
                None => comments.clear(),
            }
            continue;
        };
        let info = trimmed[fence_len..].trim();
        let mut words = info.split_whitespace();
        let lang = words.next().unwrap_or("").to_string();
        let title = words
            .filter_map(|w| w.strip_prefix("title="))
            .map(str::to_string)
            .next();
        let marks = |key: &str| -> Vec<String> {
            comments
                .iter()
                .filter(|(k, _)| k == key)
                .map(|(_, v)| v.clone())
                .collect()
        };
        let slow = marks("slow").into_iter().next();
        let warns = marks("warns");
        comments.clear();
        let mut text = String::new();
        let mut closed = false;
        for (_, l) in lines.by_ref() {
            let t = l.trim();
            if t.len() >= fence_len && t.chars().all(|c| c == fence_char) {
                closed = true;
                break;
            }
            text.push_str(l);
            text.push('\n');
        }
        if !closed {
            return Err(format!("line {}: unclosed code block", i + 1));
        }
        out.push(Block {
            line: i + 1,
            lang,
            title,
            slow,
            warns,
            text,
        });
    }
    Ok(out)
}

/// The commands of a command block (`sh`, `bash`, `console`), each as its words, with the
/// environment assignments that precede it; `None` for any other block.
#[allow(clippy::type_complexity)]
fn commands(block: &Block) -> Result<Option<Vec<(Vec<(String, String)>, Vec<String>)>>, String> {
    let console = match block.lang.as_str() {
        "sh" | "bash" | "shell" => false,
        "console" => true,
        _ => return Ok(None),
    };
    let mut joined = Vec::new();
    let mut pending = String::new();
    for line in block.text.lines() {
        let line = if pending.is_empty() && console {
            match line.strip_prefix("$ ") {
                Some(l) => l,
                None => continue,
            }
        } else {
            line
        };
        match line.trim_end().strip_suffix('\\') {
            Some(head) => {
                pending.push_str(head);
                pending.push(' ');
            }
            None => {
                pending.push_str(line);
                joined.push(std::mem::take(&mut pending));
            }
        }
    }
    if !pending.is_empty() {
        return Err("a command ends with a line continuation".into());
    }
    let mut out = Vec::new();
    for line in joined {
        for words in split_words(&line)? {
            let split = words
                .iter()
                .position(|w| !is_assignment(w))
                .unwrap_or(words.len());
            let env = words[..split]
                .iter()
                .map(|w| {
                    let (k, v) = w.split_once('=').unwrap();
                    (k.to_string(), v.to_string())
                })
                .collect();
            let rest = words[split..].to_vec();
            if !rest.is_empty() {
                out.push((env, rest));
            }
        }
    }
    Ok(Some(out))
}

fn is_assignment(w: &str) -> bool {
    w.split_once('=').is_some_and(|(k, _)| {
        !k.is_empty()
            && k.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
            && !k.starts_with(|c: char| c.is_ascii_digit())
    })
}

/// Splits a shell line into commands (at `&&` and `;`) of words: single and double quotes,
/// backslash escapes, `#` comments. Pipes, redirections and substitutions are refused.
fn split_words(line: &str) -> Result<Vec<Vec<String>>, String> {
    let mut commands = vec![Vec::new()];
    let mut word = String::new();
    let mut in_word = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            ' ' | '\t' => {
                if in_word {
                    commands.last_mut().unwrap().push(std::mem::take(&mut word));
                    in_word = false;
                }
            }
            '#' if !in_word => break,
            '\'' => {
                in_word = true;
                loop {
                    match chars.next() {
                        Some('\'') => break,
                        Some(c) => word.push(c),
                        None => return Err(format!("unclosed ' in {line:?}")),
                    }
                }
            }
            '"' => {
                in_word = true;
                loop {
                    match chars.next() {
                        Some('"') => break,
                        Some('\\') => word.push(chars.next().unwrap_or('\\')),
                        Some('$' | '`') => return Err(format!("substitution in {line:?}")),
                        Some(c) => word.push(c),
                        None => return Err(format!("unclosed \" in {line:?}")),
                    }
                }
            }
            '\\' => {
                in_word = true;
                word.push(chars.next().unwrap_or('\\'));
            }
            ';' | '&' => {
                if c == '&' && chars.next_if_eq(&'&').is_none() {
                    return Err(format!("background job in {line:?}"));
                }
                if in_word {
                    commands.last_mut().unwrap().push(std::mem::take(&mut word));
                    in_word = false;
                }
                commands.push(Vec::new());
            }
            '|' | '>' | '<' | '$' | '`' | '(' | ')' => {
                return Err(format!("unsupported shell syntax {c:?} in {line:?}"));
            }
            c => {
                in_word = true;
                word.push(c);
            }
        }
    }
    if in_word {
        commands.last_mut().unwrap().push(word);
    }
    commands.retain(|c| !c.is_empty());
    Ok(commands)
}

/// What the test does with a command.
#[derive(Debug, PartialEq)]
enum Run {
    /// Run the `hirad` under test with these arguments.
    Hirad(Vec<String>),
    /// Skipped by a rule; the reason.
    Skip(&'static str),
}

/// Maps a command to the `hirad` under test, or to a skip rule; unknown commands are errors.
fn classify(words: &[String]) -> Result<Run, String> {
    let program = words[0].as_str();
    if program == "hirad" {
        return Ok(Run::Hirad(words[1..].to_vec()));
    }
    if program == "cargo" {
        let sub = words.get(1).map(String::as_str);
        if sub == Some("run") {
            let dash = words.iter().position(|w| w == "--");
            let opts = &words[2..dash.unwrap_or(words.len())];
            let hirad = opts
                .windows(2)
                .any(|w| (w[0] == "-p" || w[0] == "--package") && w[1] == "hirad")
                || opts
                    .iter()
                    .any(|w| w == "--package=hirad" || w == "--bin=hirad")
                || opts.windows(2).any(|w| w[0] == "--bin" && w[1] == "hirad");
            if opts.iter().any(|w| w.starts_with("--example")) {
                return Ok(Run::Skip(
                    "cargo run --example: an example program of the library, not the CLI (cargo test builds the examples)",
                ));
            }
            if hirad {
                let args = dash.map(|d| words[d + 1..].to_vec()).unwrap_or_default();
                return Ok(Run::Hirad(args));
            }
            return Err(format!(
                "cargo run of something other than hirad: {words:?}"
            ));
        }
        return Ok(Run::Skip(
            "a cargo command that builds or tests the workspace this test is part of",
        ));
    }
    if program.ends_with(".sh") {
        return Ok(Run::Skip(
            "a repository script (the gallery script builds in release and runs for minutes; run it by hand, it has --quick)",
        ));
    }
    Err(format!(
        "no rule for the command {words:?}: run it as hirad, or add a skip rule to this test"
    ))
}

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
fn blocks_titles_slow_marks_and_commands() {
    let md = "intro\n\
              ```hir title=a.hir\n\
              hirad 1\n\
              ```\n\
              <!-- slow: the stand, minutes -->\n\
              <!-- warns: lost -->\n\
              ```sh\n\
              hirad gen stand \\\n  -o s.hirb && hirad info s.hirb  # comment\n\
              X=1 cargo run --release -p hirad -- solve 'my scene.hir'\n\
              ```\n\
              <!-- slow: not this one: text comes between -->\n\
              text\n\
              ~~~~console\n\
              $ hirad info a.hir\n\
              bands 1\n\
              ```\n\
              ~~~~\n\
              ```\n\
              error 0.8 %\n\
              ```\n";
    let b = blocks(md).unwrap();
    assert_eq!(b.len(), 4);
    assert_eq!((b[0].line, b[0].lang.as_str()), (2, "hir"));
    assert_eq!(b[0].title.as_deref(), Some("a.hir"));
    assert_eq!(b[0].text, "hirad 1\n");
    assert_eq!(b[0].slow, None);
    assert_eq!(b[1].slow.as_deref(), Some("the stand, minutes"));
    assert_eq!(b[1].warns, vec!["lost".to_string()]);
    assert!(b[2].warns.is_empty());
    assert_eq!(b[1].title, None);
    assert_eq!(b[2].slow, None);
    // A ``` inside a ~~~~ block does not close it.
    assert_eq!(b[2].text, "$ hirad info a.hir\nbands 1\n```\n");
    let w = |s: &[&str]| s.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let c = commands(&b[1]).unwrap().unwrap();
    assert_eq!(
        c,
        vec![
            (vec![], w(&["hirad", "gen", "stand", "-o", "s.hirb"])),
            (vec![], w(&["hirad", "info", "s.hirb"])),
            (
                vec![("X".to_string(), "1".to_string())],
                w(&[
                    "cargo",
                    "run",
                    "--release",
                    "-p",
                    "hirad",
                    "--",
                    "solve",
                    "my scene.hir"
                ])
            ),
        ]
    );
    assert_eq!(
        commands(&b[2]).unwrap().unwrap(),
        vec![(vec![], w(&["hirad", "info", "a.hir"]))]
    );
    assert_eq!(commands(&b[0]).unwrap(), None);
    assert_eq!(commands(&b[3]).unwrap(), None);
    assert!(blocks("```sh\nhirad info\n").is_err(), "unclosed block");
    assert!(split_words("hirad info x | head").is_err());
    assert!(split_words("hirad solve x > out").is_err());
}

#[test]
fn commands_map_to_the_binary_or_a_rule() {
    let w = |s: &str| s.split_whitespace().map(str::to_string).collect::<Vec<_>>();
    assert_eq!(
        classify(&w("hirad info x.hir")).unwrap(),
        Run::Hirad(w("info x.hir"))
    );
    assert_eq!(
        classify(&w(
            "cargo run --release -p hirad -- solve x.hir --image x.png"
        ))
        .unwrap(),
        Run::Hirad(w("solve x.hir --image x.png"))
    );
    assert!(matches!(
        classify(&w("cargo test --workspace")),
        Ok(Run::Skip(_))
    ));
    assert!(matches!(
        classify(&w("cargo run --release --example solve_text")),
        Ok(Run::Skip(_))
    ));
    assert!(matches!(
        classify(&w("docs/gallery.sh --quick")),
        Ok(Run::Skip(_))
    ));
    assert!(classify(&w("cargo run -p other -- x")).is_err());
    assert!(classify(&w("rm -rf x")).is_err());
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
