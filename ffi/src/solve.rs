//! `hirad_plan` and `hirad_solve`: the workspace a scene and settings need, and the solve
//! into the caller's workspace with its callbacks.

use crate::callbacks::{CasterCb, HiradCallbacks, ProgressCb, SinkCb};
use crate::executor::Stoppable;
use crate::prepare::{self, Prepared};
use crate::scene::{HiradScene, on_scene};
use crate::settings::{Checked, HIRAD_METHOD_HI, HIRAD_METHOD_HR, HiradSettings};
use crate::status::{Failure, HiradStatus, aligned};
use hirad::output::RowLabels;
use hirad::solve::RayonExecutor;
use hirad_core::hr::{self, SolveError, Stats};
use hirad_core::limits::MAX_BANDS;
use std::sync::atomic::AtomicBool;

/// Most spectral bands: the length of the per-band arrays of `HiradStats`.
pub const HIRAD_MAX_BANDS: usize = 8;
const _: () = assert!(HIRAD_MAX_BANDS == MAX_BANDS);

/// The workspace a solve needs (bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HiradPlan {
    /// What the settings come to on this scene: `HIRAD_METHOD_HR` or `HIRAD_METHOD_HI`.
    pub method: u32,
    /// Originals whose tables this call made (kept with the handle for later calls).
    pub tables_made: u32,
    /// The least workspace a solve starts with; below it `hirad_solve` refuses with
    /// `HIRAD_STATUS_WORKSPACE_TOO_SMALL`. For hi, a workspace between it and `sure_bytes`
    /// solves with fewer polygons blocking (as `hirad solve --memory` does) and may still
    /// find a level too large.
    pub min_bytes: u64,
    /// A workspace that surely opens every level at its coarsest (hr: `min_bytes`).
    pub sure_bytes: u64,
    /// A workspace that usually lets refinement finish at this epsilon: what `hirad solve`
    /// allocates without `--memory`.
    pub suggested_bytes: u64,
}

/// What a solve did. Powers are in W, per band (entries past `bands` are 0).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HiradStats {
    /// `HIRAD_METHOD_HR` or `HIRAD_METHOD_HI`: what solved.
    pub method: u32,
    /// Worker threads used.
    pub threads: u32,
    /// Spectral bands.
    pub bands: u32,
    /// 1 when the last solution met the tolerance.
    pub converged: u32,
    /// 1 when refinement stopped because the workspace was full.
    pub budget_limited: u32,
    /// Final gather passes made.
    pub final_passes: u32,
    /// `own_polygons` as solved (0 where a small workspace turned it off).
    pub own_polygons: u32,
    /// `blocking_polygons` as solved (0 where a small workspace turned it off).
    pub blocking_polygons: u32,
    /// Originals whose tables were made for this solve.
    pub tables_made: u32,
    /// The estimated change still to come, relative to the largest radiosity.
    pub remaining_change: f32,
    /// Input polygons (expanded): the polygons handed to the sink.
    pub polygons: u64,
    /// Clusters and patches.
    pub elements: u64,
    /// Links at the end.
    pub links: u64,
    /// Iterations, all rounds.
    pub iterations: u64,
    /// Refinement passes, all rounds.
    pub refinement_passes: u64,
    /// Visibility rays cast.
    pub rays: u64,
    /// Levels solved (hi: the top level and every instance opened; hr: 0).
    pub levels: u64,
    /// Closed instances over all levels.
    pub closed_instances: u64,
    /// Workspace bytes given.
    pub workspace_bytes: u64,
    /// Most workspace bytes in use at once.
    pub peak_workspace_bytes: u64,
    /// Wall-clock seconds of the call, tables included.
    pub seconds: f64,
    /// Of them, making tables.
    pub table_seconds: f64,
    /// Emitted by materials.
    pub emitted: [f64; HIRAD_MAX_BANDS],
    /// Suns and sky falling on the scene.
    pub direct: [f64; HIRAD_MAX_BANDS],
    /// Absorbed by the receiving sides of the polygons (and by closed instances).
    pub absorbed: [f64; HIRAD_MAX_BANDS],
    /// Absorbed besides, by the backs of one-sided polygons.
    pub absorbed_backs: [f64; HIRAD_MAX_BANDS],
    /// Leaving the scene.
    pub escaped: [f64; HIRAD_MAX_BANDS],
    /// (emitted + direct - absorbed - absorbed_backs - escaped) over (emitted + direct), in
    /// percent.
    pub imbalance_percent: [f64; HIRAD_MAX_BANDS],
}

