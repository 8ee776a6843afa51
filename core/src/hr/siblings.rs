//! Sibling instances opened together (hierarchical instantiation's parallel siblings): once
//! a level is solved its closed instances are independent, so consecutive ones open as jobs
//! of the executor, each in its own part of the free workspace, their results recorded
//! there (see `recorder`) and handed on in global-id order; one whose part proves too small
//! opens again alone. Each one's levels are tallied apart and added in order (see `tally`),
//! so results and sums are the same for any number of jobs.

use super::beams::beams;
use super::error::{HrError, SolveError};
use super::exec::{Executor, Progress};
use super::level::{LevelRoot, beam_floats};
use super::open::{Ctx, level};
use super::settings::Inline;
use super::state::State;
use super::tally::Tally;
use crate::geometry::Similarity;
use crate::image::SceneSource;
use crate::sink::Sink;
use crate::visibility::Unoccluded;

/// Most sibling instances opened together.
pub(super) const MAX_JOBS: usize = 16;

/// A closed instance to open: its leaf, its contents (node and placement) and their first
/// polygon's global id.
#[derive(Clone, Copy)]
pub(super) struct Item<'b> {
    pub leaf: u32,
    pub node: u32,
    pub place: Similarity,
    pub first_id: u64,
    pub inline: Inline<'b>,
    /// The instance's original.
    pub original: u32,
}

/// How an instance opened as a job went.
#[derive(Clone, Copy)]
enum Outcome {
    /// Solved; its results are recorded in its part.
    Done,
    /// Its part was too small (for its levels, or for the record of its results): opened
    /// again after the others, in the whole free workspace, as alone.
    Again,
    /// It failed.
    Failed(HrError),
}

/// A sibling instance opened in its own part of the workspace.
struct Job<'w, 'b> {
    part: &'w mut [u8],
    /// Where the part starts in the caller's workspace (bytes).
    origin: usize,
    item: Item<'b>,
    tally: Tally,
    recorded: usize,
    outcome: Outcome,
}

