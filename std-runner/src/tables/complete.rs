//! The tables a solve by hierarchical instantiation needs and its scene lacks, made before
//! it starts: every instanced original without tables gets them from the table cache, or
//! is baked with the defaults of `hirad tables` (and cached), so that `hirad solve --method
//! hi` runs on any scene; a second run finds them in the cache.

use super::{Cache, OriginalTables, TableSettings, bake_alone};
use crate::scene::{Cluster, Scene};
use crate::solve::RayonExecutor;
use anyhow::Result;

/// What [`complete`] did.
#[derive(Clone, Debug, Default)]
pub struct Completed {
    /// The originals whose tables were added, by name.
    pub originals: Vec<String>,
    /// Of those, how many came from the cache.
    pub cache_hits: u32,
    /// Those whose tables missed their error targets on the finest grids allowed.
    pub unmet: Vec<String>,
    /// Wall-clock seconds, cache reads included.
    pub seconds: f64,
}

/// The originals instanced anywhere in `scene` (its tree and the originals' own trees),
/// inner ones first (by nesting depth, then index).
pub fn instanced_originals(scene: &Scene) -> Vec<usize> {
    fn collect(c: &Cluster, out: &mut Vec<usize>) {
        if let Some(i) = &c.instance {
            out.push(i.original);
        }
        for ch in &c.children {
            collect(ch, out);
        }
    }
    let n = scene.originals.len();
    let mut used = vec![false; n];
    let mut inner: Vec<Vec<usize>> = Vec::with_capacity(n);
    let mut top = Vec::new();
    collect(&scene.root, &mut top);
    for &o in &top {
        used[o] = true;
    }
    for o in &scene.originals {
        let mut v = Vec::new();
        collect(&o.root, &mut v);
        for &i in &v {
            used[i] = true;
        }
        inner.push(v);
    }
    // Nesting depth: how many levels of originals an original holds below it (a cycle,
    // which the scene's checks refuse, stops at the originals' count).
    fn depth_of(o: usize, inner: &[Vec<usize>], depth: &mut [usize], guard: usize) -> usize {
        if depth[o] != usize::MAX || guard > inner.len() {
            return depth[o].min(guard);
        }
        let d = inner[o]
            .iter()
            .map(|&i| depth_of(i, inner, depth, guard + 1) + 1)
            .max()
            .unwrap_or(0);
        depth[o] = d;
        d
    }
    let mut depth = vec![usize::MAX; n];
    for o in 0..n {
        depth_of(o, &inner, &mut depth, 0);
    }
    let mut order: Vec<usize> = (0..n).filter(|&o| used[o]).collect();
    order.sort_by_key(|&o| (depth[o], o));
    order
}

/// The tables of original `o` of `scene` baked with `settings`: from `cache` when it holds
/// them (true), else baked and stored there (a cache that cannot be written is warned
/// about, not fatal).
pub fn obtain(
    scene: &Scene,
    o: usize,
    settings: &TableSettings,
    cache: Option<&Cache>,
    exec: &mut RayonExecutor,
    report: &mut dyn FnMut(&str, u64, u64),
) -> Result<(OriginalTables, bool)> {
    let start = std::time::Instant::now();
    let name = scene.originals[o].name.clone();
    let alone = super::Alone::new(scene, o)?;
    let key = Cache::key(scene, &alone, settings);
    if let Some(mut t) = cache.and_then(|c| c.load(&key, &name, o)) {
        t.seconds = start.elapsed().as_secs_f64();
        return Ok((t, true));
    }
    let t = bake_alone(scene, o, &alone, settings, exec, report)?;
    if let Some(c) = cache
        && let Err(e) = c.store(&key, &t)
    {
        eprintln!(
            "warning: the table cache {} cannot be written ({e:#}); the tables were computed and are used",
            c.dir().display()
        );
    }
    Ok((t, false))
}

/// The instanced originals of `scene` without tables.
pub fn missing(scene: &Scene) -> Vec<usize> {
    let all: Vec<usize> = (0..scene.originals.len()).collect();
    missing_of(scene, &all)
}

/// Of the originals `wanted`, the instanced ones without tables, inner ones first (see
/// [`instanced_originals`]).
pub fn missing_of(scene: &Scene, wanted: &[usize]) -> Vec<usize> {
    instanced_originals(scene)
        .into_iter()
        .filter(|o| wanted.contains(o))
        .filter(|&o| !scene.tables.iter().any(|t| t.original == o))
        .collect()
}

/// Adds to `scene` the tables of the instanced originals of `originals` that have none, with the defaults
/// of `hirad tables` (every grid's largest side at most `max_side` when given: coarser and
/// faster), from the default cache (see [`Cache::locate`]) where it holds them.
pub fn complete(
    scene: &mut Scene,
    originals: &[usize],
    threads: usize,
    max_side: Option<u32>,
    report: &mut dyn FnMut(&str, u64, u64),
) -> Result<Completed> {
    complete_with(
        scene,
        originals,
        &mut RayonExecutor::new(threads)?,
        max_side,
        Cache::locate(None).as_ref(),
        report,
    )
}

/// [`complete`] on the executor `exec`, with the cache `cache` (`None`: every table made,
/// nothing stored: what an embedding caller gets, which touches no file).
pub fn complete_with(
    scene: &mut Scene,
    originals: &[usize],
    exec: &mut RayonExecutor<'_>,
    max_side: Option<u32>,
    cache: Option<&Cache>,
    report: &mut dyn FnMut(&str, u64, u64),
) -> Result<Completed> {
    let start = std::time::Instant::now();
    let mut done = Completed::default();
    let todo = missing_of(scene, originals);
    if todo.is_empty() {
        return Ok(done);
    }
    let mut settings = TableSettings::default();
    if let Some(m) = max_side {
        settings.max_side = settings.max_side.min(m);
        settings.max_tau_side = settings.max_tau_side.min(m);
        settings.max_out_side = settings.max_out_side.min(m);
        settings.max_single_side = settings.max_single_side.min(m);
    }
    for o in todo {
        let (t, hit) = obtain(scene, o, &settings, cache, exec, report)?;
        done.cache_hits += u32::from(hit);
        done.originals.push(t.name.clone());
        if !t.met {
            done.unmet.push(t.name.clone());
        }
        scene.tables.push(t.to_scene());
    }
    done.seconds = start.elapsed().as_secs_f64();
    Ok(done)
}
