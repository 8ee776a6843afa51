//! Planning and solving through the C functions, called as C would: the numbers equal the
//! runner's own solve bit for bit (any thread count, any workspace alignment), a caller's
//! ray caster gives the core BVH's numbers, progress cancels at every phase, a failing sink
//! stops the solve, and every bad call gets its status and message.

use hirad_ffi::*;
use std::ffi::{CStr, c_char, c_void};
use std::ptr;

fn fixture(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fixtures")
        .join(name)
}

/// A fixture compiled to an image.
fn image(name: &str) -> Vec<u8> {
    let scene = hirad::files::load_scene(&fixture(name)).unwrap().scene;
    hirad::scene::compile(&scene).unwrap()
}

struct Scene(*mut HiradScene);

impl Scene {
    fn open(bytes: &[u8]) -> Scene {
        let mut s: *mut HiradScene = ptr::null_mut();
        let status = unsafe { hirad_scene_open_memory(bytes.as_ptr(), bytes.len(), &mut s) };
        assert_eq!(status, HiradStatus::Ok);
        Scene(s)
    }

    fn message(&self) -> String {
        unsafe { CStr::from_ptr(hirad_scene_message(self.0)) }
            .to_string_lossy()
            .into_owned()
    }

    fn plan(&self, settings: &HiradSettings, cb: Option<&HiradCallbacks>) -> HiradPlan {
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

fn defaults() -> HiradSettings {
    let mut s = std::mem::MaybeUninit::<HiradSettings>::uninit();
    assert_eq!(
        unsafe { hirad_settings_default(s.as_mut_ptr()) },
        HiradStatus::Ok
    );
    unsafe { s.assume_init() }
}

/// Cheap settings for the tests that solve many times.
fn quick() -> HiradSettings {
    HiradSettings {
        epsilon: 1e-2,
        final_rays: 16,
        final_passes: 1,
        ..defaults()
    }
}

/// A polygon as the sink received it.
#[derive(Clone, Debug, PartialEq)]
struct Row {
    id: u64,
    area: u32,
    material: u32,
    values: Vec<u32>,
    labels: Option<(String, String)>,
}

/// What the callbacks saw.
#[derive(Default)]
struct Seen {
    rows: Vec<Row>,
    /// Progress calls so far; the call with this index (from 0) answers "stop".
    calls: u64,
    stop_at: Option<u64>,
    /// The polygon callback fails (returns 7) at this row.
    fail_at: Option<usize>,
    /// Phases reported, in order of first appearance.
    phases: Vec<String>,
    /// World polygons for a caller's caster.
    world: Vec<HiradWorldPolygon>,
    /// The caster names this polygon id for every hit (to test a bad id).
    bad_id: bool,
    /// Progress and polygons came on other threads than the caller's.
    foreign_thread: bool,
    caller: Option<std::thread::ThreadId>,
}

impl Seen {
    /// Notes whether a callback runs on the thread that made this.
    fn on_caller(&mut self) {
        let me = std::thread::current().id();
        if *self.caller.get_or_insert(me) != me {
            self.foreign_thread = true;
        }
    }
}

unsafe extern "C" fn on_polygon(user: *mut c_void, p: *const HiradPolygon) -> i32 {
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

unsafe extern "C" fn on_progress(user: *mut c_void, phase: *const c_char, _: u64, _: u64) -> i32 {
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
fn brute(
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

unsafe extern "C" fn transmittance(
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

unsafe extern "C" fn first_hit(
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

fn callbacks(seen: &mut Seen) -> HiradCallbacks {
    seen.caller = Some(std::thread::current().id());
    HiradCallbacks {
        user: seen as *mut Seen as *mut c_void,
        progress: Some(on_progress),
        polygon: Some(on_polygon),
        ..HiradCallbacks::default()
    }
}

/// Solves in a workspace of `bytes` starting `offset` bytes into a fresh buffer.
fn solve_with(
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

fn solve(scene: &Scene, settings: &HiradSettings, seen: &mut Seen) -> (HiradStatus, HiradStats) {
    let plan = scene.plan(settings, None);
    let cb = callbacks(seen);
    solve_with(scene, settings, &cb, plan.suggested_bytes as usize, 0)
}

#[test]
fn hr_through_the_c_functions_equals_the_runners_solve_bit_for_bit() {
    let bytes = image("small_plant.hir");
    let scene = Scene::open(&bytes);
    let settings = defaults();
    let plan = scene.plan(&settings, None);
    assert_eq!(
        plan.method, HIRAD_METHOD_HR,
        "auto on the plant (no tables): hr"
    );
    assert!(
        plan.min_bytes > 0 && plan.min_bytes <= plan.suggested_bytes,
        "{plan:?}"
    );
    let mut seen = Seen::default();
    let (status, stats) = solve(&scene, &settings, &mut seen);
    assert_eq!(status, HiradStatus::Ok, "{}", scene.message());
    assert_eq!(scene.message(), "");

    let model = hirad::files::load_scene(&fixture("small_plant.hir"))
        .unwrap()
        .scene;
    let mut table = hirad::output::ResultsTable::new(2, true);
    let run = hirad::solve::solve_hr(
        &model,
        &hirad_core::hr::Settings::default(),
        2,
        None,
        hirad::solve::VisibilityChoice::Core,
        &hirad::output::Progress::new(true),
        &mut table,
    )
    .unwrap();
    assert_eq!(seen.rows.len(), table.len());
    for (row, r) in seen.rows.iter().enumerate() {
        assert_eq!(r.id, table.ids[row]);
        assert_eq!(r.area, table.areas[row].to_bits());
        let mut want: Vec<u32> = Vec::new();
        want.extend(table.radiosity(row, 0).iter().map(|v| v.to_bits()));
        want.extend(table.irradiance(row, 0).iter().map(|v| v.to_bits()));
        if !table.radiosity[1].is_empty() && r.values.len() > 4 {
            want.extend(table.radiosity(row, 1).iter().map(|v| v.to_bits()));
            want.extend(table.irradiance(row, 1).iter().map(|v| v.to_bits()));
        }
        assert_eq!(r.values, want, "polygon {}", r.id);
    }
    // The stats are the solve's.
    assert_eq!(stats.method, HIRAD_METHOD_HR);
    assert_eq!(stats.polygons, run.stats.polygons);
    assert_eq!(stats.links, run.stats.links);
    assert_eq!(stats.bands, 2);
    assert_eq!(stats.converged, 1);
    for b in 0..2 {
        assert_eq!(stats.absorbed[b], run.stats.balance.absorbed[b]);
        assert!(stats.imbalance_percent[b].abs() < 1.0, "{stats:?}");
    }
    assert_eq!(stats.workspace_bytes, plan.suggested_bytes);
    assert!(
        !seen.foreign_thread,
        "progress and polygons on the caller's thread only"
    );
    // Phases were told, in the core's names.
    assert!(
        seen.phases.iter().any(|p| p.starts_with("refining")),
        "{:?}",
        seen.phases
    );
}

#[test]
fn thread_counts_and_workspace_alignments_give_identical_results() {
    let bytes = image("small_plant.hir");
    let scene = Scene::open(&bytes);
    let mut reference: Option<Vec<Row>> = None;
    for threads in [1u32, 2, 3] {
        for offset in [0usize, 1, 3, 8, 13] {
            let settings = HiradSettings { threads, ..quick() };
            let plan = scene.plan(&settings, None);
            let mut seen = Seen::default();
            let cb = callbacks(&mut seen);
            // Room for any alignment: the core aligns the workspace itself.
            let (status, _) = solve_with(
                &scene,
                &settings,
                &cb,
                plan.suggested_bytes as usize + 64,
                offset,
            );
            assert_eq!(status, HiradStatus::Ok, "{}", scene.message());
            match &reference {
                None => reference = Some(seen.rows),
                Some(r) => assert!(*r == seen.rows, "threads {threads}, offset {offset}"),
            }
        }
    }
}

#[test]
fn a_callers_ray_caster_gives_the_core_bvhs_radiosity() {
    for name in ["small_plant.hir", "cornell_box.hir", "leaves_cluster.hir"] {
        let bytes = image(name);
        let scene = Scene::open(&bytes);
        let settings = HiradSettings {
            method: HIRAD_METHOD_HR,
            ..quick()
        };
        let mut core = Seen::default();
        let (status, _) = solve(&scene, &settings, &mut core);
        assert_eq!(status, HiradStatus::Ok, "{name}: {}", scene.message());

        let mut info = HiradSceneInfo::default();
        assert_eq!(
            unsafe { hirad_scene_info(scene.0, &mut info) },
            HiradStatus::Ok
        );
        let mut mine = Seen {
            world: vec![HiradWorldPolygon::default(); info.expanded_polygons as usize],
            ..Seen::default()
        };
        let n = mine.world.len() as u64;
        assert_eq!(
            unsafe { hirad_scene_world_polygons(scene.0, mine.world.as_mut_ptr(), n) },
            HiradStatus::Ok
        );
        let cb = HiradCallbacks {
            transmittance: Some(transmittance),
            first_hit: Some(first_hit),
            ..callbacks(&mut mine)
        };
        let plan = scene.plan(&settings, Some(&cb));
        assert!(plan.min_bytes > 0);
        let (status, _) = solve_with(&scene, &settings, &cb, plan.suggested_bytes as usize, 0);
        assert_eq!(status, HiradStatus::Ok, "{name}: {}", scene.message());
        assert_eq!(core.rows.len(), mine.rows.len());
        // Within float rounding: the same rays, decided by two different crossing tests.
        let mut worst = 0.0f64;
        for (a, b) in core.rows.iter().zip(&mine.rows) {
            assert_eq!(a.id, b.id);
            for (x, y) in a.values.iter().zip(&b.values) {
                let (x, y) = (f32::from_bits(*x) as f64, f32::from_bits(*y) as f64);
                worst = worst.max((x - y).abs() / x.abs().max(1e-6));
            }
        }
        assert!(worst <= 1e-5, "{name}: worst relative difference {worst:e}");
    }
}

#[test]
fn a_caster_naming_a_polygon_that_does_not_exist_is_refused() {
    let bytes = image("cornell_box.hir");
    let scene = Scene::open(&bytes);
    let mut info = HiradSceneInfo::default();
    unsafe { hirad_scene_info(scene.0, &mut info) };
    let mut mine = Seen {
        world: vec![HiradWorldPolygon::default(); info.expanded_polygons as usize],
        bad_id: true,
        ..Seen::default()
    };
    let n = mine.world.len() as u64;
    unsafe { hirad_scene_world_polygons(scene.0, mine.world.as_mut_ptr(), n) };
    let settings = HiradSettings {
        method: HIRAD_METHOD_HR,
        ..quick()
    };
    let cb = HiradCallbacks {
        transmittance: Some(transmittance),
        first_hit: Some(first_hit),
        ..callbacks(&mut mine)
    };
    let plan = scene.plan(&settings, Some(&cb));
    let (status, _) = solve_with(&scene, &settings, &cb, plan.suggested_bytes as usize, 0);
    assert_eq!(status, HiradStatus::CasterFailed, "{}", scene.message());
    assert!(scene.message().contains("first_hit"), "{}", scene.message());
    // Half a caster is refused before anything runs.
    let half = HiradCallbacks {
        first_hit: None,
        ..cb
    };
    let (status, _) = solve_with(&scene, &settings, &half, plan.suggested_bytes as usize, 0);
    assert_eq!(status, HiradStatus::InvalidSettings);
    assert!(scene.message().contains("both"), "{}", scene.message());
}

#[test]
fn progress_cancels_at_every_point_of_the_solve() {
    let bytes = image("small_plant.hir");
    let scene = Scene::open(&bytes);
    let settings = quick();
    // How many progress calls a whole solve makes.
    let mut all = Seen::default();
    assert_eq!(solve(&scene, &settings, &mut all).0, HiradStatus::Ok);
    let calls = all.calls;
    assert!(calls > 10, "{calls}");
    let mut stops = vec![0, 1, 2, 5, calls / 3, calls / 2, calls - 2, calls - 1];
    stops.dedup();
    for k in stops {
        let mut seen = Seen {
            stop_at: Some(k),
            ..Seen::default()
        };
        let (status, _) = solve(&scene, &settings, &mut seen);
        if k + 1 == calls && status == HiradStatus::Ok {
            // Asked at the very last report: every polygon was already out.
            assert!(seen.rows == all.rows);
            continue;
        }
        assert_eq!(
            status,
            HiradStatus::Cancelled,
            "stop at call {k} of {calls}: {}",
            scene.message()
        );
        assert!(scene.message().contains("cancelled"), "{}", scene.message());
        // Whatever was handed over before is a prefix of the whole, in order.
        assert!(
            seen.rows.len() < all.rows.len(),
            "stop at {k}: every polygon handed over"
        );
        assert_eq!(seen.rows[..], all.rows[..seen.rows.len()]);
        // It stopped soon after being asked.
        assert!(seen.calls <= k + 3, "stop at {k}: {} calls", seen.calls);
    }
}

#[test]
fn progress_cancels_hierarchical_instantiation_too() {
    let bytes = image("small_plant.hir");
    let scene = Scene::open(&bytes);
    // Tables are made for the closed twigs and branches (coarse, to be quick).
    let settings = HiradSettings {
        method: HIRAD_METHOD_HI,
        instancing: HIRAD_INSTANCING_ALL,
        table_max_side: 4,
        ..quick()
    };
    let mut all = Seen::default();
    let (status, stats) = solve(&scene, &settings, &mut all);
    assert!(
        matches!(status, HiradStatus::Ok | HiradStatus::NotRight),
        "{status:?}: {}",
        scene.message()
    );
    assert_eq!(stats.method, HIRAD_METHOD_HI);
    assert!(stats.levels > 1, "{stats:?}");
    assert_eq!(all.rows.len() as u64, stats.polygons);
    assert!(
        !all.foreign_thread,
        "progress and polygons on the caller's thread only"
    );
    let calls = all.calls;
    for k in [0, calls / 4, calls / 2, calls - 1] {
        let mut seen = Seen {
            stop_at: Some(k),
            ..Seen::default()
        };
        let (status, _) = solve(&scene, &settings, &mut seen);
        if k + 1 == calls && status == HiradStatus::Ok {
            // Asked at the very last report: every polygon was already out.
            assert!(seen.rows == all.rows);
            continue;
        }
        assert_eq!(
            status,
            HiradStatus::Cancelled,
            "stop at {k} of {calls}: {}",
            scene.message()
        );
        assert!(seen.rows.len() < all.rows.len());
        assert_eq!(seen.rows[..], all.rows[..seen.rows.len()]);
        assert!(seen.calls <= k + 3, "stop at {k}: {} calls", seen.calls);
    }
}

#[test]
fn a_failing_sink_stops_the_solve_with_its_code() {
    let bytes = image("small_plant.hir");
    let scene = Scene::open(&bytes);
    for at in [0usize, 1, 50, 104] {
        let mut seen = Seen {
            fail_at: Some(at),
            ..Seen::default()
        };
        let (status, _) = solve(&scene, &quick(), &mut seen);
        assert_eq!(status, HiradStatus::SinkFailed);
        assert!(
            scene.message().contains("returned 7"),
            "{}",
            scene.message()
        );
        assert_eq!(seen.rows.len(), at, "no polygon after the failing one");
    }
}

#[test]
fn a_solve_that_does_not_converge_hands_everything_over_and_says_not_right() {
    let bytes = image("furnace_099.hir");
    let scene = Scene::open(&bytes);
    let settings = HiradSettings {
        max_iterations: 2,
        ..quick()
    };
    let mut seen = Seen::default();
    let (status, stats) = solve(&scene, &settings, &mut seen);
    assert_eq!(status, HiradStatus::NotRight, "{}", scene.message());
    assert!(
        scene.message().contains("did not converge"),
        "{}",
        scene.message()
    );
    assert_eq!(stats.converged, 0);
    assert_eq!(seen.rows.len() as u64, stats.polygons);
    assert!(stats.polygons > 0);
    // A balance limit no solve meets.
    let strict = HiradSettings {
        max_imbalance_percent: 0.0,
        ..quick()
    };
    let bytes = image("small_plant.hir");
    let plant = Scene::open(&bytes);
    let (status, stats) = solve(&plant, &strict, &mut Seen::default());
    assert_eq!(status, HiradStatus::NotRight, "{}", plant.message());
    assert!(
        plant.message().contains("max_imbalance_percent"),
        "{}",
        plant.message()
    );
    assert!(stats.imbalance_percent[..2].iter().any(|&x| x != 0.0));
}

#[test]
fn labels_and_the_header_are_the_command_lines() {
    let bytes = image("small_plant.hir");
    let scene = Scene::open(&bytes);
    let mut seen = Seen::default();
    let cb = HiradCallbacks {
        labels: 1,
        ..callbacks(&mut seen)
    };
    let settings = quick();
    let plan = scene.plan(&settings, None);
    let (status, _) = solve_with(&scene, &settings, &cb, plan.suggested_bytes as usize, 0);
    assert_eq!(status, HiradStatus::Ok);
    let model = hirad::files::load_scene(&fixture("small_plant.hir"))
        .unwrap()
        .scene;
    let mut labels = hirad::output::RowLabels::of(&model);
    for r in &seen.rows {
        let (m, g) = labels.label(r.id).unwrap();
        assert_eq!(r.labels.as_ref().unwrap(), &(m.to_string(), g.to_string()));
        let mut name: *const c_char = ptr::null();
        assert_eq!(
            unsafe { hirad_scene_material_name(scene.0, r.material, &mut name) },
            HiradStatus::Ok
        );
        assert_eq!(unsafe { CStr::from_ptr(name) }.to_str().unwrap(), m);
    }
    let (mut header, mut two) = (ptr::null(), 0u32);
    assert_eq!(
        unsafe { hirad_scene_results_header(scene.0, &mut header, &mut two) },
        HiradStatus::Ok
    );
    assert_eq!(
        unsafe { CStr::from_ptr(header) }.to_str().unwrap(),
        "id,area_m2,rad_par_W_m2,rad_nir_W_m2,irr_par_W_m2,irr_nir_W_m2,rad_back_par_W_m2,rad_back_nir_W_m2,irr_back_par_W_m2,irr_back_nir_W_m2,material,group"
    );
    assert_eq!(two, 1);
    let mut name: *const c_char = ptr::null();
    assert_eq!(
        unsafe { hirad_scene_material_name(scene.0, 99, &mut name) },
        HiradStatus::InvalidSettings
    );
    // World polygons need room for every one.
    let mut few = vec![HiradWorldPolygon::default(); 3];
    assert_eq!(
        unsafe { hirad_scene_world_polygons(scene.0, few.as_mut_ptr(), 3) },
        HiradStatus::ShortBuffer
    );
    assert!(
        scene.message().contains("105 polygons"),
        "{}",
        scene.message()
    );
}

#[test]
fn floats_are_written_as_the_tables_write_them() {
    let mut buf = [0 as c_char; 64];
    let mut x = 0x9E37_79B9u32;
    let mut values = vec![
        0.0f32,
        -0.0,
        1.0,
        0.1,
        1e-45,
        f32::MAX,
        f32::MIN,
        f32::INFINITY,
        f32::NAN,
        0.0067882254,
    ];
    for _ in 0..2000 {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        values.push(f32::from_bits(x));
    }
    for v in values {
        let n = unsafe { hirad_format_float(v, buf.as_mut_ptr(), buf.len()) };
        let text = unsafe { CStr::from_ptr(buf.as_ptr()) }.to_str().unwrap();
        assert_eq!(text, v.to_string());
        assert_eq!(n, text.len());
        if v.is_finite() {
            assert_eq!(text.parse::<f32>().unwrap().to_bits(), v.to_bits());
        }
        // Too short: the length all the same, an empty string written.
        let m = unsafe { hirad_format_float(v, buf.as_mut_ptr(), n) };
        assert_eq!(m, n);
        assert_eq!(buf[0], 0);
    }
}

#[test]
fn bad_calls_get_statuses_and_messages() {
    let bytes = image("small_plant.hir");
    let scene = Scene::open(&bytes);
    let settings = quick();
    let plan = scene.plan(&settings, None);
    let mut ws = vec![0u8; plan.suggested_bytes as usize];
    let mut stats = HiradStats::default();
    let call = |scene: *mut HiradScene,
                settings: *const HiradSettings,
                ws: *mut u8,
                len: usize,
                stats: *mut HiradStats| unsafe {
        hirad_solve(scene, settings, ws, len, ptr::null(), stats)
    };
    let w = ws.as_mut_ptr();
    assert_eq!(
        call(ptr::null_mut(), &settings, w, ws.len(), &mut stats),
        HiradStatus::NullArgument
    );
    assert_eq!(
        call(scene.0, ptr::null(), w, ws.len(), &mut stats),
        HiradStatus::NullArgument
    );
    assert_eq!(
        call(scene.0, &settings, ptr::null_mut(), 10, &mut stats),
        HiradStatus::NullArgument
    );
    // Misaligned struct pointers are refused, not read.
    let mut raw = vec![0u64; 64];
    let odd = unsafe { (raw.as_mut_ptr() as *mut u8).add(1) };
    assert_eq!(
        call(
            scene.0,
            odd as *const HiradSettings,
            w,
            ws.len(),
            &mut stats
        ),
        HiradStatus::Misaligned
    );
    assert_eq!(
        call(scene.0, &settings, w, ws.len(), odd as *mut HiradStats),
        HiradStatus::Misaligned
    );
    assert_eq!(
        unsafe { hirad_settings_default(odd as *mut HiradSettings) },
        HiradStatus::Misaligned
    );
    let mut p = HiradPlan::default();
    assert_eq!(
        unsafe { hirad_plan(scene.0, &settings, odd as *const HiradCallbacks, &mut p) },
        HiradStatus::Misaligned
    );
    assert_eq!(
        unsafe { hirad_plan(scene.0, &settings, ptr::null(), ptr::null_mut()) },
        HiradStatus::NullArgument
    );
    // A workspace below the least: refused before anything runs, saying how much.
    for len in [0usize, 1, plan.min_bytes as usize - 1] {
        assert_eq!(
            call(scene.0, &settings, w, len, &mut stats),
            HiradStatus::WorkspaceTooSmall,
            "{len}"
        );
        assert!(
            scene.message().contains(&plan.min_bytes.to_string()),
            "{}",
            scene.message()
        );
    }
    // At the least it solves (the budget may cut refinement short).
    let status = call(scene.0, &settings, w, plan.min_bytes as usize, &mut stats);
    assert!(
        matches!(status, HiradStatus::Ok | HiradStatus::NotRight),
        "{status:?}: {}",
        scene.message()
    );
    // A handle whose opening failed.
    let mut broken: *mut HiradScene = ptr::null_mut();
    let short = &bytes[..100];
    unsafe { hirad_scene_open_memory(short.as_ptr(), short.len(), &mut broken) };
    assert_eq!(
        call(broken, &settings, w, ws.len(), &mut stats),
        HiradStatus::NotOpen
    );
    assert_eq!(
        unsafe { hirad_plan(broken, &settings, ptr::null(), &mut p) },
        HiradStatus::NotOpen
    );
    unsafe { hirad_scene_free(broken) };
}

#[test]
fn settings_out_of_range_are_refused_naming_the_field() {
    let bytes = image("small_plant.hir");
    let scene = Scene::open(&bytes);
    let d = defaults();
    let cases: Vec<(HiradSettings, &str)> = vec![
        (HiradSettings { method: 3, ..d }, "method"),
        (
            HiradSettings {
                method: u32::MAX,
                ..d
            },
            "method",
        ),
        (HiradSettings { instancing: 4, ..d }, "instancing"),
        (
            HiradSettings {
                instancing: HIRAD_INSTANCING_EVERY,
                instancing_every: 0,
                ..d
            },
            "instancing_every",
        ),
        (
            HiradSettings {
                method: HIRAD_METHOD_HR,
                instancing: HIRAD_INSTANCING_ALL,
                ..d
            },
            "instancing",
        ),
        (HiradSettings { threads: 1025, ..d }, "threads"),
        (HiradSettings { epsilon: 0.0, ..d }, "epsilon"),
        (
            HiradSettings {
                epsilon: f32::NAN,
                ..d
            },
            "epsilon",
        ),
        (HiradSettings { epsilon: -1.0, ..d }, "epsilon"),
        (HiradSettings { min_area: 1.0, ..d }, "min_area"),
        (HiradSettings { max_depth: 25, ..d }, "max_depth"),
        (HiradSettings { rays: 0, ..d }, "rays"),
        (HiradSettings { rays: 1025, ..d }, "rays"),
        (
            HiradSettings {
                tolerance: 0.0,
                ..d
            },
            "tolerance",
        ),
        (
            HiradSettings {
                tolerance: f32::INFINITY,
                ..d
            },
            "tolerance",
        ),
        (
            HiradSettings {
                max_children: 1,
                ..d
            },
            "max_children",
        ),
        (
            HiradSettings {
                max_children: 17,
                ..d
            },
            "max_children",
        ),
        (
            HiradSettings {
                final_rays: (1 << 20) + 1,
                ..d
            },
            "final_rays",
        ),
        (
            HiradSettings {
                final_passes: 0,
                ..d
            },
            "final_passes",
        ),
        (
            HiradSettings {
                final_passes: 5,
                ..d
            },
            "final_passes",
        ),
        (HiradSettings { sun_sides: 0, ..d }, "sun_sides"),
        (HiradSettings { sun_sides: 4, ..d }, "sun_sides"),
        (
            HiradSettings {
                sun_sides: 256 + 3,
                ..d
            },
            "sun_sides",
        ),
        (
            HiradSettings {
                max_imbalance_percent: -1.0,
                ..d
            },
            "max_imbalance_percent",
        ),
        (
            HiradSettings {
                max_imbalance_percent: f32::NAN,
                ..d
            },
            "max_imbalance_percent",
        ),
        (
            HiradSettings {
                make_tables: 2,
                ..d
            },
            "make_tables",
        ),
        (
            HiradSettings {
                table_max_side: 3,
                ..d
            },
            "table_max_side",
        ),
        (
            HiradSettings {
                table_max_side: 129,
                ..d
            },
            "table_max_side",
        ),
    ];
    let mut ws = vec![0u8; 1 << 20];
    for (s, field) in cases {
        let mut p = HiradPlan::default();
        let status = unsafe { hirad_plan(scene.0, &s, ptr::null(), &mut p) };
        assert_eq!(status, HiradStatus::InvalidSettings, "{field}: {s:?}");
        assert!(
            scene.message().contains(field),
            "{field}: {}",
            scene.message()
        );
        let mut stats = HiradStats::default();
        let status = unsafe {
            hirad_solve(
                scene.0,
                &s,
                ws.as_mut_ptr(),
                ws.len(),
                ptr::null(),
                &mut stats,
            )
        };
        assert_eq!(status, HiradStatus::InvalidSettings, "{field}");
    }
}

#[test]
fn hi_without_tables_refuses_unless_it_may_make_them() {
    let bytes = image("small_plant.hir");
    let scene = Scene::open(&bytes);
    let settings = HiradSettings {
        method: HIRAD_METHOD_HI,
        instancing: HIRAD_INSTANCING_ALL,
        make_tables: 0,
        ..quick()
    };
    let mut p = HiradPlan::default();
    let status = unsafe { hirad_plan(scene.0, &settings, ptr::null(), &mut p) };
    assert_eq!(status, HiradStatus::NoTables);
    let m = scene.message();
    assert!(
        m.contains("twig") && m.contains("branch") && m.contains("make_tables"),
        "{m}"
    );
    // hi with a caller's caster is refused: each level casts through its own BVH.
    let mut seen = Seen::default();
    let cb = HiradCallbacks {
        transmittance: Some(transmittance),
        first_hit: Some(first_hit),
        ..callbacks(&mut seen)
    };
    let made = HiradSettings {
        make_tables: 1,
        table_max_side: 4,
        ..settings
    };
    let status = unsafe { hirad_plan(scene.0, &made, &cb, &mut p) };
    assert_eq!(status, HiradStatus::InvalidSettings);
    assert!(
        scene.message().contains("HIRAD_METHOD_HR"),
        "{}",
        scene.message()
    );
    // Made once (telling the progress), kept with the handle: the second plan makes none.
    let mut seen = Seen::default();
    let first = scene.plan(&made, Some(&callbacks(&mut seen)));
    assert_eq!(first.method, HIRAD_METHOD_HI);
    assert_eq!(first.tables_made, 2);
    assert!(
        first.min_bytes <= first.sure_bytes && first.sure_bytes <= first.suggested_bytes,
        "{first:?}"
    );
    assert!(!seen.phases.is_empty());
    let again = scene.plan(&made, None);
    assert_eq!(again.tables_made, 0);
    assert_eq!(again.suggested_bytes, first.suggested_bytes);
}

unsafe extern "C" fn read_bytes(user: *mut c_void, offset: u64, buf: *mut u8, len: usize) -> i32 {
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

#[test]
fn a_scene_read_through_the_callers_function_solves_as_one_in_memory() {
    for (name, settings) in [
        ("small_plant.hir", quick()),
        (
            "small_plant.hir",
            HiradSettings {
                method: HIRAD_METHOD_HI,
                instancing: HIRAD_INSTANCING_ALL,
                table_max_side: 4,
                threads: 2,
                ..quick()
            },
        ),
        (
            "chair_room.hir",
            HiradSettings {
                threads: 2,
                ..quick()
            },
        ),
    ] {
        let bytes = image(name);
        let memory = Scene::open(&bytes);
        let mut a = Seen::default();
        let (status, _) = solve(&memory, &settings, &mut a);
        assert!(
            matches!(status, HiradStatus::Ok | HiradStatus::NotRight),
            "{name}: {}",
            memory.message()
        );

        let mut s: *mut HiradScene = ptr::null_mut();
        let status = unsafe {
            hirad_scene_open_reader(
                Some(read_bytes),
                &bytes as *const Vec<u8> as *mut c_void,
                bytes.len() as u64,
                &mut s,
            )
        };
        assert_eq!(status, HiradStatus::Ok);
        let reader = Scene(s);
        let mut b = Seen::default();
        let (status, _) = solve(&reader, &settings, &mut b);
        assert!(
            matches!(status, HiradStatus::Ok | HiradStatus::NotRight),
            "{name}: {}",
            reader.message()
        );
        assert!(a.rows == b.rows, "{name}");
    }
}
