//! Exit statuses: every error the `hirad` command ends with falls in one class, and a class
//! always ends with the same status, so that scripts can tell a typo from a bad file from a
//! wrong result.
//!
//! | status | class |
//! | --- | --- |
//! | 0 | success: every output written and every check passed |
//! | 1 | not right: the run finished and wrote its outputs, but a check failed (not converged, diverged, power balance beyond `--max-imbalance`) |
//! | 2 | usage: the command line is wrong (an unknown option, a value out of range, an output that cannot be written where it is named) |
//! | 3 | input: a file the run reads is missing, unreadable or invalid (scene, `.mtl`, reference table), with its location |
//! | 4 | failed: the run could not complete (out of memory, a write failed, an internal error) |
//! | 130, 143 | interrupted by SIGINT or SIGTERM (unfinished outputs removed) |

use std::fmt;

/// The class of an error, by the status it ends the process with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Exit {
    /// 1: the outputs were written but are not right.
    NotRight = 1,
    /// 2: the command line is wrong.
    Usage = 2,
    /// 3: an input file is missing or invalid.
    Input = 3,
    /// 4: the run could not complete.
    Failed = 4,
}

/// An error with its class.
#[derive(Debug)]
pub struct Classified {
    /// Its class.
    pub exit: Exit,
    /// What went wrong.
    pub error: anyhow::Error,
}

/// The whole chain of what went wrong (`file: line:column: what`): the mark hides the
/// error's causes from `anyhow`'s chain, so it shows them itself.
impl fmt::Display for Classified {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:#}", self.error)
    }
}

impl std::error::Error for Classified {}

fn classify(exit: Exit, error: anyhow::Error) -> anyhow::Error {
    // The first class given stays: an input error passed up through a usage check is still
    // an input error.
    if error.downcast_ref::<Classified>().is_some() {
        return error;
    }
    anyhow::Error::new(Classified { exit, error })
}

/// Marks `e` as a usage error (status 2).
pub fn usage(e: impl Into<anyhow::Error>) -> anyhow::Error {
    classify(Exit::Usage, e.into())
}

/// Marks `e` as an input error (status 3).
pub fn input(e: impl Into<anyhow::Error>) -> anyhow::Error {
    classify(Exit::Input, e.into())
}

/// Marks `e` as results that are not right (status 1).
pub fn not_right(e: impl Into<anyhow::Error>) -> anyhow::Error {
    classify(Exit::NotRight, e.into())
}

/// The class of an error the command ends with: its mark, else (anywhere in its chain of
/// causes) a marked cause, else [`Exit::Failed`].
pub fn class_of(e: &anyhow::Error) -> Exit {
    e.chain()
        .find_map(|c| c.downcast_ref::<Classified>().map(|c| c.exit))
        .unwrap_or(Exit::Failed)
}

#[cfg(test)]
mod tests {
    use super::*;
    use anyhow::{Context, anyhow};

    #[test]
    fn classes_keep_their_first_mark_and_survive_context() {
        assert_eq!(class_of(&anyhow!("x")), Exit::Failed);
        assert_eq!(class_of(&usage(anyhow!("x"))), Exit::Usage);
        let e = input(anyhow!("bad.hir:1:1: nope"));
        assert_eq!(class_of(&usage(e)), Exit::Input);
        let wrapped: anyhow::Result<()> = Err(not_right(anyhow!("lost light")));
        let e = wrapped.context("scene.hir").unwrap_err();
        assert_eq!(class_of(&e), Exit::NotRight);
        assert_eq!(format!("{e:#}"), "scene.hir: lost light");
        assert_eq!(format!("{:#}", input(anyhow!("a").context("b"))), "b: a");
        assert_eq!(format!("{}", input(anyhow!("a").context("b"))), "b: a");
        assert_eq!(Exit::NotRight as u8, 1);
        assert_eq!(Exit::Failed as u8, 4);
    }
}
