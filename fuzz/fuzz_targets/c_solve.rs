//! The C ABI's plan and solve on arbitrary settings, workspaces and callbacks over valid
//! scene images (the fixtures; `c_api` fuzzes the images themselves). Each field of
//! `HiradSettings` is the default, a valid value or raw bits; the workspace is null, short,
//! the least, the suggestion or a misaligned slice; struct pointers may be null or
//! misaligned; the progress may cancel and the sink may fail at any point. Every call must
//! return a status (never INTERNAL, never a crash), and what the callbacks saw must agree
//! with it. Valid settings are kept cheap (a run must take a fraction of a second) and
//! tables are never made (minutes each).
#![no_main]

use hirad_ffi::*;
use libfuzzer_sys::fuzz_target;
use std::ffi::{CStr, c_char, c_void};
use std::ptr;
use std::sync::OnceLock;

/// The fixtures' images, compiled once.
fn images() -> &'static [Vec<u8>] {
    static IMAGES: OnceLock<Vec<Vec<u8>>> = OnceLock::new();
    IMAGES.get_or_init(|| {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures");
        [
            "small_plant.hir",
            "cornell_box.hir",
            "furnace.hir",
            "parallel_squares.hir",
        ]
        .iter()
        .map(|f| {
            let scene = hirad::files::load_scene(&root.join(f)).unwrap().scene;
            hirad::scene::compile(&scene).unwrap()
        })
        .collect()
    })
}

/// Reads the fuzz input a few bytes at a time (zeros once it runs out).
struct Bytes<'a>(&'a [u8]);

impl Bytes<'_> {
    fn u8(&mut self) -> u8 {
        match self.0.split_first() {
            Some((&b, rest)) => {
                self.0 = rest;
                b
            }
            None => 0,
        }
    }

    fn u32(&mut self) -> u32 {
        u32::from_le_bytes([self.u8(), self.u8(), self.u8(), self.u8()])
    }

    /// The default, one of `valid`, or raw bits.
    fn field(&mut self, default: u32, valid: &[u32]) -> u32 {
        match self.u8() % 4 {
            0 | 1 => default,
            2 if !valid.is_empty() => valid[self.u8() as usize % valid.len()],
            _ => self.u32(),
        }
    }

    fn float(&mut self, default: f32, valid: &[f32]) -> f32 {
        match self.u8() % 4 {
            0 | 1 => default,
            2 if !valid.is_empty() => valid[self.u8() as usize % valid.len()],
            _ => f32::from_bits(self.u32()),
        }
    }
}

/// What the callbacks saw.
#[derive(Default)]
struct Seen {
    ids: Vec<u64>,
    progress_calls: u64,
    cancel_at: Option<u64>,
    asked_stop: bool,
    fail_at: Option<usize>,
    bands: u32,
}

unsafe extern "C" fn on_progress(user: *mut c_void, phase: *const c_char, _: u64, _: u64) -> i32 {
    let seen = unsafe { &mut *(user as *mut Seen) };
    assert!(!unsafe { CStr::from_ptr(phase) }.to_bytes().is_empty());
    let stop = seen.cancel_at.is_some_and(|k| seen.progress_calls >= k);
    seen.progress_calls += 1;
    seen.asked_stop |= stop;
    i32::from(stop)
}

unsafe extern "C" fn on_polygon(user: *mut c_void, p: *const HiradPolygon) -> i32 {
    let seen = unsafe { &mut *(user as *mut Seen) };
    let p = unsafe { &*p };
    if seen.fail_at == Some(seen.ids.len()) {
        return 3;
    }
    assert_eq!(p.bands, seen.bands);
    for a in [p.radiosity, p.irradiance] {
        let v = unsafe { std::slice::from_raw_parts(a, p.bands as usize) };
        assert!(v.iter().all(|x| x.is_finite() && *x >= 0.0), "{v:?}");
    }
    seen.ids.push(p.id);
    0
}

unsafe extern "C" fn unused_transmittance(
    _: *mut c_void,
    _: *const f32,
    _: *const f32,
    _: *const u32,
) -> f32 {
    1.0
}

/// Keeps valid settings cheap: a finer solve tests nothing more of the C ABI.
fn cheap(s: &mut HiradSettings) {
    if s.epsilon.is_finite() && s.epsilon > 0.0 {
        s.epsilon = s.epsilon.max(2e-2);
    }
    if (1..=1024).contains(&s.rays) {
        s.rays = s.rays.min(4);
    }
    if s.final_rays != HIRAD_AUTO && s.final_rays <= 1 << 20 {
        s.final_rays = s.final_rays.min(16);
    }
    if s.max_depth <= 24 {
        s.max_depth = s.max_depth.min(6);
    }
    s.max_iterations = s.max_iterations.min(2000);
    s.max_rounds = s.max_rounds.min(4);
    if s.threads <= 1024 {
        s.threads %= 3;
    }
    if s.make_tables == 1 {
        s.make_tables = 0;
    }
}

