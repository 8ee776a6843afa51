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
/// pools it made and reuses them ([`RayonExecutor::new`]); an embedder that must not keep
/// threads past a call takes [`scoped`] instead.
pub struct RayonExecutor<'p> {
    pool: Option<Pool<'p>>,
    outputs: Vec<Vec<f32>>,
    first: usize,
    batch: usize,
}

/// The pool an executor runs on: one this thread keeps, or one that lives for a call.
enum Pool<'p> {
    Kept(Arc<rayon::ThreadPool>),
    Borrowed(&'p rayon::ThreadPool),
}

impl Pool<'_> {
    fn get(&self) -> &rayon::ThreadPool {
        match self {
            Pool::Kept(p) => p,
            Pool::Borrowed(p) => p,
        }
    }
}

impl RayonExecutor<'static> {
    /// A pool of `threads` threads (at least 1), kept by this thread for later calls.
    pub fn new(threads: usize) -> anyhow::Result<Self> {
        let pool = if threads > 1 {
            Some(Pool::Kept(pool_for_this_thread(threads)?))
        } else {
            None
        };
        Ok(RayonExecutor::with(pool, threads))
    }
}

impl<'p> RayonExecutor<'p> {
    fn with(pool: Option<Pool<'p>>, threads: usize) -> Self {
        RayonExecutor {
            pool,
            outputs: Vec::new(),
            first: 0,
            batch: 64 * threads.max(1),
        }
    }

    /// Threads in the pool.
    pub fn threads(&self) -> usize {
        self.pool
            .as_ref()
            .map_or(1, |p| p.get().current_num_threads())
    }
}

/// Runs `f` with an executor of `threads` threads (at least 1) that exist only during the
/// call: they are joined before it returns, so nothing of hirad runs after it (a library
/// that may be unloaded, a caller that counts its threads), and the calling thread never
/// becomes one of them (no per-thread state of rayon's is left on it).
pub fn scoped<R>(threads: usize, f: impl FnOnce(&mut RayonExecutor<'_>) -> R) -> anyhow::Result<R> {
    if threads <= 1 {
        return Ok(f(&mut RayonExecutor::with(None, 1)));
    }
    let handles = Mutex::new(Vec::new());
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .spawn_handler(|t| {
            let h = std::thread::Builder::new()
                .name(format!("hirad-{}", t.index()))
                .spawn(|| t.run())?;
            handles.lock().unwrap_or_else(|e| e.into_inner()).push(h);
            Ok(())
        })
        .build()?;
    // Joined when `f` returns, and when it unwinds (a panic the C ABI catches).
    let joined = Joined {
        pool: Some(pool),
        handles: handles.into_inner().unwrap_or_else(|e| e.into_inner()),
    };
    let pool = joined
        .pool
        .as_ref()
        .expect("the pool lives until `joined` is dropped");
    Ok(f(&mut RayonExecutor::with(
        Some(Pool::Borrowed(pool)),
        threads,
    )))
}

/// A call's pool and its threads: dropping it tells them to end and joins each.
struct Joined {
    pool: Option<rayon::ThreadPool>,
    handles: Vec<std::thread::JoinHandle<()>>,
}

impl Drop for Joined {
    fn drop(&mut self) {
        drop(self.pool.take());
        for h in self.handles.drain(..) {
            let _ = h.join();
        }
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

impl Executor for RayonExecutor<'_> {
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
            Some(pool) if n > 1 => pool.get().install(|| {
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
                pool.get().install(|| {
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
