//! The text scene format `.hir` (specified in `docs/format.md`): parser and printer.

mod attrs;
mod body;
mod cursor;
mod lexer;
mod names;
mod parser;
mod printer;
mod resolve;
mod symbols;
mod units;

pub use names::KEYWORDS;

use crate::scene::Scene;
use std::fmt;

/// A parse error at a 1-based line and column (columns count characters).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TextError {
    /// 1-based line.
    pub line: u32,
    /// 1-based column, in characters.
    pub column: u32,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for TextError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}: {}", self.line, self.column, self.message)
    }
}

impl std::error::Error for TextError {}

/// Parses a `.hir` document into a scene that `Scene::check` and `scene::compile` accept.
/// Never panics; every fault is reported with its line and column.
pub fn parse(src: &[u8]) -> Result<Scene, TextError> {
    let mut p = parser::Parser::new(src)?;
    p.document()?;
    resolve::finish(p)
}

/// Prints a scene as a `.hir` document that [`parse`] reads back to an identical scene.
pub fn print(scene: &Scene) -> String {
    printer::print(scene)
}

#[cfg(test)]
mod tests;
