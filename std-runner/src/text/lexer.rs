//! Tokens of a `.hir` document: braces, words, quoted strings and numbers, each with its
//! 1-based line and column (in characters). Comments and whitespace are skipped here.

use super::TextError;

/// A 1-based position in the document.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) struct Pos {
    /// Line.
    pub line: u32,
    /// Column, in characters.
    pub column: u32,
}

impl Pos {
    /// The start of the document.
    pub const START: Pos = Pos { line: 1, column: 1 };

    /// An error at this position.
    pub fn error(self, message: impl Into<String>) -> TextError {
        TextError {
            line: self.line,
            column: self.column,
            message: message.into(),
        }
    }
}

/// What a token is.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Tok {
    /// `{`
    Open,
    /// `}`
    Close,
    /// A bare word `[A-Za-z_][A-Za-z0-9_.-]*`: a keyword or a name.
    Word(String),
    /// A double-quoted string, escapes resolved: always a name.
    Str(String),
    /// A run of characters that starts like a number; converted (and checked) by the parser.
    Num(String),
    /// End of input.
    End,
}

/// A token and where it starts.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Token {
    /// The token.
    pub tok: Tok,
    /// Its first character.
    pub pos: Pos,
}

impl Token {
    /// How the token reads in a message: `'{'`, `keyword 'rho'`, `number 1.5`, ...
    pub fn describe(&self) -> String {
        match &self.tok {
            Tok::Open => "'{'".into(),
            Tok::Close => "'}'".into(),
            Tok::Word(w) if super::names::is_keyword(w) => format!("keyword '{w}'"),
            Tok::Word(w) => format!("name '{w}'"),
            Tok::Str(s) => format!("string {}", super::names::quote(s)),
            Tok::Num(n) => format!("number {n}"),
            Tok::End => "the end of the input".into(),
        }
    }

    /// True if the token is the bare word `w`.
    pub fn is_word(&self, w: &str) -> bool {
        matches!(&self.tok, Tok::Word(x) if x == w)
    }
}

/// Splits a document into tokens on demand, so that errors come in document order.
pub(crate) struct Lexer<'a> {
    src: &'a str,
    at: usize,
    pos: Pos,
}

