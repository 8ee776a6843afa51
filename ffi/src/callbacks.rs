//! The caller's functions a solve calls: progress (which may cancel), a sink for every
//! finished polygon, and a ray caster standing for the core's BVH.

use glam::Vec3;
use hirad::output::RowLabels;
use hirad_core::hr;
use hirad_core::sink::{PatchResult, PolygonResult, Sink};
use hirad_core::visibility::Visibility;
use std::ffi::{CString, c_char, c_void};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// Told how a solve goes: `phase` (a NUL-terminated phase name such as "refining (links)",
/// valid during the call), `done` of `total` units (`total` 0: unknown). Non-zero asks the
/// solve to stop: it returns `HIRAD_STATUS_CANCELLED` at its next check (between passes,
/// iterations, levels and batches of the final gather) and hands out no further polygon.
pub type HiradProgressFn = Option<
    unsafe extern "C" fn(user: *mut c_void, phase: *const c_char, done: u64, total: u64) -> i32,
>;

/// Receives a finished polygon (valid during the call only). Non-zero stops the solve:
/// `hirad_solve` returns `HIRAD_STATUS_SINK_FAILED`, the code in the message.
pub type HiradPolygonFn =
    Option<unsafe extern "C" fn(user: *mut c_void, polygon: *const HiradPolygon) -> i32>;

/// The caller's ray caster: the fraction of light that passes the open segment
/// `from`..`to` (3 floats each, m, world space): 1.0 unblocked, 0.0 blocked. `skip` holds
/// two polygon ids (global ids of the expanded scene, see `hirad_scene_world_polygons`) to
/// ignore, `UINT32_MAX` for none. Called from several threads at once.
pub type HiradTransmittanceFn = Option<
    unsafe extern "C" fn(
        user: *mut c_void,
        from: *const f32,
        to: *const f32,
        skip: *const u32,
    ) -> f32,
>;

/// The caller's ray caster: the polygon the segment `from`..`to` meets first (not one in
/// `skip`): returns 1 with its id in `*polygon` and the segment parameter (0 at `from`, 1
/// at `to`) in `*t`, or 0 when nothing blocks. Called from several threads at once.
pub type HiradFirstHitFn = Option<
    unsafe extern "C" fn(
        user: *mut c_void,
        from: *const f32,
        to: *const f32,
        skip: *const u32,
        polygon: *mut u32,
        t: *mut f32,
    ) -> i32,
>;

/// The caller's functions for a solve; every one may be null. A null `HiradCallbacks`
/// pointer is the same as all null.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct HiradCallbacks {
    /// Handed to every function as it is.
    pub user: *mut c_void,
    /// Progress, and the way to cancel. Called on the thread that called `hirad_solve`,
    /// never concurrently.
    pub progress: HiradProgressFn,
    /// Every finished polygon, in increasing global id, as levels finish. Called on the
    /// thread that called `hirad_solve`, never concurrently.
    pub polygon: HiradPolygonFn,
    /// With `first_hit`: the caller's ray caster instead of the core's BVH (method HR only;
    /// give both or neither). Called from the solve's worker threads at once.
    pub transmittance: HiradTransmittanceFn,
    /// See `transmittance`.
    pub first_hit: HiradFirstHitFn,
    /// 1: every `HiradPolygon` carries its material's name and its group (the cluster
    /// path, as the `group` column of `hirad solve --results`); the scene's structure is
    /// then held in memory outside the workspace. 0: both null.
    pub labels: u32,
}

impl Default for HiradCallbacks {
    fn default() -> Self {
        HiradCallbacks {
            user: std::ptr::null_mut(),
            progress: None,
            polygon: None,
            transmittance: None,
            first_hit: None,
            labels: 0,
        }
    }
}

/// A finished polygon: area-weighted means over its patches. Pointers are valid during the
/// callback only.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct HiradPolygon {
    /// Global id: the polygon's index in the depth-first expansion of the scene.
    pub id: u64,
    /// Area (m^2).
    pub area: f32,
    /// Bands: the length of every array below.
    pub bands: u32,
    /// 1 when its material is two-sided (then the back arrays are non-null).
    pub two_sided: u32,
    /// Its material's index in the scene (see `hirad_scene_material_name`).
    pub material: u32,
    /// Front radiosity per band (W/m^2).
    pub radiosity: *const f32,
    /// Front irradiance per band (W/m^2).
    pub irradiance: *const f32,
    /// Back radiosity per band (W/m^2), null for a one-sided polygon.
    pub radiosity_back: *const f32,
    /// Back irradiance per band (W/m^2), null for a one-sided polygon.
    pub irradiance_back: *const f32,
    /// Its material's name (with `labels`), else null.
    pub material_name: *const c_char,
    /// Its group, the path of clusters from the scene's root (with `labels`), else null.
    pub group: *const c_char,
}

/// The caller's progress for the core, latching a request to stop (shared with the
/// executor, which then skips the batches a phase has left).
pub(crate) struct ProgressCb {
    pub user: *mut c_void,
    pub f: HiradProgressFn,
    pub phase: CString,
    pub stop: Arc<AtomicBool>,
}

impl ProgressCb {
    pub(crate) fn new(c: &HiradCallbacks) -> Self {
        ProgressCb {
            user: c.user,
            f: c.progress,
            phase: CString::default(),
            stop: Arc::new(AtomicBool::new(false)),
        }
    }

