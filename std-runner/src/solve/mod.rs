//! Running a solve from the runner: the hierarchical solver with rayon and obvhs (or the
//! core's own BVH), or the exact reference solver.

mod counted;
mod executor;
mod overlap;
pub mod policy;
#[cfg(test)]
mod tests_adapter;

pub use executor::{RayonExecutor, scoped};
use std::time::Instant;

use crate::output::Progress;
use crate::scene::{self, ExpandVisitor, ExpandedNode, Scene};
use crate::visibility::ObvhsVisibility;
use anyhow::{Context, Result, anyhow};
use glam::Vec3;
use hirad_core::hr::{self, HiPlan, HrError, Inline, Plan, Settings, SolveError, Stats};
use hirad_core::image::{SceneSource, SceneView};
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
#[derive(Clone, Debug)]
pub struct HrRun {
    /// The solver's statistics.
    pub stats: Stats,
    /// Wall-clock seconds per phase, in the order the phases first ran (a phase that runs
    /// again, as refining and evaluating links do every round, adds to its first entry):
    /// "setup" (compiling the scene, building the ray caster and the workspace), then the
    /// solver's phases as its progress names them, without their units.
    pub phases: Vec<(String, f64)>,
    /// The plan the workspace was sized from.
    pub plan: Plan,
    /// Threads used.
    pub threads: usize,
    /// `Settings::own_polygons` as solved: the setting, or 0 where a budget turned it off.
    pub own_polygons: u32,
    /// `Settings::blocking_polygons` as solved: the setting, or 0 where a budget turned it
    /// off.
    pub blocking_polygons: u32,
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

/// Reports the core's progress on the runner's progress line, and times its phases.
struct ProgressAdapter<'a> {
    bar: &'a Progress,
    phase: String,
    /// Refinement passes started: the phases that every pass runs again are shown with
    /// theirs, each going from 0 to 100% (one bar over all passes would run backwards as
    /// the passes add links).
    pass: u64,
    /// Levels loaded: hi's opened levels each refine with passes of their own, which one
    /// count over all of them would not number (a line said "pass 597"): only the first
    /// level's passes are numbered.
    loads: u64,
    /// Seconds per phase name (without the units in parentheses), in order of appearance.
    times: Vec<(String, f64)>,
    /// The phase being timed (index into `times`) and since when.
    current: Option<(usize, Instant)>,
}

impl ProgressAdapter<'_> {
    /// Starts timing `name` (closing the phase before it).
    fn start(&mut self, name: &str, now: Instant) {
        self.stop(now);
        let i = match self.times.iter().position(|(n, _)| n == name) {
            Some(i) => i,
            None => {
                self.times.push((name.to_string(), 0.0));
                self.times.len() - 1
            }
        };
        self.current = Some((i, now));
    }

    /// Adds the running phase's time.
    fn stop(&mut self, now: Instant) {
        if let Some((i, since)) = self.current.take() {
            self.times[i].1 += now.duration_since(since).as_secs_f64();
        }
    }
}

/// A phase's name without its units: "refining (links)" -> "refining".
fn phase_name(what: &str) -> &str {
    what.split(" (").next().unwrap_or(what).trim()
}

impl hr::Progress for ProgressAdapter<'_> {
    fn report(&mut self, what: &str, done: u64, total: u64) {
        if what != self.phase {
            self.phase = what.to_string();
            let name = phase_name(what).to_string();
            match name.as_str() {
                "refining" => self.pass += 1,
                "loaded" => self.loads += 1,
                _ => {}
            }
            let label = match name.as_str() {
                "refining" | "lighting patches" | "evaluating links"
                    if self.pass > 0 && self.loads <= 1 =>
                {
                    format!("pass {}: {what}", self.pass)
                }
                _ => what.to_string(),
            };
            self.bar
                .phase_at(&label, (total > 0).then_some(total), done);
            if self.current.is_none_or(|(i, _)| self.times[i].0 != name) {
                self.start(&name, Instant::now());
            }
        } else {
            self.bar.set_of(done, (total > 0).then_some(total));
        }
    }
}

/// The exit class of a solver error (see [`crate::exit`]): the scene's faults are input
/// errors, the settings' usage errors, a diverged solution results that are not right.
fn classify(e: HrError) -> anyhow::Error {
    let error = anyhow!("{e}");
    match e {
        HrError::Image(_)
        | HrError::SceneTooLarge
        | HrError::NoLight
        | HrError::Empty
        | HrError::BadGeometry { .. }
        | HrError::NoSteadyState { .. }
        | HrError::NoTables { .. } => crate::exit::input(error),
        HrError::WorkspaceTooSmall { .. } | HrError::Settings(_) => crate::exit::usage(error),
        HrError::Diverged { .. } => crate::exit::not_right(error),
        HrError::ScratchTooSmall | HrError::Cancelled => error,
    }
}

