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
mod bins;
mod census;
mod closure;
mod cluster_kernel;
mod cone;
mod correction_filter;
mod direct;
mod emitter_tree;
mod error;
mod eval;
mod exec;
mod final_gather;
mod gather_rays;
mod ids;
mod layout;
mod load;
mod oriented;
mod output;
mod pending;
mod pool;
mod records;
mod refine;
mod relight;
mod rest_scale;
mod sample;
mod shoot;
mod solve;
mod state;
mod vis;

pub use balance::Balance;
pub use census::{Census, census, census_scratch_bytes, grouping_clusters};
pub use error::{HrError, SolveError};
pub use exec::{Executor, NoProgress, Progress, Sequential};

use crate::image::{SceneSource, SceneView};
use crate::sink::Sink;
use crate::visibility::Visibility;
use layout::{ALIGN, Layout};

/// What the caller chooses: speed against accuracy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Refinement threshold: a link is refined while its transfer exceeds `epsilon` times the
    /// scene's emitted power (dimensionless). Smaller is finer and slower.
    pub epsilon: f32,
    /// Smallest patch, as a fraction of the scene's total polygon area.
    pub min_area: f32,
    /// Deepest quadtree subdivision of an input polygon.
    pub max_depth: u32,
    /// Visibility rays per receiver quadrature point (per side) and per cluster link.
    pub rays: u32,
    /// Convergence: stop iterating when the estimated remaining change of any radiosity is
    /// below this fraction of the largest radiosity.
    pub tolerance: f32,
    /// Cap on gather / push-pull iterations per solution.
    pub max_iterations: u32,
    /// Cap on refine-then-solve rounds.
    pub max_rounds: u32,
    /// Most children a cluster keeps before grouping levels are inserted (2..=16).
    pub max_children: u32,
    /// Final gather rays per receiving side of every input polygon (see `final_gather`):
    /// 0 leaves each polygon the hierarchy's irradiance, [`Settings::AUTO`] spreads
    /// 1e3 / epsilon rays over the scene (a million at the default epsilon), at least 64 and
    /// at most 0.65 / epsilon per side. Rounded to a square.
    pub final_rays: u32,
    /// Final gather passes (1..=4, or [`Settings::AUTO`]): with more than one, every leaf
    /// patch first gathers its own light that many times less one (with half the rays of the
    /// polygons' gather), and the polygons' gather reads those radiosities; the first such
    /// pass solves the hierarchy again with what it changed, so the links carry the change
    /// on (see `relight::relight`). `AUTO` relights
    /// at least once and goes on (up to 4 passes in all) while a pass still moves the light
    /// leaving the surfaces by more than [`relight::SETTLED`] of what enters.
    pub final_passes: u32,
    /// Sides of the polygons that suns and sky light directly: bit 0 the fronts, bit 1 the
    /// backs ([`Settings::BOTH_SIDES`], the default: both, as light does). `hirad tables`
    /// lights one side at a time to learn how an original scatters the light that falls on
    /// the fronts and on the backs of its leaves, which reflect differently.
    pub sun_sides: u8,
}

/// Most final gather passes.
pub const MAX_FINAL_PASSES: u32 = 4;

impl Settings {
    /// [`Settings::final_rays`] or [`Settings::final_passes`] chosen from the scene.
    pub const AUTO: u32 = u32::MAX;
    /// [`Settings::sun_sides`]: suns and sky light fronts and backs.
    pub const BOTH_SIDES: u8 = 3;
    /// Most final gather rays per side one may ask for.
    pub const MAX_FINAL_RAYS: u32 = 1 << 20;

