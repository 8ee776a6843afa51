//! The Markdown side of the docs' examples: fenced blocks with their titles and marks, the
//! command lines of a block split into words, and what the test does with each command.

/// A fenced code block of a Markdown file.
#[derive(Debug, Clone, PartialEq)]
pub struct Block {
    /// 1-based line of the opening fence.
    pub line: usize,
    /// First word of the info string (`sh`, `hir`, ...), empty when none.
    pub lang: String,
    /// `title=NAME` of the info string.
    pub title: Option<String>,
    /// Reason of a `<!-- slow: REASON -->` comment on the lines just before the fence.
    pub slow: Option<String>,
    /// Texts of `<!-- warns: TEXT -->` comments on the lines just before the fence.
    pub warns: Vec<String>,
    /// The block's lines, without the fences.
    pub text: String,
}

/// The fenced code blocks of `markdown` (``` or ~~~ fences, up to 3 spaces of indentation).
pub fn blocks(markdown: &str) -> Result<Vec<Block>, String> {
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
pub fn commands(
    block: &Block,
) -> Result<Option<Vec<(Vec<(String, String)>, Vec<String>)>>, String> {
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

pub fn is_assignment(w: &str) -> bool {
    w.split_once('=').is_some_and(|(k, _)| {
        !k.is_empty()
            && k.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
            && !k.starts_with(|c: char| c.is_ascii_digit())
    })
}

/// Splits a shell line into commands (at `&&` and `;`) of words: single and double quotes,
/// backslash escapes, `#` comments. Pipes, redirections and substitutions are refused.
pub fn split_words(line: &str) -> Result<Vec<Vec<String>>, String> {
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
pub enum Run {
    /// Run the `hirad` under test with these arguments.
    Hirad(Vec<String>),
    /// Skipped by a rule; the reason.
    Skip(&'static str),
}

/// Maps a command to the `hirad` under test, or to a skip rule; unknown commands are errors.
pub fn classify(words: &[String]) -> Result<Run, String> {
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