/// Workspaces up to this size (bytes) are allocated without a probe first (see `solve_hr`).
const PROBE_ABOVE: usize = 32 << 20;

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
    run_hr(
        scene, settings, None, threads, memory, visibility, progress, sink,
    )
}

/// Solves `scene` by hierarchical instantiation (`hirad_core::hr::solve_hi`: level by
/// level, the instances closed through the tables the scene carries, those of the originals
/// `inline` names expanded in place: see [`policy`]), streaming results into `sink` in
/// global-id order.
#[allow(clippy::too_many_arguments)]
pub fn solve_hi<K: Sink<Error = anyhow::Error>>(
    scene: &Scene,
    settings: &Settings,
    inline: Inline<'_>,
    threads: usize,
    memory: Option<u64>,
    progress: &Progress,
    sink: &mut K,
) -> Result<HrRun> {
    run_hr(
        scene,
        settings,
        Some(inline),
        threads,
        memory,
        VisibilityChoice::Core,
        progress,
        sink,
    )
}

/// [`solve_hi`] straight from a scene image (a `.hirb` file read on demand, see
/// `files::FileSource`): the tables are read into the workspace once, and no other copy of
/// them is held.
#[allow(clippy::too_many_arguments)]
pub fn solve_hi_image<S: SceneSource + Sync, K: Sink<Error = anyhow::Error>>(
    view: &SceneView<S>,
    settings: &Settings,
    inline: Inline<'_>,
    threads: usize,
    memory: Option<u64>,
    progress: &Progress,
    sink: &mut K,
) -> Result<HrRun> {
    let setup = Instant::now();
    run_view(
        view,
        None,
        settings,
        Some(inline),
        threads,
        memory,
        VisibilityChoice::Core,
        progress,
        sink,
        setup,
    )
}

#[allow(clippy::too_many_arguments)]
fn run_hr<K: Sink<Error = anyhow::Error>>(
    scene: &Scene,
    settings: &Settings,
    hi: Option<Inline<'_>>,
    threads: usize,
    memory: Option<u64>,
    visibility: VisibilityChoice,
    progress: &Progress,
    sink: &mut K,
) -> Result<HrRun> {
    let setup = Instant::now();
    let bytes = scene::compile(scene).map_err(|e| crate::exit::input(anyhow!("{e}")))?;
    let view = scene::read_image(&bytes).map_err(|e| crate::exit::input(anyhow!("{e}")))?;
    run_view(
        &view,
        Some(scene),
        settings,
        hi,
        threads,
        memory,
        visibility,
        progress,
        sink,
        setup,
    )
}

/// `b` bytes in MiB.
fn mib(b: u64) -> f64 {
    b as f64 / (1u64 << 20) as f64
}

/// A change of settings that lowers hi's least: what it turns off, the least it answers
/// (bytes of a plan), and what the note says of it.
struct Fallback {
    without: fn(&Settings) -> Option<Settings>,
    least: fn(&HiPlan) -> u64,
    why: &'static str,
}

/// The fallbacks in order: below the least with its margins the approximate instances' own
/// polygons go; below what surely fails (the paper stand ran in 34 MiB against a least of
/// 39.1 MiB with its margins) the originals' blocking polygons too, closed instances then
/// taking each other's light through links (the light between them by rays keeps about
/// 10 KB per instance).
const FALLBACKS: [Fallback; 2] = [
    Fallback {
        without: |s| {
            (s.own_polygons > 0).then_some(Settings {
                own_polygons: 0,
                ..*s
            })
        },
        least: |p| p.min_bytes,
        why: "with which hi's plan surely opens every level with closed approximate instances blocking by their own polygons: they block as their originals do (--own-polygons 0",
    },
    Fallback {
        without: |s| {
            (s.blocking_polygons > 0).then_some(Settings {
                own_polygons: 0,
                blocking_polygons: 0,
                ..*s
            })
        },
        least: |p| p.bare_min_bytes,
        why: "without which hi's plan surely fails with closed instances blocking by their originals' polygons: they block by their tables' transmittance and take each other's light through links (--blocking-polygons 0",
    },
];

