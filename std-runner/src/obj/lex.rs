//! Splits OBJ/MTL bytes into logical lines of whitespace-separated tokens, each token located
//! by its 1-based physical line and character column.
//!
//! Rules: lines end in `\n` (a `\r` just before it is whitespace, one elsewhere is reported);
//! `#` starts a comment that runs to the end of the physical line; a backslash that ends a
//! physical line (trailing whitespace allowed, comments excluded) joins the next physical line
//! to this logical line. Bytes that are not UTF-8 are replaced by U+FFFD and reported once per
//! file by the caller.

use std::ops::Range;

/// A 1-based line and character column.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub(crate) struct Pos {
    /// 1-based physical line.
    pub line: u32,
    /// 1-based column, in characters.
    pub col: u32,
}

/// One token of a logical line: its bytes in [`Line::text`] and where it starts.
#[derive(Clone, Debug)]
struct Span {
    bytes: Range<usize>,
    pos: Pos,
    chars: u32,
}

/// A logical line: the tokens of one statement.
#[derive(Debug, Default)]
pub(crate) struct Line {
    /// The joined content of the physical lines, comments and continuations removed.
    text: String,
    spans: Vec<Span>,
    /// Some byte of the line was not UTF-8 (replaced by U+FFFD).
    pub invalid_utf8: bool,
    /// A carriage return that does not end its physical line (a file with classic Mac OS
    /// line ends would otherwise read as one long line).
    pub bare_cr: Option<Pos>,
}

impl Line {
    /// Number of tokens (at least 1 for a line returned by [`Lexer::next_line`]).
    pub fn len(&self) -> usize {
        self.spans.len()
    }

    /// Token `i`.
    pub fn tok(&self, i: usize) -> &str {
        &self.text[self.spans[i].bytes.clone()]
    }

    /// Where token `i` starts.
    pub fn pos(&self, i: usize) -> Pos {
        self.spans[i].pos
    }

    /// Where token `i` starts, moved right by `chars` characters (a part of a token).
    pub fn pos_in(&self, i: usize, chars: usize) -> Pos {
        let p = self.spans[i].pos;
        Pos {
            line: p.line,
            col: p
                .col
                .saturating_add(u32::try_from(chars).unwrap_or(u32::MAX)),
        }
    }

    /// Just after the last token: where a missing value was expected.
    pub fn end(&self) -> Pos {
        match self.spans.last() {
            Some(s) => Pos {
                line: s.pos.line,
                col: s.pos.col.saturating_add(s.chars),
            },
            None => Pos::default(),
        }
    }

    /// Tokens `from..` as written, with the original spacing between them (one space where a
    /// continuation joined two physical lines). Empty when `from` is past the end.
    pub fn rest(&self, from: usize) -> &str {
        match (self.spans.get(from), self.spans.last()) {
            (Some(a), Some(b)) => &self.text[a.bytes.start..b.bytes.end],
            _ => "",
        }
    }

    /// Tokens `from..` joined by single spaces (how names with several words are read).
    pub fn joined(&self, from: usize) -> String {
        let mut s = String::new();
        for i in from..self.len() {
            if i > from {
                s.push(' ');
            }
            s.push_str(self.tok(i));
        }
        s
    }
}

/// Reads logical lines from a byte buffer.
pub(crate) struct Lexer<'a> {
    src: &'a [u8],
    at: usize,
    /// Number of the next physical line.
    line: u32,
}

impl<'a> Lexer<'a> {
    /// A lexer at the start of `src`.
    pub fn new(src: &'a [u8]) -> Self {
        Lexer {
            src,
            at: 0,
            line: 1,
        }
    }

    /// Number of the last physical line read (0 before the first).
    pub fn last_line(&self) -> u32 {
        self.line.saturating_sub(1)
    }

    /// Fills `out` with the next logical line that has tokens; false at the end of input.
    pub fn next_line(&mut self, out: &mut Line) -> bool {
        out.text.clear();
        out.spans.clear();
        out.invalid_utf8 = false;
        out.bare_cr = None;
        while self.at < self.src.len() {
            let rest = &self.src[self.at..];
            let len = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
            let physical = &rest[..len];
            self.at += len + 1;
            let line = self.line;
            self.line = self.line.saturating_add(1);
            let decoded = String::from_utf8_lossy(physical);
            if matches!(decoded, std::borrow::Cow::Owned(_)) {
                out.invalid_utf8 = true;
            }
            let continued = add_physical(out, &decoded, line);
            if !continued && !out.spans.is_empty() {
                return true;
            }
        }
        !out.spans.is_empty()
    }
}

/// Appends the tokens of one physical line; returns whether it continues on the next line.
fn add_physical(out: &mut Line, text: &str, line: u32) -> bool {
    let (content, continued) = match text.find('#') {
        Some(k) => (&text[..k], false),
        None => {
            let trimmed = text.trim_end();
            match trimmed.strip_suffix('\\') {
                Some(c) => (c, true),
                None => (text, false),
            }
        }
    };
    let body = content.strip_suffix('\r').unwrap_or(content);
    if out.bare_cr.is_none()
        && let Some(k) = body.find('\r')
    {
        let col = u32::try_from(body[..k].chars().count() + 1).unwrap_or(u32::MAX);
        out.bare_cr = Some(Pos { line, col });
    }
    if !out.text.is_empty() {
        out.text.push(' ');
    }
    let base = out.text.len();
    out.text.push_str(content);
    let mut start: Option<(usize, u32)> = None;
    let mut col = 0u32;
    let mut chars = 0u32;
    for (k, c) in content.char_indices() {
        col = col.saturating_add(1);
        if c.is_whitespace() {
            if let Some((s, scol)) = start.take() {
                push_span(out, base + s..base + k, line, scol, chars);
            }
        } else {
            match start {
                None => {
                    start = Some((k, col));
                    chars = 1;
                }
                Some(_) => chars = chars.saturating_add(1),
            }
        }
    }
    if let Some((s, scol)) = start {
        push_span(out, base + s..base + content.len(), line, scol, chars);
    }
    continued
}

fn push_span(out: &mut Line, bytes: Range<usize>, line: u32, col: u32, chars: u32) {
    out.spans.push(Span {
        bytes,
        pos: Pos { line, col },
        chars,
    });
}