impl Default for HiradStats {
    fn default() -> Self {
        HiradStats {
            method: 0,
            threads: 0,
            bands: 0,
            converged: 0,
            budget_limited: 0,
            final_passes: 0,
            own_polygons: 0,
            blocking_polygons: 0,
            tables_made: 0,
            remaining_change: 0.0,
            polygons: 0,
            elements: 0,
            links: 0,
            iterations: 0,
            refinement_passes: 0,
            rays: 0,
            levels: 0,
            closed_instances: 0,
            workspace_bytes: 0,
            peak_workspace_bytes: 0,
            seconds: 0.0,
            table_seconds: 0.0,
            emitted: [0.0; HIRAD_MAX_BANDS],
            direct: [0.0; HIRAD_MAX_BANDS],
            absorbed: [0.0; HIRAD_MAX_BANDS],
            absorbed_backs: [0.0; HIRAD_MAX_BANDS],
            escaped: [0.0; HIRAD_MAX_BANDS],
            imbalance_percent: [0.0; HIRAD_MAX_BANDS],
        }
    }
}

/// Reads and checks the settings, refusing null and misaligned pointers.
///
/// # Safety
/// `settings` null or a readable `HiradSettings`.
unsafe fn checked(settings: *const HiradSettings) -> Result<Checked, Failure> {
    if settings.is_null() {
        return Err(Failure::new(HiradStatus::NullArgument, "settings is null"));
    }
    if !aligned(settings) {
        return Err(Failure::new(
            HiradStatus::Misaligned,
            "settings is not aligned for a HiradSettings",
        ));
    }
    // SAFETY: non-null, aligned, readable by the caller's promise.
    unsafe { settings.read() }.check()
}

/// The callbacks, all null for a null pointer.
///
/// # Safety
/// `callbacks` null or a readable `HiradCallbacks`.
unsafe fn callbacks_of(callbacks: *const HiradCallbacks) -> Result<HiradCallbacks, Failure> {
    if !aligned(callbacks) {
        return Err(Failure::new(
            HiradStatus::Misaligned,
            "callbacks is not aligned for a HiradCallbacks",
        ));
    }
    // SAFETY: null or aligned and readable by the caller's promise.
    let c = unsafe { callbacks.as_ref() }.copied().unwrap_or_default();
    if c.labels > 1 {
        return Err(Failure::new(
            HiradStatus::InvalidSettings,
            format!("callbacks.labels must be 0 or 1, not {}", c.labels),
        ));
    }
    Ok(c)
}

/// The caller's ray caster, if it gave one (both functions or neither).
fn caster_of(c: &HiradCallbacks, polygons: u64) -> Result<Option<CasterCb>, Failure> {
    match (c.transmittance, c.first_hit) {
        (Some(transmittance), Some(first_hit)) => Ok(Some(CasterCb {
            user: c.user,
            polygons,
            bad_id: AtomicBool::new(false),
            transmittance,
            first_hit,
        })),
        (None, None) => Ok(None),
        _ => Err(Failure::new(
            HiradStatus::InvalidSettings,
            "give the ray caster's transmittance and first_hit both, or neither",
        )),
    }
}

/// Plans a solve of `scene` with `settings`: the method they come to and the workspace it
/// needs, at `*plan`. Where hierarchical instantiation needs tables the scene lacks (and
/// `make_tables` is 1), they are made now (telling `callbacks->progress`; this takes
/// minutes per original) and kept with the handle for the solve.
///
/// # Safety
/// `scene` null or a live handle; `settings` null or a readable `HiradSettings`;
/// `callbacks` null or a readable `HiradCallbacks` whose functions follow their contracts;
/// `plan` null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hirad_plan(
    scene: *mut HiradScene,
    settings: *const HiradSettings,
    callbacks: *const HiradCallbacks,
    plan: *mut HiradPlan,
) -> HiradStatus {
    // SAFETY: the caller's promises, passed on.
    unsafe {
        on_scene(scene, |s| {
            if plan.is_null() {
                return Err(Failure::new(HiradStatus::NullArgument, "plan is null"));
            }
            if !aligned(plan) {
                return Err(Failure::new(HiradStatus::Misaligned, "plan is not aligned"));
            }
            let c = checked(settings)?;
            let cb = callbacks_of(callbacks)?;
            let polygons = s.open_view()?.info().expanded_polygons;
            let caster = caster_of(&cb, polygons)?.is_some();
            let mut progress = ProgressCb::new(&cb);
            let made = with_threads(c.threads, |exec| {
                let prepared = prepare::prepare(s, &c, caster, &mut progress, exec)?;
                let b = prepare::bytes(s, &prepared, &c, caster)?;
                Ok(HiradPlan {
                    method: method_of(&prepared),
                    tables_made: prepared.tables_made,
                    min_bytes: b.min,
                    sure_bytes: b.sure,
                    suggested_bytes: b.suggested,
                })
            })?;
            plan.write(made);
            Ok(())
        })
    }
}