    /// Checks every setting's range.
    pub fn check(&self) -> Result<(), HrError> {
        if !(self.epsilon.is_finite() && self.epsilon > 0.0) {
            return Err(HrError::Settings("epsilon must be a positive number"));
        }
        if !(self.min_area.is_finite() && (0.0..1.0).contains(&self.min_area)) {
            return Err(HrError::Settings("min_area must lie in [0, 1)"));
        }
        if self.max_depth > 24 {
            return Err(HrError::Settings("max_depth must be at most 24"));
        }
        if self.rays == 0 || self.rays > 1024 {
            return Err(HrError::Settings("rays must lie in 1..=1024"));
        }
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return Err(HrError::Settings("tolerance must be a positive number"));
        }
        if !(2..=16).contains(&self.max_children) {
            return Err(HrError::Settings("max_children must lie in 2..=16"));
        }
        if !(1..=MAX_FINAL_PASSES).contains(&self.final_passes) && self.final_passes != Self::AUTO {
            return Err(HrError::Settings(
                "final_passes must lie in 1..=4 (or be Settings::AUTO)",
            ));
        }
        if self.final_rays > Self::MAX_FINAL_RAYS && self.final_rays != Self::AUTO {
            return Err(HrError::Settings(
                "final_rays must lie in 0..=1048576 (or be Settings::AUTO)",
            ));
        }
        if !(1..=Self::BOTH_SIDES).contains(&self.sun_sides) {
            return Err(HrError::Settings(
                "sun_sides must lie in 1..=3 (bit 0 fronts, bit 1 backs)",
            ));
        }
        Ok(())
    }
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            epsilon: 1e-3,
            min_area: 1e-6,
            max_depth: 12,
            rays: 4,
            tolerance: 1e-4,
            max_iterations: 20_000,
            max_rounds: 24,
            max_children: 8,
            final_rays: Settings::AUTO,
            final_passes: Settings::AUTO,
            sun_sides: Settings::BOTH_SIDES,
        }
    }
}

/// What a solve did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stats {
    /// Input polygons (after expansion).
    pub polygons: u64,
    /// Clusters (grouping levels included).
    pub clusters: u64,
    /// Patches (input polygons and their sub-patches).
    pub patches: u64,
    /// Links at the end.
    pub links: u64,
    /// Most links alive at once.
    pub peak_links: u64,
    /// Link coefficients computed.
    pub evaluations: u64,
    /// Visibility rays cast.
    pub rays: u64,
    /// Of `rays`, those of each phase.
    pub rays_by_phase: RaysByPhase,
    /// Gather / push-pull iterations, all rounds.
    pub iterations: u64,
    /// Refine-then-solve rounds.
    pub rounds: u32,
    /// Refinement passes, all rounds.
    pub refinement_passes: u64,
    /// Peak workspace bytes in use.
    pub peak_bytes: u64,
    /// Workspace bytes provided.
    pub workspace_bytes: u64,
    /// True when refinement stopped because the workspace was full.
    pub budget_limited: bool,
    /// True when the last solution stopped at the iteration cap before converging.
    pub iteration_capped: bool,
    /// The power epsilon was relative to at the end (W, largest band): what leaves all
    /// surfaces, emitted and reflected.
    pub emitted_power: f32,
    /// True when the last solution met the tolerance (false: it stopped at the iteration
    /// cap, see `remaining_change`).
    pub converged: bool,
    /// The estimated change still to come in the last solution, relative to the largest
    /// radiosity (the geometric tail of the last iterations' changes).
    pub remaining_change: f32,
    /// True when a radiosity grew without bound (not finite): the solution is meaningless and
    /// `converged` is false.
    pub diverged: bool,
    /// Where the power went, per band.
    pub balance: Balance,
    /// Final gather passes made, the polygons' own included (0 without the gather).
    pub final_passes: u32,
    /// How much the last relighting pass moved the light leaving the surfaces, relative to
    /// what enters (largest band; 0 with fewer than two passes).
    pub final_change: f32,
}

/// Visibility rays per phase of a solve (what the ray count of [`Stats`] is spent on).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RaysByPhase {
    /// Direct light of suns and sky on every patch, its buried points, the closed-scene test.
    pub lighting: u64,
    /// Visibility of links.
    pub links: u64,
    /// The final gather: relighting passes and the polygons' own gather.
    pub final_gather: u64,
}

/// What a scene needs, in bytes of workspace.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Plan {
    /// The expanded scene's counts.
    pub census: Census,
    /// Bytes of the static part (everything but the growing pools) at `min_bytes`.
    pub static_bytes: u64,
    /// The least workspace that holds the coarsest solution (input polygons, initial links).
    pub min_bytes: u64,
    /// A workspace that usually lets refinement finish at this epsilon (an estimate: the run
    /// reports whether the budget limited it).
    pub suggested_bytes: u64,
    /// Bytes per patch of a one-sided / two-sided polygon.
    pub patch_bytes: [u64; 2],
    /// Bytes per link.
    pub link_bytes: u64,
}

/// Tolerance of the solutions between refinement rounds (relative to the largest radiosity;
/// the last solution meets [`Settings::tolerance`]).
const LOOSE_TOLERANCE: f32 = 1e-2;

/// Aligns the workspace start; returns the usable part.
fn aligned(ws: &mut [u8]) -> &mut [u8] {
    let skip = ws.as_ptr().align_offset(ALIGN).min(ws.len());
    &mut ws[skip..]
}

