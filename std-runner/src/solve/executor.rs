//! The solver's chunks of work spread over a rayon thread pool. Chunks are fixed by the core
//! and applied in order, so the result is bit-identical whatever the thread count.

use hirad_core::hr::Executor;
use rayon::prelude::*;
use std::ops::Range;

/// Runs a batch of chunks on a pool of `threads` threads; with one thread, on the caller's
/// own (handing each batch to a pool thread and waiting for it cost more than the work in
/// small scenes: a Cornell box solve spent most of its time waking threads).
pub struct RayonExecutor {
    pool: Option<rayon::ThreadPool>,
    outputs: Vec<Vec<f32>>,
    first: usize,
    batch: usize,
}

impl RayonExecutor {
    /// A pool of `threads` threads (at least 1).
    pub fn new(threads: usize) -> anyhow::Result<Self> {
        let pool = if threads > 1 {
            Some(
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .thread_name(|i| format!("hirad-{i}"))
                    .build()?,
            )
        } else {
            None
        };
        Ok(RayonExecutor {
            pool,
            outputs: Vec::new(),
            first: 0,
            batch: 64 * threads.max(1),
        })
    }

    /// Threads in the pool.
    pub fn threads(&self) -> usize {
        self.pool.as_ref().map_or(1, |p| p.current_num_threads())
    }
}

impl Executor for RayonExecutor {
    fn compute(
        &mut self,
        chunks: Range<usize>,
        out_len: usize,
        work: &(dyn Fn(usize, &mut [f32]) + Sync),
    ) -> bool {
        let n = chunks.len();
        if self.outputs.len() < n {
            self.outputs.resize_with(n, Vec::new);
        }
        for o in &mut self.outputs[..n] {
            o.clear();
            o.resize(out_len, 0.0);
        }
        self.first = chunks.start;
        let start = chunks.start;
        let outs = &mut self.outputs[..n];
        match &self.pool {
            // A single chunk gains nothing from another thread.
            Some(pool) if n > 1 => pool.install(|| {
                outs.par_iter_mut()
                    .enumerate()
                    .for_each(|(k, out)| work(start + k, out));
            }),
            _ => {
                for (k, out) in outs.iter_mut().enumerate() {
                    work(start + k, out);
                }
            }
        }
        true
    }

    fn output(&self, chunk: usize) -> &[f32] {
        &self.outputs[chunk - self.first]
    }

    fn batch(&self) -> usize {
        self.batch
    }
}
