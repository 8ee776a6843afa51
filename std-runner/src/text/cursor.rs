//! A one-token lookahead over the lexer, with the small readers every statement uses:
//! names, numbers (finite `f32`) and whole numbers (`u32`), each with a message that says
//! what was expected and what was found.

use super::TextError;
use super::lexer::{Lexer, Pos, Tok, Token};
use super::names::is_keyword;
use hirad_core::limits::MAX_NAME_BYTES;

/// The token stream of one document.
pub(crate) struct Cursor<'a> {
    lexer: Lexer<'a>,
    peeked: Option<Token>,
}

/// A number token not yet converted: its text and position.
pub(crate) type RawNumber = (String, Pos);

impl<'a> Cursor<'a> {
    /// A cursor over `src` (refuses invalid UTF-8).
    pub fn new(src: &'a [u8]) -> Result<Self, TextError> {
        Ok(Cursor {
            lexer: Lexer::new(src)?,
            peeked: None,
        })
    }

    /// The next token, without consuming it.
    pub fn peek(&mut self) -> Result<&Token, TextError> {
        if self.peeked.is_none() {
            self.peeked = Some(self.lexer.next_token()?);
        }
        match &self.peeked {
            Some(t) => Ok(t),
            None => Err(Pos::START.error("internal error: lost a token")),
        }
    }

    /// Consumes the next token.
    pub fn next(&mut self) -> Result<Token, TextError> {
        match self.peeked.take() {
            Some(t) => Ok(t),
            None => self.lexer.next_token(),
        }
    }

    /// Consumes the next token if it is the bare word `w`, returning its position.
    pub fn eat_word(&mut self, w: &str) -> Result<Option<Pos>, TextError> {
        if self.peek()?.is_word(w) {
            Ok(Some(self.next()?.pos))
        } else {
            Ok(None)
        }
    }

    /// Consumes a `{`, or explains that one was expected `why`.
    pub fn open(&mut self, why: &str) -> Result<Pos, TextError> {
        let t = self.next()?;
        if t.tok == Tok::Open {
            Ok(t.pos)
        } else {
            Err(t
                .pos
                .error(format!("expected '{{' {why}, found {}", t.describe())))
        }
    }

    /// True if the next token can be read as a name (a quoted string or a non-keyword word).
    pub fn at_name(&mut self) -> Result<bool, TextError> {
        Ok(match &self.peek()?.tok {
            Tok::Str(_) => true,
            Tok::Word(w) => !is_keyword(w),
            _ => false,
        })
    }

    /// Reads a name; `what` says which (for messages), e.g. "material name".
    pub fn name(&mut self, what: &str) -> Result<(String, Pos), TextError> {
        let t = self.next()?;
        let name = match t.tok {
            Tok::Str(s) => s,
            Tok::Word(w) if is_keyword(&w) => {
                return Err(t.pos.error(format!(
                    "expected a {what}, found keyword '{w}' (write \"{w}\" to use it as a name)"
                )));
            }
            Tok::Word(w) => w,
            _ => {
                return Err(t
                    .pos
                    .error(format!("expected a {what}, found {}", t.describe())));
            }
        };
        if name.len() > MAX_NAME_BYTES {
            return Err(t.pos.error(format!(
                "this {what} is {} bytes long; names are at most {MAX_NAME_BYTES} bytes",
                name.len()
            )));
        }
        Ok((name, t.pos))
    }

    /// Consumes every number token that follows (a statement's values end at the next word,
    /// brace or the end). A bare `inf` or `nan` right after them is refused here.
    pub fn raw_numbers(&mut self) -> Result<Vec<RawNumber>, TextError> {
        let mut out = Vec::new();
        loop {
            let t = self.peek()?;
            match &t.tok {
                Tok::Num(n) => {
                    let item = (n.clone(), t.pos);
                    self.next()?;
                    out.push(item);
                }
                Tok::Word(w) if is_non_finite_word(w) => {
                    return Err(t.pos.error(format!(
                        "'{w}' is not allowed: every value must be a finite number"
                    )));
                }
                _ => return Ok(out),
            }
        }
    }

    /// Reads exactly `n` numbers after the keyword `kw` (at `at`); `detail` says what they
    /// are, e.g. "(x y z)".
    pub fn numbers(
        &mut self,
        kw: &str,
        at: Pos,
        n: usize,
        detail: &str,
    ) -> Result<Vec<(f32, Pos)>, TextError> {
        let raw = self.raw_numbers()?;
        let values = raw
            .iter()
            .map(|(t, p)| Ok((to_f32(t, *p)?, *p)))
            .collect::<Result<Vec<_>, TextError>>()?;
        if values.len() != n {
            let noun = if n == 1 { "number" } else { "numbers" };
            return Err(at.error(format!(
                "expected {n} {noun} after '{kw}' {detail}, found {}",
                values.len()
            )));
        }
        Ok(values)
    }

    /// Reads one number after the keyword `kw`.
    pub fn number(&mut self, kw: &str, at: Pos, detail: &str) -> Result<(f32, Pos), TextError> {
        let v = self.numbers(kw, at, 1, detail)?;
        v.first()
            .copied()
            .ok_or_else(|| at.error("internal error: missing number"))
    }

    /// Reads one whole number after the keyword `kw`; `what` names it for messages.
    pub fn integer(&mut self, kw: &str, what: &str) -> Result<(u32, Pos), TextError> {
        let t = self.next()?;
        match &t.tok {
            Tok::Num(n) => Ok((to_u32(n, t.pos, what)?, t.pos)),
            _ => Err(t.pos.error(format!(
                "expected {what} (a whole number) after '{kw}', found {}",
                t.describe()
            ))),
        }
    }
}

/// True for the words `str::parse::<f32>` would read as infinity or NaN.
fn is_non_finite_word(w: &str) -> bool {
    ["inf", "infinity", "nan"]
        .iter()
        .any(|x| x.eq_ignore_ascii_case(w))
}

/// Converts a number token to a finite `f32`.
pub(crate) fn to_f32(text: &str, at: Pos) -> Result<f32, TextError> {
    match text.parse::<f32>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => {
            let lower = text.to_ascii_lowercase();
            if lower.contains("inf") || lower.contains("nan") {
                Err(at.error(format!(
                    "'{text}' is not allowed: every value must be a finite number"
                )))
            } else {
                Err(at.error(format!(
                    "'{text}' is too large for a 32-bit float (the largest is about 3.4e38)"
                )))
            }
        }
        Err(_) => Err(at.error(format!("'{text}' is not a number"))),
    }
}

/// Converts a number token to a `u32`; `what` names it for messages.
pub(crate) fn to_u32(text: &str, at: Pos, what: &str) -> Result<u32, TextError> {
    if text.is_empty() || !text.bytes().all(|b| b.is_ascii_digit()) {
        return Err(at.error(format!(
            "expected {what} (a whole number like 0, 1, 2), found '{text}'"
        )));
    }
    text.parse::<u32>().map_err(|_| {
        at.error(format!(
            "{what} '{text}' is too large (at most {})",
            u32::MAX
        ))
    })
}