/// Opens the closed instances `items` (siblings in the level `st`, in global-id order, in
/// `free`, which starts `origin` bytes into the caller's workspace). More than one: each in
/// its own part of `free`, as jobs of the executor (concurrently if it runs them so), each
/// solved as alone with its results recorded, then handed on in order; one that did not
/// fit its part is opened again in the whole of `free`, as are the ones after it. The
/// results, and the tallies added in order, are the same for any number of jobs.
#[allow(clippy::too_many_arguments)]
pub(super) fn open_batch<S, K, E, P>(
    ctx: &mut Ctx<'_, S, K, P>,
    st: &State,
    mine: &[u8],
    vis: &super::vis::Vis<'_, Unoccluded>,
    free: &mut [u8],
    origin: usize,
    exec: &mut E,
    items: &[Item<'_>],
    depth: usize,
) -> Result<(), SolveError<K::Error>>
where
    S: SceneSource + Sync,
    K: Sink,
    E: Executor,
    P: Progress,
{
    let mut again = 0;
    if items.len() > 1 {
        again = items.len();
        let part = (free.len() / items.len()) & !(super::layout::ALIGN - 1);
        let mut jobs: heapless::Vec<Job<'_, '_>, MAX_JOBS> = heapless::Vec::new();
        let mut rest = &mut *free;
        for (k, item) in items.iter().enumerate() {
            let at = part.min(rest.len());
            let (p, r) = core::mem::take(&mut rest).split_at_mut(at);
            rest = r;
            let _ = jobs.push(Job {
                part: p,
                origin: origin + k * part,
                item: *item,
                tally: Tally::new(),
                recorded: 0,
                outcome: Outcome::Again,
            });
        }
        let shared = ctx.shared;
        let work = |_: usize, job: &mut Job<'_, '_>| {
            // Half the part records what the contents hand out (each polygon and its leaf
            // patches, see `recorder`; pages untouched cost nothing), half solves them.
            let record = (job.part.len() / 2) & !(super::layout::ALIGN - 1);
            let (rec, ws) = job.part.split_at_mut(record);
            let Ok(words) = bytemuck::try_cast_slice_mut::<u8, u32>(rec) else {
                return;
            };
            let mut recorder = super::recorder::Recorder::new(words);
            let mut progress = super::exec::NoProgress;
            let mut sub = Ctx::new(shared, &mut progress, &mut recorder);
            let origin = job.origin + record;
            let r = open_child(
                &mut sub,
                st,
                mine,
                vis,
                &job.item,
                ws,
                origin,
                &mut super::exec::Sequential,
                depth,
            );
            job.tally = sub.tally;
            job.recorded = recorder.len();
            job.outcome = match r {
                Ok(()) if !job.tally.stats.budget_limited => Outcome::Done,
                Ok(()) => Outcome::Again,
                Err(SolveError::Sink(_)) => Outcome::Again,
                Err(SolveError::Hr(HrError::WorkspaceTooSmall { .. })) => Outcome::Again,
                Err(SolveError::Hr(e)) => Outcome::Failed(e),
            };
        };
        exec.run_jobs(&mut jobs, &work);
        for (k, job) in jobs.iter().enumerate() {
            match job.outcome {
                Outcome::Failed(e) => return Err(e.into()),
                Outcome::Again => {
                    again = k;
                    ctx.tally.stats.opened_again += (items.len() - k) as u64;
                    break;
                }
                Outcome::Done => {
                    let words: &[u32] = bytemuck::cast_slice(&job.part[..4 * job.recorded]);
                    super::recorder::replay(words, ctx.sink).map_err(SolveError::Sink)?;
                    ctx.tally.add(&job.tally);
                    ctx.tally.stats.levels_together += job.tally.levels;
                }
            }
        }
    }
    for item in &items[again..] {
        let mut sub = Ctx::new(ctx.shared, &mut *ctx.progress, &mut *ctx.sink);
        open_child(&mut sub, st, mine, vis, item, free, origin, exec, depth)?;
        let t = sub.tally;
        ctx.tally.add(&t);
    }
    Ok(())
}

/// Opens closed instance `item` of level `st` (at `depth`): its beams into `free`, then its
/// contents as the next level above them.
#[allow(clippy::too_many_arguments)]
fn open_child<S, K, E, P>(
    ctx: &mut Ctx<'_, S, K, P>,
    st: &State,
    mine: &[u8],
    vis: &super::vis::Vis<'_, Unoccluded>,
    item: &Item<'_>,
    free: &mut [u8],
    origin: usize,
    exec: &mut E,
    depth: usize,
) -> Result<(), SolveError<K::Error>>
where
    S: SceneSource + Sync,
    K: Sink,
    E: Executor,
    P: Progress,
{
    let n = beams(st, mine, item.leaf, free, 0).map_err(|e| super::open::at_origin(e, origin))?;
    let bands = st.bands;
    let bytes = (n * beam_floats(bands) * 4).next_multiple_of(super::layout::ALIGN);
    let (b, child_ws) = free.split_at_mut(bytes.min(free.len()));
    let floats: &[f32] = bytemuck::cast_slice(&b[..n * beam_floats(bands) * 4]);
    let child = LevelRoot {
        node: item.node,
        place: item.place,
        beams: Some((floats, st.suns)),
        inline: item.inline,
        children: ctx
            .shared
            .rooms
            .get(item.original as usize)
            .map_or(Default::default(), |r| r.below),
        own_growth: ctx
            .shared
            .rooms
            .get(item.original as usize)
            .map_or(u64::MAX, super::room::own_growth),
        // As many passes as the parent took at most (all it may take where it gathered
        // nothing): see `relight::relight_passes`.
        most_passes: match st.stats.final_passes {
            0 => st.most_passes,
            n => n.min(st.most_passes),
        },
    };
    // The contents' rays go on through this level (and those it is open in).
    let here = super::vis::Outer {
        vis,
        st,
        ws: mine,
        opened: item.leaf,
    };
    level(
        ctx,
        &child,
        Some(&here),
        child_ws,
        origin + bytes,
        exec,
        item.first_id,
        depth + 1,
    )
}
