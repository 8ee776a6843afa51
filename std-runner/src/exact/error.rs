//! Why the reference solver refuses a scene or stops.

use crate::scene::SceneError;
use std::fmt;

/// An error of [`super::solve_exact`]; `E` is the sink's error type.
#[derive(Debug)]
pub enum ExactError<E> {
    /// The scene fails `Scene::check`.
    Scene(SceneError),
    /// The settings are out of range.
    Settings(String),
    /// The scene is too large for a full-matrix solver.
    TooLarge {
        /// What was counted.
        what: &'static str,
        /// How many there are (or would be).
        count: u64,
        /// The hard limit.
        limit: u64,
    },
    /// The iteration cap was reached before the tolerance.
    NotConverged {
        /// Sweeps done.
        iterations: u32,
        /// Estimated remaining error, relative to the largest radiosity.
        error: f64,
    },
    /// The polygon list could not be turned into a ray-casting structure.
    Visibility(crate::visibility::VisibilityError),
    /// The sink refused a result.
    Sink(E),
}

impl<E: fmt::Display> fmt::Display for ExactError<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ExactError::Scene(e) => write!(f, "scene refused: {e}"),
            ExactError::Settings(m) => write!(f, "settings: {m}"),
            ExactError::TooLarge { what, count, limit } => write!(
                f,
                "too large for the exact solver: {count} {what}, at most {limit} \
                 (use the hierarchical solver)"
            ),
            ExactError::NotConverged { iterations, error } => write!(
                f,
                "no convergence after {iterations} iterations (estimated error {error:.3e} of \
                 the largest radiosity); raise the iteration cap"
            ),
            ExactError::Visibility(e) => write!(f, "visibility: {e}"),
            ExactError::Sink(e) => write!(f, "output: {e}"),
        }
    }
}

impl<E: fmt::Debug + fmt::Display> std::error::Error for ExactError<E> {}