/// Runs `f` with a thread pool that lives for the call only: no thread of hirad's runs
/// after a C function returns (a library that may be unloaded must leave none behind).
fn with_threads<R>(
    threads: usize,
    f: impl FnOnce(&mut RayonExecutor<'_>) -> Result<R, Failure>,
) -> Result<R, Failure> {
    hirad::solve::scoped(threads, f)
        .map_err(|e| Failure::new(HiradStatus::OutOfMemory, format!("the thread pool: {e:#}")))?
}

fn method_of(p: &Prepared) -> u32 {
    if p.hi.is_some() {
        HIRAD_METHOD_HI
    } else {
        HIRAD_METHOD_HR
    }
}

/// Solves `scene` with `settings` in the caller's workspace (`workspace_bytes` bytes at
/// `workspace`, any alignment, cleared first; at least the plan's `min_bytes`), handing
/// every finished polygon to `callbacks->polygon` and the figures to `*stats`. hirad
/// allocates nothing else for the solve itself: the thread pool, tables made for
/// hierarchical instantiation and labels are the exceptions (see docs/embedding.md).
///
/// Returns `HIRAD_STATUS_OK` only when the numbers are right; `HIRAD_STATUS_NOT_RIGHT`
/// when every polygon was handed over but the solution did not converge or its power
/// balance is off by more than `max_imbalance_percent` (`*stats` is written then too).
///
/// # Safety
/// `scene` null or a live handle; `settings` null or a readable `HiradSettings`;
/// `workspace` null or `workspace_bytes` writable bytes that nothing else touches during
/// the call; `callbacks` null or a readable `HiradCallbacks` whose functions follow their
/// contracts; `stats` null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hirad_solve(
    scene: *mut HiradScene,
    settings: *const HiradSettings,
    workspace: *mut u8,
    workspace_bytes: usize,
    callbacks: *const HiradCallbacks,
    stats: *mut HiradStats,
) -> HiradStatus {
    // SAFETY: the caller's promises, passed on.
    unsafe {
        on_scene(scene, |s| {
            if !aligned(stats) {
                return Err(Failure::new(
                    HiradStatus::Misaligned,
                    "stats is not aligned",
                ));
            }
            if workspace.is_null() && workspace_bytes > 0 {
                return Err(Failure::new(HiradStatus::NullArgument, "workspace is null"));
            }
            let c = checked(settings)?;
            let cb = callbacks_of(callbacks)?;
            let mut out = HiradStats::default();
            let result = with_threads(c.threads, |exec| {
                solve(s, &c, &cb, workspace, workspace_bytes, exec, &mut out)
            });
            if !stats.is_null()
                && result
                    .as_ref()
                    .map_or_else(|e| e.status == HiradStatus::NotRight, |_| true)
            {
                stats.write(out);
            }
            result
        })
    }
}