/// hi's plan of `view` and the settings it solves with under the budget `memory`: each of
/// [`FALLBACKS`] taken where the budget is below its least and the plan without is smaller
/// (a note says so, on the progress line's stream).
fn budget_plan<S: SceneSource>(
    view: &SceneView<S>,
    settings: Settings,
    inline: Inline<'_>,
    memory: Option<u64>,
    progress: &Progress,
) -> Result<(Settings, HiPlan)> {
    hi_budget_plan(view, settings, inline, memory, &mut |note| {
        if progress.enabled() {
            eprintln!("note: {note}");
        }
    })
    .map_err(classify)
}

/// hi's plan of `view` and the settings it solves with under the budget `memory` (bytes;
/// `None`: no budget, the settings as given): each of [`FALLBACKS`] taken where the budget is
/// below its least and the plan without is smaller, `note` told why (a sentence without
/// "note: "). What `hirad solve --method hi --memory` and the C ABI both solve with.
pub fn hi_budget_plan<S: SceneSource>(
    view: &SceneView<S>,
    settings: Settings,
    inline: Inline<'_>,
    memory: Option<u64>,
    note: &mut dyn FnMut(String),
) -> Result<(Settings, HiPlan), HrError> {
    let mut scratch = vec![0u8; hr::plan_hi_scratch_bytes(view)];
    let mut settings = settings;
    let mut p = hr::plan_hi(view, &settings, inline, &mut scratch)?;
    let Some(m) = memory else {
        return Ok((settings, p));
    };
    for f in &FALLBACKS {
        let Some(without) = (f.without)(&settings).filter(|_| m < (f.least)(&p)) else {
            continue;
        };
        let q = hr::plan_hi(view, &without, inline, &mut scratch)?;
        if (f.least)(&q) < (f.least)(&p) {
            note(format!(
                "--memory {:.1} MiB is less than the {:.1} MiB {}: {:.1} MiB surely opens every level)",
                mib(m),
                mib((f.least)(&p)),
                f.why,
                mib(q.min_bytes)
            ));
            settings = without;
            p = q;
        }
    }
    Ok((settings, p))
}

/// A note on the top level's closed instances' received light when it takes more than a
/// quarter of the budget `m` (bytes): tables that keep each polygon's first scattering
/// apart hold 16 bytes per polygon and instance at two bands, which `hirad tables
/// --max-single-side 0` avoids.
fn received_note<S: SceneSource>(
    view: &SceneView<S>,
    settings: &Settings,
    inline: Inline<'_>,
    m: u64,
) -> Option<String> {
    let mut scratch = vec![0u8; hr::census_scratch_bytes(view)];
    let c = hr::census_level(
        view,
        settings.max_children,
        hr::Instancing::Top,
        inline,
        hr::BlockingLimits::of(settings),
        &mut scratch,
    )
    .ok()?;
    let bytes = c.received_floats.saturating_mul(4);
    (bytes > m / 4).then(|| {
        format!(
            "note: the top level's {} closed instances keep {:.1} MiB of received light; tables made with `hirad tables --max-single-side 0` keep no polygon's first scattering apart (16 bytes per polygon and instance at two bands), at some accuracy in sunlit leaves",
            c.instances,
            mib(bytes)
        )
    })
}

