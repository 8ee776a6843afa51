//! Running a solve from the runner: the hierarchical solver with rayon and obvhs (or the
//! core's own BVH), or the exact reference solver.

mod executor;

pub use executor::RayonExecutor;

use crate::output::Progress;
use crate::scene::{self, ExpandVisitor, ExpandedNode, Scene};
use crate::visibility::ObvhsVisibility;
use anyhow::{Context, Result, anyhow, bail};
use glam::Vec3;
use hirad_core::hr::{self, HrError, Plan, Settings, SolveError, Stats};
use hirad_core::sink::Sink;

/// Which ray caster the hierarchical solver uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum VisibilityChoice {
    /// The runner's obvhs BVH (fast; its memory is outside the workspace).
    Obvhs,
    /// The core's own BVH, built inside the workspace (what an embedded caller gets).
    Core,
}

/// What a hierarchical run produced.
#[derive(Clone, Copy, Debug)]
pub struct HrRun {
    /// The solver's statistics.
    pub stats: Stats,
    /// The plan the workspace was sized from.
    pub plan: Plan,
    /// Threads used.
    pub threads: usize,
}

/// World-space corners of every polygon of the expanded scene, in global-id order.
pub fn world_polygons(scene: &Scene) -> Vec<Vec<Vec3>> {
    struct Collect(Vec<Vec<Vec3>>);
    impl ExpandVisitor for Collect {
        type Error = std::convert::Infallible;
        fn node(&mut self, n: &ExpandedNode<'_>) -> Result<(), Self::Error> {
            for p in &n.cluster.polygons {
                let c = &p.corners[..p.corner_count()];
                self.0.push(
                    c.iter()
                        .map(|&i| n.to_world.point(n.cluster.vertices[i as usize]))
                        .collect(),
                );
            }
            Ok(())
        }
    }
    let mut c = Collect(Vec::new());
    let _ = scene::expand(scene, &mut c);
    c.0
}

/// Reports the core's progress on the runner's progress line.
struct ProgressAdapter<'a> {
    bar: &'a Progress,
    phase: String,
}

impl hr::Progress for ProgressAdapter<'_> {
    fn report(&mut self, what: &str, done: u64, total: u64) {
        if what != self.phase {
            self.phase = what.to_string();
            self.bar.phase(what, (total > 0).then_some(total));
        }
        self.bar.set(done);
    }
}

/// Solves `scene` with the hierarchical solver, streaming results into `sink`.
///
/// `memory`: workspace bytes; `None` takes the plan's suggestion.
pub fn solve_hr<K: Sink<Error = anyhow::Error>>(
    scene: &Scene,
    settings: &Settings,
    threads: usize,
    memory: Option<u64>,
    visibility: VisibilityChoice,
    progress: &Progress,
    sink: &mut K,
) -> Result<HrRun> {
    let bytes = scene::compile(scene).map_err(|e| anyhow!("{e}"))?;
    let view = scene::read_image(&bytes).map_err(|e| anyhow!("{e}"))?;
    let internal = visibility == VisibilityChoice::Core;
    let mut scratch = vec![0u8; hr::census_scratch_bytes(&view)];
    let plan = hr::plan(&view, settings, internal, &mut scratch).map_err(|e| anyhow!("{e}"))?;
    let size = memory.unwrap_or(plan.suggested_bytes);
    if size < plan.min_bytes {
        bail!(
            "--memory {size} is too small for this scene: the coarsest solution needs {} bytes (suggested: {})",
            plan.min_bytes,
            plan.suggested_bytes
        );
    }
    let size =
        usize::try_from(size).context("--memory does not fit this machine's address space")?;
    // Ask first, so that an impossible size is an error rather than an abort; then take zeroed
    // pages, which the system hands out lazily: only what the solver uses becomes resident.
    let mut probe: Vec<u8> = Vec::new();
    probe
        .try_reserve_exact(size)
        .map_err(|_| anyhow!("cannot allocate a workspace of {size} bytes (--memory)"))?;
    drop(probe);
    let mut workspace = vec![0u8; size];
    let mut exec = RayonExecutor::new(threads)?;
    let mut adapter = ProgressAdapter {
        bar: progress,
        phase: String::new(),
    };
    let result = match visibility {
        VisibilityChoice::Obvhs => {
            let polygons = world_polygons(scene);
            let vis = ObvhsVisibility::new(&polygons).map_err(|e| anyhow!("{e}"))?;
            drop(polygons);
            hr::solve(
                &view,
                settings,
                &mut workspace,
                Some(&vis),
                &mut exec,
                &mut adapter,
                sink,
            )
        }
        VisibilityChoice::Core => hr::solve(
            &view,
            settings,
            &mut workspace,
            None::<&ObvhsVisibility>,
            &mut exec,
            &mut adapter,
            sink,
        ),
    };
    progress.finish();
    let stats = result.map_err(|e| match e {
        SolveError::Hr(HrError::WorkspaceTooSmall { needed }) => {
            anyhow!("the workspace ({size} bytes) cannot hold even the coarsest solution: it needs {needed} bytes")
        }
        SolveError::Hr(e) => anyhow!("{e}"),
        SolveError::Sink(e) => e,
    })?;
    Ok(HrRun {
        stats,
        plan,
        threads: exec.threads(),
    })
}
