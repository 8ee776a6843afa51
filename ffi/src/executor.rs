//! The runner's thread pool with the caller's request to stop: once the progress callback
//! asked, the batches a phase has left are skipped (the core's `Executor::cancelled`).

use hirad::solve::RayonExecutor;
use hirad_core::hr::Executor;
use std::ops::Range;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// [`RayonExecutor`] that says when the caller asked to stop.
pub(crate) struct Stoppable<'e, 'p> {
    pub inner: &'e mut RayonExecutor<'p>,
    /// Set by the progress callback's answer (shared with `ProgressCb`).
    pub stop: Arc<AtomicBool>,
}

impl Executor for Stoppable<'_, '_> {
    fn compute(
        &mut self,
        chunks: Range<usize>,
        out_len: usize,
        work: &(dyn Fn(usize, &mut [f32]) + Sync),
    ) -> bool {
        self.inner.compute(chunks, out_len, work)
    }

    fn output(&self, chunk: usize) -> &[f32] {
        self.inner.output(chunk)
    }

    fn batch(&self) -> usize {
        self.inner.batch()
    }

    fn parallelism(&self) -> usize {
        self.inner.parallelism()
    }

    fn run_jobs<T: Send, P: Send>(
        &mut self,
        jobs: &mut [T],
        parts: &mut [P],
        work: &(dyn Fn(usize, &mut T, &mut P) + Sync),
    ) {
        self.inner.run_jobs(jobs, parts, work)
    }

    fn cancelled(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}
