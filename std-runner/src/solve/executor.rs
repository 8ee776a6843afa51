//! The solver's chunks of work spread over a rayon thread pool. Chunks are fixed by the core
//! and applied in order, so the result is bit-identical whatever the thread count.

use hirad_core::hr::Executor;
use rayon::prelude::*;
use std::cell::RefCell;
use std::ops::Range;
use std::sync::{Arc, Mutex};

/// Runs a batch of chunks on a pool of `threads` threads; with one thread, on the caller's
/// own (handing each batch to a pool thread and waiting for it cost more than the work in
/// small scenes: a Cornell box solve spent most of its time waking threads).
///
/// The calling thread is one of the pool's threads: between batches the solver works alone
/// on it (applying results in order), and a pool of as many other threads as cores would
/// leave them spinning on the cores it needs (a 2-thread solve of a 122,000-polygon tree
/// took 8% longer that way). rayon leaks such a pool's registry, so each thread keeps the
/// pools it made and reuses them.
pub struct RayonExecutor {
    pool: Option<Arc<rayon::ThreadPool>>,
    outputs: Vec<Vec<f32>>,
    first: usize,
    batch: usize,
}

impl RayonExecutor {
    /// A pool of `threads` threads (at least 1).
    pub fn new(threads: usize) -> anyhow::Result<Self> {
        let pool = if threads > 1 {
            Some(pool_for_this_thread(threads)?)
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

thread_local! {
    /// Pools made on this thread, by thread count.
    static POOLS: RefCell<Vec<(usize, Arc<rayon::ThreadPool>)>> = const { RefCell::new(Vec::new()) };
}

/// This thread's pool of `threads` threads (itself included), made on first use.
fn pool_for_this_thread(threads: usize) -> anyhow::Result<Arc<rayon::ThreadPool>> {
    POOLS.with(|pools| {
        let mut pools = pools.borrow_mut();
        if let Some((_, p)) = pools.iter().find(|(n, _)| *n == threads) {
            return Ok(p.clone());
        }
        let builder = || {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .thread_name(|i| format!("hirad-{i}"))
        };
        // A thread belongs to at most one pool: after the first, the caller waits while
        // the pool's own threads work.
        let pool = Arc::new(match builder().use_current_thread().build() {
            Ok(p) => p,
            Err(_) => builder().build()?,
        });
        pools.push((threads, pool.clone()));
        Ok(pool)
    })
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
        // Every chunk writes what it hands back (the core's own executor reuses one scratch
        // buffer without clearing it), so a buffer of the right length is reused as it is.
        for o in &mut self.outputs[..n] {
            if o.len() != out_len {
                o.clear();
                o.resize(out_len, 0.0);
            }
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

    fn parallelism(&self) -> usize {
        self.threads()
    }

    fn run_jobs<T: Send, P: Send>(
        &mut self,
        jobs: &mut [T],
        parts: &mut [P],
        work: &(dyn Fn(usize, &mut T, &mut P) + Sync),
    ) {
        match &self.pool {
            Some(pool) if jobs.len() > 1 && parts.len() > 1 => {
                // A job takes the part of the pool thread it runs on: one job at a time per
                // thread (a job runs no pool work itself), so a part is never held twice
                // and its lock never waits. Jobs are handed out one by one, so that a long
                // one does not hold back those after it.
                let locks: Vec<Mutex<&mut P>> = parts.iter_mut().map(Mutex::new).collect();
                pool.install(|| {
                    jobs.par_iter_mut()
                        .enumerate()
                        .with_max_len(1)
                        .for_each(|(k, job)| {
                            let t = rayon::current_thread_index().unwrap_or(0) % locks.len();
                            let mut part = locks[t].lock().unwrap_or_else(|e| e.into_inner());
                            work(k, job, &mut part);
                        });
                });
            }
            _ => {
                if let Some(part) = parts.first_mut() {
                    for (k, job) in jobs.iter_mut().enumerate() {
                        work(k, job, part);
                    }
                }
            }
        }
    }

    fn batch(&self) -> usize {
        self.batch
    }
}
