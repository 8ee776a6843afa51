//! The C functions around a solve: labels and the results header as the command line writes
//! them, floats as its tables write them, every bad call and settings field refused with
//! its status and message, and hi's tables refused or made once.

mod common;

use common::*;
use hirad_ffi::*;
use std::ffi::{CStr, c_char};
use std::ptr;

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
