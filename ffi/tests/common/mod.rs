//! What the tests of the C functions share: fixtures compiled to images, a scene handle
//! freed on drop, settings, callbacks that record what a solve hands out (and may cancel or
//! fail), and a brute-force ray caster written apart from the core's.
#![allow(dead_code)] // each test file uses its own part

use hirad_ffi::*;
use std::ffi::{CStr, c_char, c_void};
use std::ptr;

pub fn fixture(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fixtures")
        .join(name)
}

/// A fixture compiled to an image.
pub fn image(name: &str) -> Vec<u8> {
    let scene = hirad::files::load_scene(&fixture(name)).unwrap().scene;
    hirad::scene::compile(&scene).unwrap()
}

pub struct Scene(pub *mut HiradScene);

impl Scene {
    pub fn open(bytes: &[u8]) -> Scene {
        let mut s: *mut HiradScene = ptr::null_mut();
        let status = unsafe { hirad_scene_open_memory(bytes.as_ptr(), bytes.len(), &mut s) };
        assert_eq!(status, HiradStatus::Ok);
        Scene(s)
    }

    pub fn message(&self) -> String {
        unsafe { CStr::from_ptr(hirad_scene_message(self.0)) }
            .to_string_lossy()
            .into_owned()
    }

    pub fn plan(&self, settings: &HiradSettings, cb: Option<&HiradCallbacks>) -> HiradPlan {
        let mut plan = HiradPlan::default();
        let cb = cb.map_or(ptr::null(), |c| c as *const HiradCallbacks);
        let status = unsafe { hirad_plan(self.0, settings, cb, &mut plan) };
        assert_eq!(status, HiradStatus::Ok, "{}", self.message());
        plan
    }
}

impl Drop for Scene {
    fn drop(&mut self) {
        unsafe { hirad_scene_free(self.0) };
    }
}

pub fn defaults() -> HiradSettings {
    let mut s = std::mem::MaybeUninit::<HiradSettings>::uninit();
    assert_eq!(
        unsafe { hirad_settings_default(s.as_mut_ptr()) },
        HiradStatus::Ok
    );
    unsafe { s.assume_init() }
}

/// Cheap settings for the tests that solve many times.
pub fn quick() -> HiradSettings {
    HiradSettings {
        epsilon: 1e-2,
        final_rays: 16,
        final_passes: 1,
        ..defaults()
    }
}

/// A polygon as the sink received it.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    pub id: u64,
    pub area: u32,
    pub material: u32,
    pub values: Vec<u32>,
    pub labels: Option<(String, String)>,
}

/// What the callbacks saw.
#[derive(Default)]
pub struct Seen {
    pub rows: Vec<Row>,
    /// Progress calls so far; the call with this index (from 0) answers "stop".
    pub calls: u64,
    pub stop_at: Option<u64>,
    /// The polygon callback fails (returns 7) at this row.
    pub fail_at: Option<usize>,
    /// Phases reported, in order of first appearance.
    pub phases: Vec<String>,
    /// World polygons for a caller's caster.
    pub world: Vec<HiradWorldPolygon>,
    /// The caster names this polygon id for every hit (to test a bad id).
    pub bad_id: bool,
    /// Progress and polygons came on other threads than the caller's.
    pub foreign_thread: bool,
    pub caller: Option<std::thread::ThreadId>,
}

impl Seen {
    /// Notes whether a callback runs on the thread that made this.
    pub fn on_caller(&mut self) {
        let me = std::thread::current().id();
        if *self.caller.get_or_insert(me) != me {
            self.foreign_thread = true;
        }
    }
}

pub unsafe extern "C" fn on_polygon(user: *mut c_void, p: *const HiradPolygon) -> i32 {
    let seen = unsafe { &mut *(user as *mut Seen) };
    seen.on_caller();
    let p = unsafe { &*p };
    if seen.fail_at == Some(seen.rows.len()) {
        return 7;
    }
    let n = p.bands as usize;
    let mut values = Vec::new();
    for a in [
        p.radiosity,
        p.irradiance,
        p.radiosity_back,
        p.irradiance_back,
    ] {
        if !a.is_null() {
            values.extend(
                unsafe { std::slice::from_raw_parts(a, n) }
                    .iter()
                    .map(|v| v.to_bits()),
            );
        }
    }
    assert_eq!(p.two_sided != 0, !p.radiosity_back.is_null());
    let text = |c: *const c_char| unsafe { CStr::from_ptr(c) }.to_string_lossy().into_owned();
    let labels = (!p.group.is_null()).then(|| (text(p.material_name), text(p.group)));
    seen.rows.push(Row {
        id: p.id,
        area: p.area.to_bits(),
        material: p.material,
        values,
        labels,
    });
    0
}

