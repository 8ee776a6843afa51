//! Planning and solving through the C functions, called as C would: the numbers equal the
//! runner's own solve bit for bit (any thread count, any workspace alignment, a scene read
//! through the caller's function), and a caller's ray caster gives the core BVH's numbers.

mod common;

use common::*;
use hirad_ffi::*;
use std::ffi::c_void;
use std::ptr;

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