/// Solves the scene image `view` (`scene`, its model, for a caller's ray caster).
#[allow(clippy::too_many_arguments)]
fn run_view<S: SceneSource + Sync, K: Sink<Error = anyhow::Error>>(
    view: &SceneView<S>,
    scene: Option<&Scene>,
    settings: &Settings,
    hi_inline: Option<Inline<'_>>,
    threads: usize,
    memory: Option<u64>,
    visibility: VisibilityChoice,
    progress: &Progress,
    sink: &mut K,
    setup: Instant,
) -> Result<HrRun> {
    let hi = hi_inline.is_some();
    let internal = visibility == VisibilityChoice::Core || hi;
    let mut scratch = vec![0u8; hr::census_scratch_bytes(view)];
    let plan = hr::plan(view, settings, internal, &mut scratch).map_err(classify)?;
    // Hierarchical instantiation holds one path of levels: without a budget it gets its own
    // plan's suggestion (the top level's estimated plan and room for its widest closed
    // instances side by side), whatever the expanded scene would need.
    let (settings, hi_plan) = match hi_inline {
        Some(inline) => {
            let (solved, p) = budget_plan(view, *settings, inline, memory, progress)?;
            (solved, Some(p))
        }
        None => (*settings, None),
    };
    let settings = &settings;
    let size = match (memory, hi_plan) {
        // Below hi's least with its margin a level may find too little room hours in: say
        // so before the solve starts (it tries: the paper stand ran in 34 MiB against a
        // least of 39.1 MiB).
        (Some(m), Some(p)) => {
            if progress.enabled() && m < p.min_bytes {
                eprintln!(
                    "warning: --memory {:.1} MiB is less than the {:.1} MiB with which hi's plan surely opens every level: the solve tries, and stops (exit 2) if a level does not fit",
                    mib(m),
                    mib(p.min_bytes)
                );
                if let Some(inline) = hi_inline
                    && m < p.bare_min_bytes
                    && let Some(note) = received_note(view, settings, inline, m)
                {
                    eprintln!("{note}");
                }
            }
            m
        }
        (Some(m), None) => m,
        (None, Some(p)) => {
            if progress.enabled() {
                eprintln!(
                    "note: workspace {:.1} MiB, hi's own plan: the top level {:.1} MiB, room for its closed instances {:.1} MiB ({:.1} MiB surely opens every level; --memory sets a budget)",
                    mib(p.suggested_bytes),
                    mib(p.top_level_bytes),
                    mib(p.children_bytes),
                    mib(p.min_bytes)
                );
            }
            p.suggested_bytes
        }
        (None, None) => plan.suggested_bytes,
    };
    if size < plan.min_bytes && !hi {
        return Err(crate::exit::usage(anyhow!(
            "--memory {size} is too small for this scene: the coarsest solution needs {} bytes (suggested: {})",
            plan.min_bytes,
            plan.suggested_bytes
        )));
    }
    let size =
        usize::try_from(size).context("--memory does not fit this machine's address space")?;
    // Ask first, so that an impossible size is an error rather than an abort; then take zeroed
    // pages, which the system hands out lazily: only what the solver uses becomes resident.
    // Only for sizes where an abort is possible at all: freeing a probe below glibc's
    // largest mmap threshold (32 MiB) raises the threshold, and the zeroed workspace then
    // comes from the heap and is cleared byte by byte (4% of a Cornell solve's instructions).
    if size > PROBE_ABOVE {
        let mut probe: Vec<u8> = Vec::new();
        probe
            .try_reserve_exact(size)
            .map_err(|_| anyhow!("cannot allocate a workspace of {size} bytes (--memory)"))?;
        drop(probe);
    }
    let mut workspace = vec![0u8; size];
    let mut exec = RayonExecutor::new(threads)?;
    let mut adapter = ProgressAdapter {
        bar: progress,
        phase: String::new(),
        pass: 0,
        loads: 0,
        times: Vec::new(),
        current: None,
    };
    adapter.times.push(("setup".to_string(), 0.0));
    adapter.current = Some((0, setup));
    let result = match visibility {
        _ if let Some(inline) = hi_inline => hr::solve_hi(
            view,
            settings,
            inline,
            &mut workspace,
            &mut exec,
            &mut adapter,
            &mut counted::Counted {
                inner: sink,
                progress,
                done: 0,
                total: view.info().expanded_polygons,
            },
        ),
        VisibilityChoice::Obvhs if let Some(scene) = scene => {
            let polygons = world_polygons(scene);
            let directions: Vec<Vec3> = scene.suns.iter().map(|l| l.towards).collect();
            let vis = ObvhsVisibility::new(&polygons)
                .map_err(|e| anyhow!("{e}"))?
                .with_directions(&polygons, &directions);
            drop(polygons);
            hr::solve(
                view,
                settings,
                &mut workspace,
                Some(&vis),
                &mut exec,
                &mut adapter,
                sink,
            )
        }
        _ => hr::solve(
            view,
            settings,
            &mut workspace,
            None::<&ObvhsVisibility>,
            &mut exec,
            &mut adapter,
            sink,
        ),
    };
    adapter.stop(Instant::now());
    let phases = adapter.times;
    progress.finish();
    let stats = result.map_err(|e| match e {
        SolveError::Hr(HrError::WorkspaceTooSmall { needed }) => {
            crate::exit::usage(anyhow!("the workspace ({size} bytes) cannot hold even the coarsest solution: it needs {needed} bytes"))
        }
        SolveError::Hr(e) => classify(e),
        SolveError::Sink(e) => e,
    })?;
    Ok(HrRun {
        stats,
        phases,
        plan,
        threads: exec.threads(),
        own_polygons: settings.own_polygons,
        blocking_polygons: settings.blocking_polygons,
    })
}