fuzz_target!(|data: &[u8]| {
    let mut b = Bytes(data);
    let image = &images()[b.u8() as usize % images().len()];
    let mut scene: *mut HiradScene = ptr::null_mut();
    assert_eq!(
        unsafe { hirad_scene_open_memory(image.as_ptr(), image.len(), &mut scene) },
        HiradStatus::Ok
    );
    let mut info = HiradSceneInfo::default();
    assert_eq!(
        unsafe { hirad_scene_info(scene, &mut info) },
        HiradStatus::Ok
    );

    let d = HiradSettings::default();
    let mut s = HiradSettings {
        method: b.field(d.method, &[0, 1, 2]),
        instancing: b.field(d.instancing, &[0, 1, 2, 3]),
        instancing_every: b.field(d.instancing_every, &[1, 2, 3]),
        threads: b.field(d.threads, &[0, 1, 2]),
        epsilon: b.float(d.epsilon, &[1e-2, 5e-2, 0.2]),
        min_area: b.float(d.min_area, &[0.0, 1e-4, 0.5]),
        max_depth: b.field(d.max_depth, &[0, 2, 6]),
        rays: b.field(d.rays, &[1, 2, 4]),
        tolerance: b.float(d.tolerance, &[1e-3, 0.5]),
        max_iterations: b.field(d.max_iterations, &[0, 1, 5, 100]),
        max_rounds: b.field(d.max_rounds, &[0, 1, 3]),
        max_children: b.field(d.max_children, &[2, 4, 16]),
        final_rays: b.field(d.final_rays, &[0, 4, 16]),
        final_passes: b.field(d.final_passes, &[1, 2, 4]),
        sun_sides: b.field(d.sun_sides, &[1, 2, 3]),
        blocking_polygons: b.field(d.blocking_polygons, &[0, 10]),
        own_polygons: b.field(d.own_polygons, &[0, 10]),
        max_imbalance_percent: b.float(d.max_imbalance_percent, &[0.0, 1.0, 100.0]),
        make_tables: b.field(0, &[0]),
        table_max_side: b.field(d.table_max_side, &[0, 4, 128]),
    };
    cheap(&mut s);

    let mut seen = Seen {
        bands: info.bands,
        cancel_at: (b.u8() % 3 == 0).then(|| u64::from(b.u8())),
        fail_at: (b.u8() % 4 == 0).then(|| usize::from(b.u8())),
        ..Seen::default()
    };
    let callbacks = HiradCallbacks {
        user: &mut seen as *mut Seen as *mut c_void,
        progress: Some(on_progress),
        polygon: Some(on_polygon),
        // Half a caster must be refused.
        transmittance: (b.u8() % 8 == 0).then_some(unused_transmittance as _),
        first_hit: None,
        labels: u32::from(b.u8() % 3),
    };
    let mode = b.u8();
    let cb: *const HiradCallbacks = if mode & 1 == 0 {
        &callbacks
    } else {
        ptr::null()
    };

    let mut plan = HiradPlan::default();
    let planned = unsafe { hirad_plan(scene, &s, cb, &mut plan) };
    let message = || {
        unsafe { CStr::from_ptr(hirad_scene_message(scene)) }
            .to_str()
            .expect("messages are UTF-8")
            .to_string()
    };
    assert_ne!(planned, HiradStatus::Internal, "{}", message());
    if planned != HiradStatus::Ok {
        assert!(!message().is_empty());
    }

    // The workspace: null, empty, below the least, the least, the suggestion; at an offset.
    let want = plan.suggested_bytes.min(64 << 20) as usize;
    let len = match b.u8() % 6 {
        0 => 0,
        1 => (plan.min_bytes as usize).saturating_sub(1 + b.u8() as usize),
        2 => plan.min_bytes as usize,
        _ => want,
    };
    let offset = usize::from(b.u8() % 16);
    let mut buf = vec![0u8; len + offset];
    let workspace = if mode & 2 != 0 && len == 0 {
        ptr::null_mut()
    } else {
        unsafe { buf.as_mut_ptr().add(offset) }
    };
    // Room for a HiradStats at an offset of 4 bytes too.
    let mut raw = [0u64; std::mem::size_of::<HiradStats>() / 8 + 2];
    let stats: *mut HiradStats = match mode >> 2 & 3 {
        0 => ptr::null_mut(),
        1 => unsafe { (raw.as_mut_ptr() as *mut u8).add(4) as *mut HiradStats },
        _ => raw.as_mut_ptr() as *mut HiradStats,
    };
    let status = unsafe { hirad_solve(scene, &s, workspace, len, cb, stats) };
    let m = message();
    assert_ne!(status, HiradStatus::Internal, "{m}");
    let n = info.expanded_polygons as usize;
    match status {
        HiradStatus::Ok => {
            assert_eq!(planned, HiradStatus::Ok);
            assert!(m.is_empty());
            if !cb.is_null() {
                assert_eq!(
                    seen.ids,
                    (0..n as u64).collect::<Vec<_>>(),
                    "every polygon once, in order"
                );
            }
        }
        HiradStatus::NotRight => {
            if !cb.is_null() {
                assert_eq!(seen.ids.len(), n);
            }
        }
        HiradStatus::Cancelled => {
            assert!(seen.asked_stop);
            assert!(seen.ids.len() < n);
        }
        HiradStatus::SinkFailed => assert_eq!(Some(seen.ids.len()), seen.fail_at),
        HiradStatus::WorkspaceTooSmall => assert!(
            planned != HiradStatus::Ok || (len as u64) < plan.sure_bytes,
            "{len} {plan:?}: {m}"
        ),
        HiradStatus::Misaligned => assert!(mode >> 2 & 3 == 1),
        HiradStatus::NullArgument => assert!(workspace.is_null()),
        HiradStatus::InvalidSettings | HiradStatus::NoTables | HiradStatus::InvalidScene => {
            assert!(!m.is_empty())
        }
        other => panic!("{other:?}: {m}"),
    }
    // The handle stays usable.
    assert_eq!(
        unsafe { hirad_scene_info(scene, &mut info) },
        HiradStatus::Ok
    );
    unsafe { hirad_scene_free(scene) };
});
