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
use super::open::{Ctx, flush, level};
use super::settings::Inline;
use super::state::State;
use super::tally::Tally;
use crate::geometry::Similarity;
use crate::image::SceneSource;
use crate::sink::Sink;
use crate::visibility::Unoccluded;

/// Most sibling instances opened together.
pub(super) const MAX_JOBS: usize = 16;

/// Sibling instances opened together per job the executor runs at once.
pub(super) const BATCH_PER_WORKER: usize = 4;

/// Children's rooms a level leaves free when it refines under a budget (see
/// `room::capped_total`): two side by side, each with as much again for the record of what
/// it hands out. A constant, not the thread count: a level capped by the threads refined
/// differently on one thread and on two, and as a job (one at a time inside) and alone, so
/// that results under a budget changed with the threads. More workers than the room allows
/// get smaller parts, and an instance whose part proves too small opens again alone.
pub(super) const ROOMS_KEPT: u64 = 4;

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

/// A sibling instance opened as a job: its results are recorded in its own slot of the
/// workspace, its levels solved in the part of the worker that takes it.
struct Job<'w, 'b> {
    /// Where its results are recorded.
    slot: &'w mut [u8],
    item: Item<'b>,
    tally: Tally,
    recorded: usize,
    outcome: Outcome,
}

/// What a batch hands out, in global-id order.
#[derive(Clone, Copy)]
pub(super) enum Entry<'b> {
    /// The level's `count` polygons before `polygon`, the last with global id `next_id - 1`.
    Own {
        polygon: u32,
        count: u32,
        next_id: u64,
    },
    /// A closed instance's contents.
    Child(Item<'b>),
}

/// Closed instances waiting to be opened and the level's polygons between them.
pub(super) type Batch<'b> = heapless::Vec<Entry<'b>, { 2 * MAX_JOBS + 1 }>;