    /// True once the caller asked to stop.
    pub(crate) fn stopped(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }

    /// Tells the caller; true once it asked to stop.
    pub(crate) fn tell(&mut self, what: &str, done: u64, total: u64) -> bool {
        if let Some(f) = self.f {
            if self.phase.as_bytes() != what.as_bytes() {
                self.phase = CString::new(what.replace('\0', " ")).unwrap_or_default();
            }
            // SAFETY: the caller's function, given its own pointer and a live C string.
            if unsafe { f(self.user, self.phase.as_ptr(), done, total) } != 0 {
                self.stop.store(true, Ordering::Relaxed);
            }
        }
        self.stopped()
    }
}

impl hr::Progress for ProgressCb {
    fn report(&mut self, what: &str, done: u64, total: u64) {
        self.tell(what, done, total);
    }

    fn cancelled(&mut self) -> bool {
        self.stopped()
    }
}

/// The caller's polygon function as the core's sink (its error: the caller's code).
pub(crate) struct SinkCb {
    pub user: *mut c_void,
    pub f: HiradPolygonFn,
    pub labels: Option<RowLabels>,
    /// The material of the polygon whose patches are coming (from its first patch).
    pub material: Option<u32>,
}

impl Sink for SinkCb {
    type Error = i32;

    fn patch(&mut self, patch: &PatchResult<'_>) -> Result<(), i32> {
        self.material.get_or_insert(patch.material);
        Ok(())
    }

    fn polygon(&mut self, p: &PolygonResult<'_>) -> Result<(), i32> {
        let material = self.material.take().unwrap_or(u32::MAX);
        let Some(f) = self.f else {
            return Ok(());
        };
        let (name, group) = match self.labels.as_mut().and_then(|l| l.label(p.id)) {
            Some((m, g)) => (c_text(m), c_text(g)),
            None => (None, None),
        };
        let back = |v: &[f32]| {
            if v.is_empty() {
                std::ptr::null()
            } else {
                v.as_ptr()
            }
        };
        let out = HiradPolygon {
            id: p.id,
            area: p.area,
            bands: p.radiosity[0].len() as u32,
            two_sided: u32::from(p.two_sided),
            material,
            radiosity: p.radiosity[0].as_ptr(),
            irradiance: p.irradiance[0].as_ptr(),
            radiosity_back: back(p.radiosity[1]),
            irradiance_back: back(p.irradiance[1]),
            material_name: name.as_ref().map_or(std::ptr::null(), |s| s.as_ptr()),
            group: group.as_ref().map_or(std::ptr::null(), |s| s.as_ptr()),
        };
        // SAFETY: the caller's function, given its own pointer and a polygon whose arrays
        // and strings live until it returns.
        match unsafe { f(self.user, &out) } {
            0 => Ok(()),
            code => Err(code),
        }
    }
}

fn c_text(s: &str) -> Option<CString> {
    CString::new(s.replace('\0', " ")).ok()
}

/// The caller's ray caster as the core's `Visibility`.
pub(crate) struct CasterCb {
    pub user: *mut c_void,
    /// Polygons of the expanded scene: a hit on an id at or past it is the caller's fault.
    pub polygons: u64,
    /// Set when the caller's `first_hit` named a polygon that does not exist (taken as no
    /// hit, and the solve refused).
    pub bad_id: AtomicBool,
    pub transmittance: unsafe extern "C" fn(*mut c_void, *const f32, *const f32, *const u32) -> f32,
    pub first_hit: unsafe extern "C" fn(
        *mut c_void,
        *const f32,
        *const f32,
        *const u32,
        *mut u32,
        *mut f32,
    ) -> i32,
}

// SAFETY: the caller promises (see `HiradCallbacks::transmittance`) that its caster may be
// called from several threads at once with the same `user`.
unsafe impl Sync for CasterCb {}
// SAFETY: as for `Sync`: the pointer is only handed back to the caller's functions.
unsafe impl Send for CasterCb {}

impl Visibility for CasterCb {
    fn transmittance(&self, from: Vec3, to: Vec3, skip: [u32; 2]) -> f32 {
        let (a, b) = (from.to_array(), to.to_array());
        // SAFETY: the caller's function, given live arrays of 3, 3 and 2 values.
        let t = unsafe { (self.transmittance)(self.user, a.as_ptr(), b.as_ptr(), skip.as_ptr()) };
        // A caller's NaN or out-of-range answer must not poison the solution.
        if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) }
    }

    fn first_hit(&self, from: Vec3, to: Vec3, skip: [u32; 2]) -> Option<(u32, f32)> {
        let (a, b) = (from.to_array(), to.to_array());
        let (mut polygon, mut t) = (u32::MAX, f32::NAN);
        // SAFETY: the caller's function, given live arrays and two writable values.
        let hit = unsafe {
            (self.first_hit)(
                self.user,
                a.as_ptr(),
                b.as_ptr(),
                skip.as_ptr(),
                &mut polygon,
                &mut t,
            )
        };
        if hit != 0 && u64::from(polygon) >= self.polygons {
            self.bad_id.store(true, Ordering::Relaxed);
            return None;
        }
        (hit != 0 && t.is_finite()).then_some((polygon, t.clamp(0.0, 1.0)))
    }
}
