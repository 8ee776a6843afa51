//! Why a solve stops: the solver's own errors (with their messages) and the sink's.

use crate::image::ImageError;

/// Why a solve could not run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrError {
    /// The image could not be read.
    Image(ImageError),
    /// The workspace cannot hold even the coarsest solution; `needed` bytes would.
    WorkspaceTooSmall {
        /// Bytes the coarsest solution needs.
        needed: u64,
    },
    /// The scratch given to planning is too small.
    ScratchTooSmall,
    /// The expanded scene has more elements than one workspace can index.
    SceneTooLarge,
    /// Nothing emits light: no emitting material, sun or sky.
    NoLight,
    /// The scene has no polygons.
    Empty,
    /// A setting is out of range (the message names it).
    Settings(&'static str),
    /// A polygon is unusable once placed (its instance transforms overflow f32).
    BadGeometry {
        /// Global id of the polygon.
        polygon: u64,
    },
    /// The solution diverged: a radiosity grew without bound (a defect of the solver, since
    /// every checked scene absorbs some light). Nothing is written.
    Diverged {
        /// Iterations run when it was found.
        iterations: u64,
    },
    /// The scene has no steady state in a band: it is closed (no light leaves it), nothing
    /// in it absorbs that band, and something emits it.
    NoSteadyState {
        /// The band.
        band: u32,
    },
    /// An instance stays closed but its original has no directional tables in the image.
    NoTables {
        /// The original (index).
        original: u32,
    },
    /// The caller's progress asked to stop ([`super::Progress::cancelled`]).
    Cancelled,
}

impl From<ImageError> for HrError {
    fn from(e: ImageError) -> Self {
        HrError::Image(e)
    }
}

impl core::fmt::Display for HrError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            HrError::Image(e) => write!(f, "{e}"),
            HrError::NoTables { original } => write!(
                f,
                "original {original} has closed instances but no directional tables in the image (compute them with `hirad tables SCENE -o OUT.hirb`, or expand every instance: `--instancing none`)"
            ),
            HrError::WorkspaceTooSmall { needed } => {
                write!(
                    f,
                    "the workspace cannot hold even the coarsest solution: it needs at least {needed} bytes"
                )
            }
            HrError::ScratchTooSmall => f.write_str("the planning scratch is too small"),
            HrError::SceneTooLarge => {
                f.write_str("the expanded scene has more elements than one workspace can index")
            }
            HrError::NoLight => {
                f.write_str("nothing emits light: give a material 'emit', or add a sun or sky")
            }
            HrError::Empty => f.write_str("the scene has no polygons"),
            HrError::Cancelled => f.write_str("the solve was cancelled by its progress callback"),
            HrError::Settings(what) => write!(f, "invalid setting: {what}"),
            HrError::NoSteadyState { band } => write!(
                f,
                "no steady state in band {band}: the scene is closed (no light leaves it), every surface reflects or transmits all of that band, and light is emitted in it, so its radiosity would grow without bound (give some surface a reflectance below 1, or open the scene)"
            ),
            HrError::Diverged { iterations } => write!(
                f,
                "the solution diverged after {iterations} iterations (a radiosity grew without bound), so nothing was written; this is a solver defect: please report the scene"
            ),
            HrError::BadGeometry { polygon } => {
                write!(
                    f,
                    "polygon {polygon} is unusable once placed (its transforms overflow 32-bit floats)"
                )
            }
        }
    }
}

/// A solve error: the solver's own, or the sink's.
#[derive(Debug, PartialEq, Eq)]
pub enum SolveError<E> {
    /// The solver could not run.
    Hr(HrError),
    /// The sink refused a result.
    Sink(E),
}

impl<E> From<HrError> for SolveError<E> {
    fn from(e: HrError) -> Self {
        SolveError::Hr(e)
    }
}

impl<E> From<ImageError> for SolveError<E> {
    fn from(e: ImageError) -> Self {
        SolveError::Hr(HrError::Image(e))
    }
}