/// Plans a solve: the exact minimum and a suggested workspace size. `scratch` must hold
/// [`census_scratch_bytes`]. `internal_bvh`: whether the solve will build the core's own BVH
/// in the workspace (no visibility given to [`solve`]) rather than use the caller's.
pub fn plan<S: SceneSource>(
    view: &SceneView<S>,
    settings: &Settings,
    internal_bvh: bool,
    scratch: &mut [u8],
) -> Result<Plan, HrError> {
    settings.check()?;
    let c = census(view, settings.max_children, scratch)?;
    plan_from(view, settings, internal_bvh, &c)
}

fn sources<S: SceneSource>(view: &SceneView<S>) -> u32 {
    view.info().suns + view.info().sky
}

fn plan_from<S: SceneSource>(
    view: &SceneView<S>,
    settings: &Settings,
    internal: bool,
    c: &Census,
) -> Result<Plan, HrError> {
    let info = view.info();
    let bands = info.bands as usize;
    let lay0 = Layout::new(
        c,
        info.materials,
        sources(view),
        bands,
        settings,
        internal,
        usize::MAX / 4,
    )
    .ok_or(HrError::SceneTooLarge)?;
    let st = lay0.strides;
    let fits = |total: u64| -> bool {
        let Some(lay) = Layout::new(
            c,
            info.materials,
            sources(view),
            bands,
            settings,
            internal,
            total as usize,
        ) else {
            return false;
        };
        let per = |stride: usize| (lay.block_size / stride) as u64;
        let blocks = |n: u64, stride: usize| {
            if n == 0 {
                0
            } else {
                n.div_ceil(per(stride).max(1))
            }
        };
        let links = 2 + sources(view) as u64 + 64;
        let total = blocks(c.polys_one_sided, st.patch1)
            + blocks(c.polys_two_sided, st.patch2)
            + blocks(links, st.link);
        per(st.patch2) > 0 && per(st.link) > 0 && total <= lay.block_count as u64
    };
    // The smallest workspace whose layout holds the coarsest solution.
    let mut lo = lay0.fixed_bytes as u64;
    let mut hi = lo.saturating_mul(2).saturating_add(1 << 20);
    while !fits(hi) {
        lo = hi;
        hi = hi.checked_mul(2).ok_or(HrError::SceneTooLarge)?;
    }
    while lo + 1024 < hi {
        let mid = lo + (hi - lo) / 2;
        if fits(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let min_bytes = hi + ALIGN as u64;
    // Measured at epsilon 1e-3 (BENCHMARKS.md): plant and furniture scenes end near 1.3
    // patches and 1 to 5 links per polygon; large surfaces (walls, floors) add some thousands
    // of each, growing as 1/epsilon, the per-polygon part more slowly. Twice that, never less
    // than 16 MiB (nothing on a desktop; embedded callers set their own budget).
    let s = (1e-3 / settings.epsilon.max(1e-9)).clamp(0.1, 1000.0) as f64;
    let polys = c.polygons() as f64;
    let patches = 2.0 * (2.0 * polys * libm::sqrt(s) + 8000.0 * s);
    let links = 2.0 * (8.0 * polys * libm::sqrt(s) + 12000.0 * s);
    let patch_avg = if polys > 0.0 {
        (c.polys_one_sided as f64 * st.patch1 as f64 + c.polys_two_sided as f64 * st.patch2 as f64)
            / polys
    } else {
        st.patch1 as f64
    };
    // Emission bins (power and area): at most one cluster in 16 polygons is large enough to
    // keep them.
    let bins = polys / 16.0 * 2.0 * st.bins as f64;
    let grow = patches * patch_avg + links * st.link as f64 + bins;
    let suggested = (min_bytes as f64 + grow * 1.05)
        .max(16.0 * 1024.0 * 1024.0)
        .min(u64::MAX as f64 / 2.0) as u64;
    let at_min = Layout::new(
        c,
        info.materials,
        sources(view),
        bands,
        settings,
        internal,
        min_bytes as usize,
    )
    .ok_or(HrError::SceneTooLarge)?;
    Ok(Plan {
        census: *c,
        static_bytes: at_min.static_bytes as u64,
        min_bytes,
        suggested_bytes: suggested.max(min_bytes),
        patch_bytes: [st.patch1 as u64, st.patch2 as u64],
        link_bytes: st.link as u64,
    })
}

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
    let mut run = Run::start(view, settings, workspace, visibility, executor, progress)?;
    run.rounds(progress);
    run.finish(progress, sink)
}

/// A solve under way: the state, the workspace's main part, visibility, and the executor
/// with the workspace's scratch.
struct Run<'w, V: ?Sized, E: Executor> {
    st: state::State,
    ws: &'w mut [u8],
    vis: vis::Vis<'w, V>,
    seq: exec::Fallback<'w, E>,
}