pub unsafe extern "C" fn on_progress(
    user: *mut c_void,
    phase: *const c_char,
    _: u64,
    _: u64,
) -> i32 {
    let seen = unsafe { &mut *(user as *mut Seen) };
    let phase = unsafe { CStr::from_ptr(phase) }
        .to_string_lossy()
        .into_owned();
    if !seen.phases.contains(&phase) {
        seen.phases.push(phase);
    }
    let stop = seen.stop_at.is_some_and(|k| seen.calls >= k);
    seen.calls += 1;
    i32::from(stop)
}

/// Möller-Trumbore over every world polygon in double precision, with the core BVH's margin
/// at both ends of a segment (written apart from the core's watertight test).
pub fn brute(
    seen: &Seen,
    from: [f32; 3],
    to: [f32; 3],
    skip: [u32; 2],
    any: bool,
) -> Option<(u32, f64)> {
    const MARGIN: f64 = 1e-5;
    let sub = |a: [f32; 3], b: [f32; 3]| {
        [
            a[0] as f64 - b[0] as f64,
            a[1] as f64 - b[1] as f64,
            a[2] as f64 - b[2] as f64,
        ]
    };
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let d = sub(to, from);
    let mut best: Option<(u32, f64)> = None;
    for (i, p) in seen.world.iter().enumerate() {
        if skip.contains(&(i as u32)) {
            continue;
        }
        for k in 2..p.corners as usize {
            let (a, b, c) = (p.corner[0], p.corner[k - 1], p.corner[k]);
            let (e1, e2, s) = (sub(b, a), sub(c, a), sub(from, a));
            let pv = cross(d, e2);
            let det = dot(e1, pv);
            if det == 0.0 {
                continue;
            }
            let u = dot(s, pv) / det;
            if !(0.0..=1.0).contains(&u) {
                continue;
            }
            let q = cross(s, e1);
            let v = dot(d, q) / det;
            if v < 0.0 || u + v > 1.0 {
                continue;
            }
            let t = dot(e2, q) / det;
            if t > MARGIN && t < 1.0 - MARGIN && best.is_none_or(|(_, b)| t < b) {
                best = Some((i as u32, t));
                if any {
                    return best;
                }
            }
        }
    }
    best
}

pub unsafe extern "C" fn transmittance(
    user: *mut c_void,
    from: *const f32,
    to: *const f32,
    skip: *const u32,
) -> f32 {
    let seen = unsafe { &*(user as *const Seen) };
    let (from, to, skip) = unsafe {
        (
            *(from as *const [f32; 3]),
            *(to as *const [f32; 3]),
            *(skip as *const [u32; 2]),
        )
    };
    if brute(seen, from, to, skip, true).is_some() {
        0.0
    } else {
        1.0
    }
}

pub unsafe extern "C" fn first_hit(
    user: *mut c_void,
    from: *const f32,
    to: *const f32,
    skip: *const u32,
    polygon: *mut u32,
    t: *mut f32,
) -> i32 {
    let seen = unsafe { &*(user as *const Seen) };
    let (from, to, skip) = unsafe {
        (
            *(from as *const [f32; 3]),
            *(to as *const [f32; 3]),
            *(skip as *const [u32; 2]),
        )
    };
    match brute(seen, from, to, skip, false) {
        Some((id, at)) => {
            unsafe {
                *polygon = if seen.bad_id { u32::MAX - 1 } else { id };
                *t = at as f32;
            }
            1
        }
        None => 0,
    }
}

pub fn callbacks(seen: &mut Seen) -> HiradCallbacks {
    seen.caller = Some(std::thread::current().id());
    HiradCallbacks {
        user: seen as *mut Seen as *mut c_void,
        progress: Some(on_progress),
        polygon: Some(on_polygon),
        ..HiradCallbacks::default()
    }
}

/// Solves in a workspace of `bytes` starting `offset` bytes into a fresh buffer.
pub fn solve_with(
    scene: &Scene,
    settings: &HiradSettings,
    cb: &HiradCallbacks,
    bytes: usize,
    offset: usize,
) -> (HiradStatus, HiradStats) {
    let mut buf = vec![0xA5u8; bytes + offset];
    let mut stats = HiradStats::default();
    let status = unsafe {
        hirad_solve(
            scene.0,
            settings,
            buf.as_mut_ptr().add(offset),
            bytes,
            cb,
            &mut stats,
        )
    };
    (status, stats)
}

pub fn solve(
    scene: &Scene,
    settings: &HiradSettings,
    seen: &mut Seen,
) -> (HiradStatus, HiradStats) {
    let plan = scene.plan(settings, None);
    let cb = callbacks(seen);
    solve_with(scene, settings, &cb, plan.suggested_bytes as usize, 0)
}

pub unsafe extern "C" fn read_bytes(
    user: *mut c_void,
    offset: u64,
    buf: *mut u8,
    len: usize,
) -> i32 {
    let bytes = unsafe { &*(user as *const Vec<u8>) };
    let from = offset as usize;
    match bytes.get(from..from + len) {
        Some(src) => {
            unsafe { ptr::copy_nonoverlapping(src.as_ptr(), buf, len) };
            0
        }
        None => 5,
    }
}