/// Opens the closed instances of `entries` (siblings in the level `st`, in `free`, which
/// starts `origin` bytes into the caller's workspace) and hands out the level's polygons
/// between them, in order. More than one instance: as jobs of the executor, taken by as
/// many workers as it runs at once, each solving its jobs' levels in its own part of
/// `free`; each job's results are recorded in a slot of their own and handed on in order. A job whose slot or part proved too small is opened again in the
/// whole of `free`, as are the ones after it. Which worker takes a job changes neither its
/// results nor whether it fits: the results, and the tallies added in order, are the same
/// for any number of workers.
#[allow(clippy::too_many_arguments)]
pub(super) fn open_batch<S, K, E, P>(
    ctx: &mut Ctx<'_, S, K, P>,
    st: &State,
    mine: &[u8],
    vis: &super::vis::Vis<'_, Unoccluded>,
    free: &mut [u8],
    origin: usize,
    exec: &mut E,
    scratch: &mut [f32],
    entries: &[Entry<'_>],
    depth: usize,
) -> Result<(), SolveError<K::Error>>
where
    S: SceneSource + Sync,
    K: Sink,
    E: Executor,
    P: Progress,
{
    let mut items: heapless::Vec<Item<'_>, MAX_JOBS> = heapless::Vec::new();
    for e in entries {
        if let Entry::Child(item) = e {
            items.push(*item).map_err(|_| HrError::SceneTooLarge)?;
        }
    }
    let mut outcomes: heapless::Vec<(Outcome, Tally, usize), MAX_JOBS> = heapless::Vec::new();
    let workers = exec.parallelism().clamp(1, MAX_JOBS).min(items.len());
    // Where each job's record starts in `free` and its length, when jobs ran.
    let mut slots: heapless::Vec<(usize, usize), MAX_JOBS> = heapless::Vec::new();
    if items.len() > 1 && workers > 1 {
        // Half of `free` records what the jobs hand out (each polygon and its leaf patches,
        // see `recorder`; pages untouched cost nothing), in equal slots, as many as a batch
        // holds: the same slots batch after batch, so that only the records' own pages are
        // ever touched; the other half is the workers' parts.
        let align = super::layout::ALIGN;
        let records = (free.len() / 2) & !(align - 1);
        let (rec, rest) = free.split_at_mut(records);
        let part = (rest.len() / workers) & !(align - 1);
        let batch = (exec.parallelism().clamp(1, MAX_JOBS) * BATCH_PER_WORKER)
            .clamp(items.len(), MAX_JOBS.max(items.len()));
        let share = (records / batch) & !(align - 1);
        let mut jobs: heapless::Vec<Job<'_, '_>, MAX_JOBS> = heapless::Vec::new();
        let mut left = rec;
        let mut at = 0;
        for item in &items {
            let len = share.min(left.len());
            let (slot, r) = core::mem::take(&mut left).split_at_mut(len);
            left = r;
            let _ = slots.push((at, len));
            at += len;
            let _ = jobs.push(Job {
                slot,
                item: *item,
                tally: Tally::new(),
                recorded: 0,
                outcome: Outcome::Again,
            });
        }
        // Each worker's part of the workspace, where the jobs it takes solve their levels one
        // after another.
        let mut parts: heapless::Vec<&mut [u8], MAX_JOBS> = heapless::Vec::new();
        let mut left = rest;
        for _ in 0..workers {
            let len = part.min(left.len());
            let (p, r) = core::mem::take(&mut left).split_at_mut(len);
            left = r;
            let _ = parts.push(p);
        }
        let shared = ctx.shared;
        let parts_at = origin + records;
        let work = |k: usize, job: &mut Job<'_, '_>, part: &mut &mut [u8]| {
            let Ok(words) = bytemuck::try_cast_slice_mut::<u8, u32>(&mut job.slot[..]) else {
                return;
            };
            let mut recorder = super::recorder::Recorder::new(words);
            let mut progress = super::exec::NoProgress;
            let mut sub = Ctx::new(shared, &mut progress, &mut recorder);
            // Reported as if job k ran in part k mod workers (the stats do not depend on
            // which worker took it; every part is the same size).
            let at = parts_at + (k % workers) * part.len();
            let r = open_child(
                &mut sub,
                st,
                mine,
                vis,
                &job.item,
                part,
                at,
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
        // The workers report nothing while they solve (their levels' phases interleave):
        // the time goes to this phase, not to the last one this thread reported.
        let n = jobs.len() as u64;
        ctx.progress.report(JOBS_PHASE, 0, n);
        exec.run_jobs(&mut jobs, &mut parts, &work);
        ctx.progress.report(JOBS_PHASE, n, n);
        for job in &jobs {
            let _ = outcomes.push((job.outcome, job.tally, job.recorded));
        }
    }
    // In order: the level's polygons, the jobs' records; from the first job that did not
    // fit on (or without jobs), each instance opened alone in the whole of `free`.
    let mut k = 0;
    let mut alone = outcomes.is_empty();
    for e in entries {
        match e {
            Entry::Own {
                polygon,
                count,
                next_id,
            } => {
                let mut pending = *count;
                flush(
                    ctx,
                    st,
                    mine,
                    vis,
                    exec,
                    scratch,
                    *polygon,
                    &mut pending,
                    *next_id,
                )?;
            }
            Entry::Child(item) => {
                if !alone {
                    let (outcome, tally, recorded) = outcomes[k];
                    match outcome {
                        Outcome::Failed(e) => return Err(e.into()),
                        Outcome::Done => {
                            let (at, _) = slots[k];
                            let words: &[u32] = bytemuck::cast_slice(&free[at..at + 4 * recorded]);
                            super::recorder::replay(words, ctx.sink).map_err(SolveError::Sink)?;
                            ctx.tally.add(&tally);
                            ctx.tally.stats.levels_together += tally.levels;
                            k += 1;
                            continue;
                        }
                        Outcome::Again => {
                            alone = true;
                            ctx.tally.stats.opened_again += (items.len() - k) as u64;
                        }
                    }
                }
                let mut sub = Ctx::new(ctx.shared, &mut *ctx.progress, &mut *ctx.sink);
                open_child(&mut sub, st, mine, vis, item, free, origin, exec, depth)?;
                let t = sub.tally;
                ctx.tally.add(&t);
                k += 1;
            }
        }
    }
    Ok(())
}

/// The progress phase of sibling levels solved as jobs by the workers.
pub(super) const JOBS_PHASE: &str = "opening levels as jobs (levels)";

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