/// The workspace's parts for a layout: the main part, the core BVH's bytes, the executor's
/// scratch.
type Parts<'w> = (&'w mut [u8], &'w mut [u8], &'w mut [f32]);

fn parts<'w>(lay: &Layout, ws: &'w mut [u8], min_bytes: u64) -> Result<Parts<'w>, HrError> {
    let too_small = HrError::WorkspaceTooSmall { needed: min_bytes };
    if ws.len() < lay.main_bytes + lay.bvh_bytes + lay.scratch_floats * 4 {
        return Err(too_small);
    }
    let (main, rest) = ws.split_at_mut(lay.main_bytes);
    let (bvh_bytes, scratch_bytes) = rest.split_at_mut(lay.bvh_bytes);
    let scratch: &mut [f32] =
        bytemuck::try_cast_slice_mut(&mut scratch_bytes[..lay.scratch_floats * 4])
            .map_err(|_| too_small)?;
    Ok((main, bvh_bytes, scratch))
}

impl<'w, V: Visibility + ?Sized, E: Executor> Run<'w, V, E> {
    /// Counts, lays out and loads the scene, builds the core's BVH when no visibility is
    /// given, lights every patch, and evaluates the first links.
    fn start<S: SceneSource, P: Progress>(
        view: &SceneView<S>,
        settings: &Settings,
        workspace: &'w mut [u8],
        visibility: Option<&'w V>,
        executor: &'w mut E,
        progress: &mut P,
    ) -> Result<Self, HrError> {
        settings.check()?;
        let total = workspace.len();
        let ws = aligned(workspace);
        // Count the scene with the workspace itself as scratch, then lay it out.
        let need = census_scratch_bytes(view);
        if ws.len() < need {
            return Err(HrError::WorkspaceTooSmall {
                needed: need as u64,
            });
        }
        let c = census(view, settings.max_children, &mut ws[..need])?;
        if c.polygons() == 0 {
            return Err(HrError::Empty);
        }
        let internal = visibility.is_none();
        let plan = plan_from(view, settings, internal, &c)?;
        let info = view.info();
        let lay = Layout::new(
            &c,
            info.materials,
            sources(view),
            info.bands as usize,
            settings,
            internal,
            ws.len(),
        )
        .ok_or(HrError::WorkspaceTooSmall {
            needed: plan.min_bytes,
        })?;
        let (ws, bvh_bytes, scratch) = parts(&lay, ws, plan.min_bytes)?;
        let mut st = load::load(view, settings, &c, lay, ws).map_err(|e| match e {
            HrError::WorkspaceTooSmall { .. } => HrError::WorkspaceTooSmall {
                needed: plan.min_bytes,
            },
            e => e,
        })?;
        let vis = match visibility {
            Some(v) => vis::Vis::External(v),
            None => {
                let n = st.polygons as usize;
                let (nodes, order) = bvh_bytes.split_at_mut(
                    crate::bvh::nodes_needed(st.polygons)
                        * core::mem::size_of::<crate::bvh::BvhNode>(),
                );
                let nodes: &mut [crate::bvh::BvhNode] =
                    bytemuck::try_cast_slice_mut(nodes).map_err(|_| HrError::SceneTooLarge)?;
                let order: &mut [u32] = bytemuck::try_cast_slice_mut(&mut order[..4 * n])
                    .map_err(|_| HrError::SceneTooLarge)?;
                let polys = vis::WsPolygons { st: &st, ws };
                let bvh = crate::bvh::build(
                    st.polygons,
                    |id| crate::bvh::PolygonSet::bounds(&polys, id),
                    nodes,
                    order,
                )
                .map_err(|e| match e {
                    crate::bvh::BvhError::InvalidBounds { primitive } => HrError::BadGeometry {
                        polygon: primitive as u64,
                    },
                    _ => HrError::SceneTooLarge,
                })?;
                vis::Vis::Internal(bvh)
            }
        };
        st.stats.workspace_bytes = total as u64;
        bins::allocate(&mut st, ws);
        progress.report("loaded (polygons)", st.polygons as u64, st.polygons as u64);
        let mut seq = exec::Fallback {
            inner: executor,
            scratch,
        };
        direct::prepare_pending(&mut st, ws, &vis, &mut seq, progress);
        bins::areas(&st, ws);
        direct::test_closed(&mut st, ws, &vis);
        if let Some(band) = direct::no_steady_state(&st, ws) {
            return Err(HrError::NoSteadyState { band: band as u32 });
        }
        solve::pull(&st, ws);
        st.power = solve::flow(&st, ws).max(f32::MIN_POSITIVE);
        pending::evaluate_pending(&mut st, ws, &vis, &mut seq, progress);
        Ok(Run { st, ws, vis, seq })
    }

