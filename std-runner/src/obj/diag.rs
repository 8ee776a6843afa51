//! Diagnostics of an import: located errors and the list of warnings, in file order.

use super::ObjError;
use super::lex::Pos;
use std::collections::BTreeSet;

/// Most warnings kept; beyond it they are counted and summarised in one last line, so that a
/// file with millions of degenerate faces cannot fill memory with messages.
pub const MAX_WARNINGS: usize = 1000;

/// An error at `pos` of `file` (empty for the OBJ itself).
pub(crate) fn error(file: &str, pos: Pos, message: impl Into<String>) -> ObjError {
    ObjError {
        file: file.to_string(),
        line: pos.line,
        column: pos.col,
        message: message.into(),
    }
}

/// Warnings of one import, shared by the OBJ and its MTL files.
#[derive(Debug, Default)]
pub(crate) struct Warnings {
    list: Vec<String>,
    dropped: u64,
    /// `(file, kind)` pairs already reported by [`Warnings::once`].
    seen: BTreeSet<(String, String)>,
}

impl Warnings {
    /// Adds `FILE:LINE:COL: message` (no `FILE:` for the OBJ).
    pub fn add(&mut self, file: &str, pos: Pos, message: impl AsRef<str>) {
        if self.list.len() >= MAX_WARNINGS {
            self.dropped += 1;
            return;
        }
        let message = message.as_ref();
        self.list.push(if file.is_empty() {
            format!("{}:{}: {message}", pos.line, pos.col)
        } else {
            format!("{file}:{}:{}: {message}", pos.line, pos.col)
        });
    }

    /// Adds the warning only the first time `kind` is reported for `file`.
    pub fn once(&mut self, file: &str, kind: &str, pos: Pos, message: impl AsRef<str>) {
        if self.seen.insert((file.to_string(), kind.to_string())) {
            self.add(file, pos, message);
        }
    }

    /// Every warning made, kept or not.
    pub fn total(&self) -> u64 {
        self.list.len() as u64 + self.dropped
    }

    /// The warnings, with a last line counting those beyond [`MAX_WARNINGS`].
    pub fn finish(mut self) -> Vec<String> {
        if self.dropped > 0 {
            self.list
                .push(format!("... and {} more warnings not shown", self.dropped));
        }
        self.list
    }
}
