//! The text scene format `.hir` (specified in `docs/format.md`): parser and printer.

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

/// Parses a `.hir` document.
pub fn parse(src: &[u8]) -> Result<Scene, TextError> {
    let _ = src;
    Err(TextError {
        line: 1,
        column: 1,
        message: "the .hir parser is not written yet".into(),
    })
}

/// Prints a scene as a `.hir` document that [`parse`] reads back to an identical scene.
pub fn print(scene: &Scene) -> String {
    let _ = scene;
    String::new()
}
