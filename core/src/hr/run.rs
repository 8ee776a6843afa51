//! The driver of a solve: start (count, lay out, load, light), refinement rounds, finish
//! (final gather, balance, polygons to the sink).

use super::census::{census_at, census_scratch_bytes};
use super::error::{HrError, SolveError};
use super::exec::{self, Executor, Progress};
use super::layout::Layout;
use super::level::LevelRoot;
use super::plan::{aligned, plan_level};
use super::settings::{Instancing, Settings, Stats};
use super::{
    balance, bins, closure, direct, gather_rays, instance_light, load, output, pending, refine,
    relight, solve, state, vis,
};
use crate::image::{SceneSource, SceneView};
use crate::sink::Sink;
use crate::visibility::Visibility;

/// Tolerance of the solutions between refinement rounds (relative to the largest radiosity;
/// the last solution meets [`Settings::tolerance`]).
const LOOSE_TOLERANCE: f32 = 1e-2;

/// A solve under way: the state, the workspace's main part, visibility, and the executor
/// with the workspace's scratch.
pub(super) struct Run<'w, V: ?Sized, E: Executor> {
    pub(super) st: state::State,
    pub(super) ws: &'w mut [u8],
    pub(super) vis: vis::Vis<'w, V>,
    pub(super) seq: exec::Fallback<'w, E>,
}

/// The workspace's parts for a layout: the main part, the core BVH's bytes, the executor's
/// scratch.
type Parts<'w> = (&'w mut [u8], &'w mut [u8], &'w mut [f32]);

pub(super) fn parts<'w>(
    lay: &Layout,
    ws: &'w mut [u8],
    min_bytes: u64,
) -> Result<Parts<'w>, HrError> {
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

/// The core's own BVH over the loaded polygons, built in `bvh_bytes`.
pub(super) fn core_bvh<'w>(
    st: &state::State,
    ws: &[u8],
    bvh_bytes: &'w mut [u8],
) -> Result<crate::bvh::Bvh<'w>, HrError> {
    let n = st.polygons as usize;
    let (nodes, order) = bvh_bytes.split_at_mut(
        crate::bvh::nodes_needed(st.polygons) * core::mem::size_of::<crate::bvh::BvhNode>(),
    );
    let nodes: &mut [crate::bvh::BvhNode] =
        bytemuck::try_cast_slice_mut(nodes).map_err(|_| HrError::SceneTooLarge)?;
    let order: &mut [u32] =
        bytemuck::try_cast_slice_mut(&mut order[..4 * n]).map_err(|_| HrError::SceneTooLarge)?;
    let polys = vis::WsPolygons { st, ws };
    crate::bvh::build(
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
    })
}

