//! Hierarchical radiosity with clustering over the whole (expanded) scene, in a workspace the
//! caller provides.
//!
//! The scene is loaded into a cluster hierarchy (crowded clusters get grouping levels); links
//! start from a self-link on the root and from each directional source to the root, and are
//! refined while a link's transfer (emitter radiosity x form factor x receiver area) exceeds
//! `epsilon` times the scene's emitted power, by splitting clusters and subdividing polygons
//! into quadtree patches. Form factors to polygons are exact point-to-polygon integrals over
//! fixed receiver quadrature points (so they close to 1 in closed scenes), times visibility
//! from several deterministic rays; clusters exchange light as isotropic volumes. Gathering
//! and push-pull iterate to convergence; refinement and solution alternate until nothing
//! refines. Every byte comes from the workspace; a full workspace stops refinement and is
//! reported, never a panic.
//!
//! Work that dominates (evaluating links, gathering) runs in fixed chunks through an
//! [`Executor`], so that a caller can spread it over threads: chunks are independent and
//! applied in order, so results are bit-identical for any number of threads.

mod balance;
mod beams;
mod bins;
mod blockers;
mod census;
mod closure;
mod cluster_kernel;
mod cone;
mod correction_filter;
mod direct;
mod emitter_tree;
mod emitters;
mod error;
mod eval;
mod eval_gathered;
mod eval_reciprocal;
mod exchange;
mod exec;
mod final_gather;
mod gather_rays;
mod group;
mod ids;
mod instance_gather;
mod instance_kernel;
mod instance_light;
mod layout;
mod level;
mod load;
mod load_instances;
mod local_field;
mod noted_radiance;
mod open;
mod oriented;
mod original_geometry;
mod output;
mod pending;
mod plan;
mod plan_hi;
mod polygon_light;
mod pool;
mod reach;
mod recorder;
mod records;
mod refine;
mod relight;
mod rest_scale;
mod room;
mod run;
mod sample;
mod settings;
mod shoot;
mod siblings;
mod solve;
mod state;
mod tally;
mod vis;

pub use balance::Balance;
pub use census::{Census, census, census_level, census_scratch_bytes, grouping_clusters};
pub use error::{HrError, SolveError};
pub use exec::{Executor, NoProgress, Progress, Sequential};
pub use open::solve_hi;
pub use plan::{Plan, plan};
pub use plan_hi::{HiPlan, plan_hi, plan_hi_scratch_bytes};
pub use settings::{
    BlockingLimits, Inline, Instancing, MAX_FINAL_PASSES, RaysByPhase, Settings, Stats,
    WorkspaceRegions,
};

use crate::image::{SceneSource, SceneView};
use crate::sink::Sink;
use crate::visibility::Visibility;
use run::Run;

/// Solves the scene and hands every polygon to `sink` in global-id order.
///
/// `workspace` is all the memory the solver uses; [`plan`] says how much a scene needs.
/// `visibility`: the caller's ray caster (polygon ids are global ids), or `None` for the
/// core's own BVH, built in the workspace.
pub fn solve<S, V, K, E, P>(
    view: &SceneView<S>,
    settings: &Settings,
    workspace: &mut [u8],
    visibility: Option<&V>,
    executor: &mut E,
    progress: &mut P,
    sink: &mut K,
) -> Result<Stats, SolveError<K::Error>>
where
    S: SceneSource,
    V: Visibility + ?Sized,
    K: Sink,
    E: Executor,
    P: Progress,
{
    let mut run = Run::start(
        view,
        settings,
        Instancing::None,
        &level::LevelRoot::scene(view),
        None,
        workspace,
        visibility,
        executor,
        progress,
    )?;
    run.rounds(progress);
    run.finish(progress, sink)
}

/// Hooks for the benchmarks (`benches/hr.rs`): one phase of a solve at a time, from a state
/// that can be copied with its workspace and run again. Not a stable interface.
#[doc(hidden)]
pub mod bench;

/// Hooks for the tests of a level with closed instances (issue 18, under construction).
/// Not a stable interface.
#[doc(hidden)]
pub mod level_probe;

/// A diagnostic of the transport link by link, for `examples/audit.rs` (through `bench`).
#[doc(hidden)]
pub mod audit;