    /// Refinement round `round`: refine until stable, close, solve (to the loose tolerance
    /// unless nothing was refined or it is the last round allowed). Returns whether the
    /// rounds are over.
    fn round<P: Progress>(&mut self, round: u32, progress: &mut P) -> bool {
        let settings = self.st.settings;
        let (st, ws) = (&mut self.st, &mut *self.ws);
        st.stats.rounds = round + 1;
        let refined = refine::refine_until_stable(st, ws, &self.vis, &mut self.seq, progress);
        closure::update(st, ws, &mut self.seq, progress);
        let last = !refined && round > 0;
        let final_tolerance = last || round + 1 == settings.max_rounds;
        // While refinement goes on, each solution only guides the next refinement: it is
        // taken to a looser tolerance; the last one to the one asked for.
        let tol = if final_tolerance {
            settings.tolerance
        } else {
            settings.tolerance.max(LOOSE_TOLERANCE)
        };
        solve::iterate(st, ws, &mut self.seq, progress, tol);
        if st.stats.diverged {
            return true;
        }
        st.power = solve::flow(st, ws).max(f32::MIN_POSITIVE);
        if last {
            return true;
        }
        refine::clear_examined(st, ws);
        if final_tolerance {
            // Out of rounds while still refining: the solution meets the tolerance asked for
            // all the same.
            return true;
        }
        false
    }

    /// Every refinement round, until nothing refines or the rounds run out.
    fn rounds<P: Progress>(&mut self, progress: &mut P) {
        if self.st.settings.max_rounds == 0 {
            // No refinement at all: the coarsest solution, to the tolerance asked for.
            let tol = self.st.settings.tolerance;
            solve::iterate(&mut self.st, self.ws, &mut self.seq, progress, tol);
            return;
        }
        for round in 0..self.st.settings.max_rounds {
            if self.round(round, progress) {
                break;
            }
        }
    }

    /// The final passes: statistics, the relighting passes of the final gather, the power
    /// balance, and every polygon to the sink.
    fn finish<K: Sink, P: Progress>(
        mut self,
        progress: &mut P,
        sink: &mut K,
    ) -> Result<Stats, SolveError<K::Error>> {
        let (st, ws) = (&mut self.st, &mut *self.ws);
        if st.stats.diverged {
            // Radiosities without bound: no sink would take them, and none mean anything.
            return Err(SolveError::Hr(HrError::Diverged {
                iterations: st.stats.iterations,
            }));
        }
        st.stats.links = st.links.live() as u64;
        st.stats.clusters = st.clusters as u64;
        st.stats.patches = st.patches[0].len as u64 + st.patches[1].len as u64;
        st.stats.peak_bytes = st.stats.peak_bytes.max(st.bytes_in_use() as u64);
        st.stats.emitted_power = st.power;
        if gather_rays::rays_per_side(st, ws) > 0 {
            gather_rays::note_shares(st, ws);
            relight::relight_passes(st, ws, &self.vis, &mut self.seq, progress);
        }
        let rays = 4 * st.settings.rays;
        st.stats.balance = balance::measure(st, ws, &self.vis, &mut self.seq, rays, progress);
        progress.report(output::phase(st, ws), 0, st.polygons as u64);
        let written = output::emit(st, ws, &self.vis, &mut self.seq, progress, sink)
            .map_err(SolveError::Sink)?;
        st.stats.rays += written.rays;
        st.stats.rays_by_phase.final_gather += written.rays;
        if let Some(absorbed) = written.absorbed {
            st.stats.balance.absorbed = absorbed;
        }
        Ok(st.stats)
    }
}

/// Hooks for the benchmarks (`benches/hr.rs`): one phase of a solve at a time, from a state
/// that can be copied with its workspace and run again. Not a stable interface.
#[doc(hidden)]
pub mod bench;

/// A diagnostic of the transport link by link, for `examples/audit.rs` (through `bench`).
#[doc(hidden)]
pub mod audit;