/// The solve behind `hirad_solve`.
///
/// # Safety
/// `workspace` null (with `len` 0) or `len` writable bytes nothing else touches.
unsafe fn solve(
    s: &mut HiradScene,
    c: &Checked,
    cb: &HiradCallbacks,
    workspace: *mut u8,
    len: usize,
    pool: &mut RayonExecutor<'_>,
    out: &mut HiradStats,
) -> Result<(), Failure> {
    let start = std::time::Instant::now();
    let polygons = s.open_view()?.info().expanded_polygons;
    let caster = caster_of(cb, polygons)?;
    let mut progress = ProgressCb::new(cb);
    let prepared = prepare::prepare(s, c, caster.is_some(), &mut progress, pool)?;
    if progress.stopped() {
        return Err(prepare::failure(hr::HrError::Cancelled));
    }
    let labels = if cb.labels == 1 {
        Some(RowLabels::shared(s.model()?))
    } else {
        None
    };
    let b = prepare::bytes(s, &prepared, c, caster.is_some())?;
    if (len as u64) < b.min {
        return Err(Failure::new(
            HiradStatus::WorkspaceTooSmall,
            format!(
                "the workspace of {len} bytes is below the {} bytes this scene and these settings need at least (suggested: {}; see hirad_plan)",
                b.min, b.suggested
            ),
        ));
    }
    let ws: &mut [u8] = if len == 0 {
        &mut []
    } else {
        // SAFETY: `len` writable bytes nothing else touches, by the caller's promise; cleared
        // first, so that the slice holds initialised bytes.
        unsafe {
            std::ptr::write_bytes(workspace, 0, len);
            std::slice::from_raw_parts_mut(workspace, len)
        }
    };
    let mut exec = Stoppable {
        inner: pool,
        stop: progress.stop.clone(),
    };
    let mut sink = SinkCb {
        user: cb.user,
        f: cb.polygon,
        labels,
        material: None,
    };
    let Some(view) = prepared.view(s) else {
        return Err(Failure::new(HiradStatus::NotOpen, "no open scene"));
    };
    let mut solved = c.core;
    let result = match &prepared.hi {
        Some(d) => {
            let (settings, _) = hirad::solve::hi_budget_plan(
                view,
                c.core,
                d.inline(),
                Some(len as u64),
                &mut |_| {},
            )
            .map_err(prepare::failure)?;
            solved = settings;
            hr::solve_hi(
                view,
                &settings,
                d.inline(),
                ws,
                &mut exec,
                &mut progress,
                &mut sink,
            )
        }
        None => hr::solve(
            view,
            &c.core,
            ws,
            caster.as_ref(),
            &mut exec,
            &mut progress,
            &mut sink,
        ),
    };
    let bands = view.info().bands;
    let st = match result {
        Ok(st) => st,
        Err(SolveError::Hr(e)) => return Err(prepare::failure(e)),
        Err(SolveError::Sink(code)) => {
            return Err(Failure::new(
                HiradStatus::SinkFailed,
                format!("the polygon callback returned {code}: the solve stopped there"),
            ));
        }
    };
    if caster
        .as_ref()
        .is_some_and(|v| v.bad_id.load(std::sync::atomic::Ordering::Relaxed))
    {
        return Err(Failure::new(
            HiradStatus::CasterFailed,
            format!(
                "the ray caster's first_hit named a polygon id at or past the scene's {polygons} polygons: the results were handed over but rest on misses"
            ),
        ));
    }
    *out = stats_of(&st, &prepared, &solved, bands, exec.inner.threads());
    out.seconds = start.elapsed().as_secs_f64();
    match verdict(&st, c, bands) {
        Some(why) => Err(Failure::new(HiradStatus::NotRight, why)),
        None => Ok(()),
    }
}

fn stats_of(
    st: &Stats,
    p: &Prepared,
    solved: &hr::Settings,
    bands: u32,
    threads: usize,
) -> HiradStats {
    let mut out = HiradStats {
        method: method_of(p),
        threads: threads as u32,
        bands,
        converged: u32::from(st.converged),
        budget_limited: u32::from(st.budget_limited),
        final_passes: st.final_passes,
        own_polygons: solved.own_polygons,
        blocking_polygons: solved.blocking_polygons,
        tables_made: p.tables_made,
        remaining_change: st.remaining_change,
        polygons: st.polygons,
        elements: st.clusters + st.patches,
        links: st.links,
        iterations: st.iterations,
        refinement_passes: st.refinement_passes,
        rays: st.rays,
        levels: st.levels,
        closed_instances: st.closed_instances,
        workspace_bytes: st.workspace_bytes,
        peak_workspace_bytes: st.peak_bytes,
        table_seconds: p.table_seconds,
        ..HiradStats::default()
    };
    let b = &st.balance;
    for k in 0..(bands as usize).min(HIRAD_MAX_BANDS) {
        out.emitted[k] = b.emitted[k];
        out.direct[k] = b.direct[k];
        out.absorbed[k] = b.absorbed[k];
        out.absorbed_backs[k] = b.absorbed_backs[k];
        out.escaped[k] = b.escaped[k];
        out.imbalance_percent[k] = 100.0 * b.relative_imbalance(k);
    }
    out
}

/// Why a finished solve's numbers are not right, as `hirad solve` decides (exit 1).
fn verdict(st: &Stats, c: &Checked, bands: u32) -> Option<String> {
    if !st.converged {
        return Some(format!(
            "the solution did not converge within {} iterations (estimated change still to come {:.1e} of the largest radiosity): every polygon was handed over, but the values are not final (raise tolerance, or check that the scene absorbs light)",
            c.core.max_iterations, st.remaining_change
        ));
    }
    let worst = (0..bands as usize).max_by(|&x, &y| {
        st.balance
            .relative_imbalance(x)
            .abs()
            .total_cmp(&st.balance.relative_imbalance(y).abs())
    })?;
    let off = 100.0 * st.balance.relative_imbalance(worst);
    (off.abs() > c.max_imbalance_percent).then(|| {
        format!(
            "band {worst}: the power balance is off by {off:+.3}% (in {:.6} W, out {:.6} W), above max_imbalance_percent {}: every polygon was handed over, but the values are not right",
            st.balance.emitted[worst] + st.balance.direct[worst],
            st.balance.absorbed[worst] + st.balance.absorbed_backs[worst] + st.balance.escaped[worst],
            c.max_imbalance_percent
        )
    })
}
