//! Running the solver's independent chunks of work: on the caller's threads, or one at a
//! time in the workspace's own scratch.

use core::ops::Range;

/// Spreads chunks of work over threads (the runner uses rayon); the core's default runs
/// them itself.
///
/// Chunks are fixed by the solver, independent of each other and applied in increasing
/// order after they are computed, so an executor can never change the result.
pub trait Executor {
    /// Computes every chunk in `chunks` with `work(chunk, out)`, each with its own `out` of
    /// `out_len` floats, in any order and possibly concurrently, keeping the outputs for
    /// [`Executor::output`]. Returns false to let the solver run them itself.
    fn compute(
        &mut self,
        chunks: Range<usize>,
        out_len: usize,
        work: &(dyn Fn(usize, &mut [f32]) + Sync),
    ) -> bool;

    /// The output of a chunk of the last [`Executor::compute`].
    fn output(&self, chunk: usize) -> &[f32];

    /// How many chunks it takes at once.
    fn batch(&self) -> usize {
        1
    }

    /// True once the caller wants the solve stopped: the batches of chunks a phase has
    /// left are skipped, and the solve ends at the progress's next check (an executor that
    /// says so shares the flag with a [`Progress`] whose `cancelled` says so too).
    fn cancelled(&self) -> bool {
        false
    }

    /// How many jobs [`Executor::run_jobs`] runs at once (hierarchical instantiation opens
    /// that many sibling instances together, each in its own part of the workspace).
    fn parallelism(&self) -> usize {
        1
    }

    /// Runs `work(k, &mut jobs[k], part)` for every job, in any order and possibly
    /// concurrently; each job owns its element and is handed one of `parts` that no job
    /// running at the same time holds (as many parts as [`Executor::parallelism`], or
    /// fewer: no more jobs run at once than there are parts). The default runs them one
    /// after another in `parts[0]`. Runs nothing when `parts` is empty.
    fn run_jobs<T: Send, P: Send>(
        &mut self,
        jobs: &mut [T],
        parts: &mut [P],
        work: &(dyn Fn(usize, &mut T, &mut P) + Sync),
    ) {
        let Some(part) = parts.first_mut() else {
            return;
        };
        for (k, job) in jobs.iter_mut().enumerate() {
            work(k, job, part);
        }
    }
}

/// Runs nothing itself: the solver computes chunk after chunk in its workspace.
#[derive(Clone, Copy, Debug, Default)]
pub struct Sequential;

impl Executor for Sequential {
    fn compute(
        &mut self,
        _: Range<usize>,
        _: usize,
        _: &(dyn Fn(usize, &mut [f32]) + Sync),
    ) -> bool {
        false
    }

    fn output(&self, _: usize) -> &[f32] {
        &[]
    }
}

/// Told how a long solve is going.
pub trait Progress {
    /// `what` is a phase name ("refining", "solving", ...); `done` of `total` units.
    fn report(&mut self, what: &str, done: u64, total: u64);

    /// True once the caller wants the solve stopped: it ends with
    /// [`super::HrError::Cancelled`] at its next check (between refinement passes,
    /// iterations, relighting passes, levels and batches of the final gather), having
    /// handed no further polygon to the sink. Once true it must stay true.
    fn cancelled(&mut self) -> bool {
        false
    }
}

/// Ignores progress.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoProgress;

impl Progress for NoProgress {
    fn report(&mut self, _: &str, _: u64, _: u64) {}
}

/// The caller's executor, with the workspace scratch as the fallback when it declines.
pub(crate) struct Fallback<'a, E: Executor> {
    pub inner: &'a mut E,
    pub scratch: &'a mut [f32],
}

impl<E: Executor> Fallback<'_, E> {
    /// Chunks to take at once.
    pub(crate) fn batch(&self) -> usize {
        self.inner.batch().max(1)
    }

    /// Computes `chunks`; returns true if the outputs live in the inner executor.
    pub(crate) fn compute(
        &mut self,
        chunks: Range<usize>,
        out_len: usize,
        work: &(dyn Fn(usize, &mut [f32]) + Sync),
    ) -> Result<bool, ()> {
        if self.inner.compute(chunks.clone(), out_len, work) {
            return Ok(true);
        }
        // One chunk at a time through the scratch: callers take batches of one then.
        if chunks.len() != 1 || out_len > self.scratch.len() {
            return Err(());
        }
        work(chunks.start, &mut self.scratch[..out_len]);
        Ok(false)
    }

    pub(crate) fn output(&self, chunk: usize, inner: bool, out_len: usize) -> &[f32] {
        if inner {
            self.inner.output(chunk)
        } else {
            &self.scratch[..out_len]
        }
    }
}

/// Runs `work` over `n` chunks and `apply`s their outputs in order.
pub(crate) fn run_chunks<E: Executor, T>(
    ex: &mut Fallback<'_, E>,
    ctx: &mut T,
    n: usize,
    out_len: usize,
    work: impl Fn(&T, usize, &mut [f32]) + Sync,
    apply: impl FnMut(&mut T, usize, &[f32]),
    report: &mut dyn FnMut(usize, usize),
) where
    T: Sync,
{
    run_chunks_scaled(ex, ctx, n, 1, out_len, work, apply, report)
}

/// [`run_chunks`] with `scale` times the executor's batch per call: for chunks `scale`
/// times smaller than [`super::layout::CHUNK`], so that a call covers as many items.
#[allow(clippy::too_many_arguments)]
pub(crate) fn run_chunks_scaled<E: Executor, T>(
    ex: &mut Fallback<'_, E>,
    ctx: &mut T,
    n: usize,
    scale: usize,
    out_len: usize,
    work: impl Fn(&T, usize, &mut [f32]) + Sync,
    mut apply: impl FnMut(&mut T, usize, &[f32]),
    report: &mut dyn FnMut(usize, usize),
) where
    T: Sync,
{
    let mut start = 0;
    let mut batch = ex.batch() * scale.max(1);
    // Announce the phase before its first batch, so that a caller timing phases by their
    // reports charges this work to this phase, not to the one before.
    report(0, n);
    while start < n {
        if ex.inner.cancelled() {
            break;
        }
        let end = (start + batch).min(n);
        let shared: &T = ctx;
        let w = |c: usize, out: &mut [f32]| work(shared, c, out);
        match ex.compute(start..end, out_len, &w) {
            Ok(inner) => {
                for c in start..end {
                    apply(ctx, c, ex.output(c, inner, out_len));
                }
                start = end;
                report(start, n);
            }
            // The executor declined a batch: take chunks one by one from now on.
            Err(()) if batch > 1 => batch = 1,
            // Cannot happen (the scratch is sized for any chunk); never loop forever.
            Err(()) => break,
        }
    }
}