/// Line and column of byte `offset` of `text` (which must be valid UTF-8 up to `offset`).
fn position_of(text: &str, offset: usize) -> Pos {
    let before = text.get(..offset).unwrap_or(text);
    let line = before.bytes().filter(|&b| b == b'\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let mut column = before.get(line_start..).map_or(0, |l| l.chars().count()) + 1;
    if line_start == 0 && before.starts_with('\u{feff}') {
        // The byte-order mark takes no column (see `Lexer::new`).
        column -= 1;
    }
    Pos {
        line: saturate(line),
        column: saturate(column),
    }
}

fn saturate(x: usize) -> u32 {
    u32::try_from(x).unwrap_or(u32::MAX)
}

fn starts_word(c: char) -> bool {
    c.is_ascii_alphabetic() || c == '_'
}

fn continues_word(c: char) -> bool {
    c.is_ascii_alphanumeric() || matches!(c, '_' | '.' | '-')
}

fn starts_number(c: char) -> bool {
    c.is_ascii_digit() || matches!(c, '+' | '-' | '.')
}

fn continues_number(c: char) -> bool {
    c.is_ascii_alphanumeric() || matches!(c, '_' | '.' | '+' | '-')
}

impl<'a> Lexer<'a> {
    /// A lexer over `src`; refuses invalid UTF-8 at the line:column of its first bad byte.
    pub fn new(src: &'a [u8]) -> Result<Self, TextError> {
        let text = match std::str::from_utf8(src) {
            Ok(t) => t,
            Err(e) => {
                let good = e.valid_up_to();
                // The prefix is valid by definition of `valid_up_to`.
                let prefix =
                    std::str::from_utf8(src.get(..good).unwrap_or_default()).unwrap_or_default();
                return Err(position_of(prefix, good)
                    .error("the file is not valid UTF-8 (invalid byte sequence here)"));
            }
        };
        // A byte-order mark some editors write is skipped and takes no column.
        let at = if text.starts_with('\u{feff}') {
            '\u{feff}'.len_utf8()
        } else {
            0
        };
        Ok(Lexer {
            src: text,
            at,
            pos: Pos::START,
        })
    }

    fn peek_char(&self) -> Option<char> {
        self.src.get(self.at..).and_then(|s| s.chars().next())
    }

    fn bump(&mut self) -> Option<char> {
        let c = self.peek_char()?;
        self.at += c.len_utf8();
        if c == '\n' {
            self.pos.line = self.pos.line.saturating_add(1);
            self.pos.column = 1;
        } else {
            self.pos.column = self.pos.column.saturating_add(1);
        }
        Some(c)
    }

    fn skip_blanks(&mut self) {
        while let Some(c) = self.peek_char() {
            if c == '#' {
                while let Some(c) = self.peek_char() {
                    if c == '\n' {
                        break;
                    }
                    self.bump();
                }
            } else if c.is_whitespace() {
                self.bump();
            } else {
                break;
            }
        }
    }

    fn take_while(&mut self, keep: fn(char) -> bool) -> String {
        let start = self.at;
        while self.peek_char().is_some_and(keep) {
            self.bump();
        }
        self.src.get(start..self.at).unwrap_or_default().to_string()
    }

    /// The next token; [`Tok::End`] forever once the input is exhausted.
    pub fn next_token(&mut self) -> Result<Token, TextError> {
        self.skip_blanks();
        let pos = self.pos;
        let Some(c) = self.peek_char() else {
            return Ok(Token { tok: Tok::End, pos });
        };
        let tok = match c {
            '{' => {
                self.bump();
                Tok::Open
            }
            '}' => {
                self.bump();
                Tok::Close
            }
            '"' => Tok::Str(self.string()?),
            c if starts_word(c) => Tok::Word(self.take_while(continues_word)),
            c if starts_number(c) => Tok::Num(self.take_while(continues_number)),
            c => {
                return Err(pos.error(format!(
                    "unexpected character {c:?}: expected a keyword, a name, a number, a quoted string, '{{' or '}}'"
                )));
            }
        };
        Ok(Token { tok, pos })
    }

    /// A quoted string; the opening quote is the current character.
    fn string(&mut self) -> Result<String, TextError> {
        let open = self.pos;
        self.bump();
        let mut out = String::new();
        loop {
            let at = self.pos;
            match self.bump() {
                None | Some('\n') => {
                    return Err(open.error(
                        "unterminated string: a quoted name must end with '\"' on the same line (write \\n for a line break)",
                    ));
                }
                Some('"') => return Ok(out),
                Some('\\') => out.push(self.escape(at)?),
                Some(c) => out.push(c),
            }
        }
    }

    /// The character an escape stands for; `at` is the backslash.
    fn escape(&mut self, at: Pos) -> Result<char, TextError> {
        let bad = || {
            at.error("unknown escape: use \\\" \\\\ \\n \\t \\r or \\u{hex} inside a quoted name")
        };
        match self.bump() {
            Some('"') => Ok('"'),
            Some('\\') => Ok('\\'),
            Some('n') => Ok('\n'),
            Some('t') => Ok('\t'),
            Some('r') => Ok('\r'),
            Some('u') => {
                if self.bump() != Some('{') {
                    return Err(bad());
                }
                let hex = self.take_while(|c| c.is_ascii_hexdigit());
                if self.bump() != Some('}') || hex.is_empty() || hex.len() > 6 {
                    return Err(
                        at.error("malformed \\u{...} escape: expected 1 to 6 hex digits in braces")
                    );
                }
                u32::from_str_radix(&hex, 16)
                    .ok()
                    .and_then(char::from_u32)
                    .ok_or_else(|| at.error(format!("\\u{{{hex}}} is not a Unicode scalar value")))
            }
            _ => Err(bad()),
        }
    }
}