impl<'w, V: Visibility + ?Sized, E: Executor> Run<'w, V, E> {
    /// Counts, lays out and loads the scene, builds the core's BVH when no visibility is
    /// given, lights every patch, and evaluates the first links.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn start<S: SceneSource, P: Progress>(
        view: &SceneView<S>,
        settings: &Settings,
        instancing: Instancing,
        level: &LevelRoot<'_>,
        outer: Option<&'w vis::Outer<'w>>,
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
        let c = census_at(
            view,
            settings.max_children,
            instancing,
            level.inline,
            super::settings::BlockingLimits::of(settings),
            level.node,
            &mut ws[..need],
        )?;
        if c.polygons() == 0 && c.instances == 0 {
            return Err(HrError::Empty);
        }
        let internal = visibility.is_none();
        let n_sources = level.sources(view);
        let plan = plan_level(view, settings, internal, &c, n_sources, outer.is_some())?;
        let info = view.info();
        let lay = Layout::new(
            &c,
            info.materials,
            info.originals,
            n_sources,
            info.bands as usize,
            outer.is_some(),
            internal,
            ws.len(),
        )
        .ok_or(HrError::WorkspaceTooSmall {
            needed: plan.min_bytes,
        })?;
        let (ws, bvh_bytes, scratch) = parts(&lay, ws, plan.min_bytes)?;
        let loaded = load::load(view, settings, instancing, level, &c, lay, ws);
        let mut st = loaded.map_err(|e| match e {
            HrError::WorkspaceTooSmall { .. } => HrError::WorkspaceTooSmall {
                needed: plan.min_bytes,
            },
            e => e,
        })?;
        let vis = match visibility {
            Some(v) => vis::Vis::External(v),
            None => match outer {
                None => vis::Vis::Internal(core_bvh(&st, ws, bvh_bytes)?),
                Some(o) => vis::Vis::Nested(core_bvh(&st, ws, bvh_bytes)?, o),
            },
        };
        st.stats.workspace_bytes = total as u64;
        bins::allocate(&mut st, ws);
        progress.report("loaded (polygons)", st.polygons as u64, st.polygons as u64);
        if progress.cancelled() || executor.cancelled() {
            return Err(HrError::Cancelled);
        }
        let mut seq = exec::Fallback {
            inner: executor,
            scratch,
        };
        direct::prepare_pending(&mut st, ws, &vis, &mut seq, progress);
        if progress.cancelled() || seq.inner.cancelled() {
            return Err(HrError::Cancelled);
        }
        if st.instances > 0 {
            instance_light::light_instances(&mut st, ws, &vis, &mut seq, progress);
            super::exchange::build(&mut st, ws, &vis, &mut seq, progress);
        }
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
    pub(super) fn round<P: Progress>(&mut self, round: u32, progress: &mut P) -> bool {
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
    pub(super) fn rounds<P: Progress>(&mut self, progress: &mut P) {
        if self.st.settings.max_rounds == 0 {
            // No refinement at all: the coarsest solution, to the tolerance asked for.
            let tol = self.st.settings.tolerance;
            solve::iterate(&mut self.st, self.ws, &mut self.seq, progress, tol);
            return;
        }
        for round in 0..self.st.settings.max_rounds {
            if progress.cancelled() || self.round(round, progress) {
                break;
            }
        }
    }

    /// The relighting passes of the final gather (see `relight`): the patches' light
    /// gathered by rays, the solution solved again from it.
    pub(super) fn relight<P: Progress>(&mut self, progress: &mut P) {
        Self::relight_with(&mut self.st, self.ws, &self.vis, &mut self.seq, progress);
    }

    fn relight_with(
        st: &mut state::State,
        ws: &mut [u8],
        vis: &vis::Vis<'_, V>,
        seq: &mut exec::Fallback<'_, E>,
        progress: &mut dyn Progress,
    ) {
        if gather_rays::rays_per_side(st, ws) > 0 {
            gather_rays::note_shares(st, ws);
            relight::relight_passes(st, ws, vis, seq, progress);
        }
    }

    /// The final passes: statistics, the relighting passes of the final gather, the power
    /// balance, and every polygon to the sink.
    pub(super) fn finish<K: Sink, P: Progress>(
        mut self,
        progress: &mut P,
        sink: &mut K,
    ) -> Result<Stats, SolveError<K::Error>> {
        let (st, ws) = (&mut self.st, &mut *self.ws);
        if progress.cancelled() || self.seq.inner.cancelled() {
            return Err(SolveError::Hr(HrError::Cancelled));
        }
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
        Self::relight_with(st, ws, &self.vis, &mut self.seq, progress);
        let rays = 4 * st.settings.rays;
        st.stats.balance = balance::measure(
            st,
            ws,
            &self.vis,
            &mut self.seq,
            rays,
            balance::Scope::Scene,
            progress,
        );
        super::blockers::note_radiance(st, ws, &mut self.seq);
        if progress.cancelled() || self.seq.inner.cancelled() {
            return Err(SolveError::Hr(HrError::Cancelled));
        }
        progress.report(output::phase(st, ws), 0, st.polygons as u64);
        let written = output::emit(st, ws, &self.vis, &mut self.seq, progress, sink)
            .map_err(SolveError::Sink)?;
        if written.cancelled {
            return Err(SolveError::Hr(HrError::Cancelled));
        }
        st.stats.rays += written.rays;
        st.stats.rays_by_phase.final_gather += written.rays;
        if let Some(mut absorbed) = written.absorbed {
            // The closed instances' own, which no polygon of this level holds.
            for i in 0..st.instances {
                let placed = st.placed(ws, i);
                let received = st.received(ws, i);
                if let Ok(r) = crate::tables::closed::Received::over(&placed, received) {
                    for (b, a) in absorbed.iter_mut().enumerate().take(st.bands) {
                        *a += r.absorbed(b) as f64;
                    }
                }
            }
            st.stats.balance.absorbed = absorbed;
        }
        Ok(st.stats)
    }
}
