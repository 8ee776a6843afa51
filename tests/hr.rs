//! The hierarchical solver against known answers: analytic form factors, closed furnaces,
//! the exact solver on the Cornell box, budgets, determinism, scale and translucency.

use hirad::exact::{ExactSettings, solve_exact_obvhs};
use hirad::output::ResultsTable;
use hirad::scene::{Scene, read_image};
use hirad::solve::{RayonExecutor, world_polygons};
use hirad::visibility::ObvhsVisibility;
use hirad_core::hr::{
    self, Executor, HrError, NoProgress, Sequential, Settings, SolveError, Stats,
};
use hirad_tests::fixture;

fn load(name: &str) -> Scene {
    hirad::text::parse(&std::fs::read(fixture(name)).unwrap()).unwrap()
}

/// How a test runs the solver.
#[derive(Clone, Copy, PartialEq)]
enum Run {
    /// Core BVH, sequential.
    Core,
    /// Core BVH, rayon with this many threads.
    CoreThreads(usize),
    /// obvhs, rayon with this many threads.
    Obvhs(usize),
}

fn solve_with(
    scene: &Scene,
    settings: &Settings,
    run: Run,
    memory: Option<usize>,
) -> Result<(ResultsTable, Stats), SolveError<String>> {
    let bytes = hirad::scene::compile(scene).unwrap();
    let view = read_image(&bytes).unwrap();
    let internal = matches!(run, Run::Core | Run::CoreThreads(_));
    let mut scratch = vec![0u8; hr::census_scratch_bytes(&view)];
    let plan = hr::plan(&view, settings, internal, &mut scratch).unwrap();
    let mut ws = vec![0u8; memory.unwrap_or(plan.suggested_bytes as usize)];
    let two_sided = scene.materials.iter().any(|m| m.data.two_sided);
    let mut table = ResultsTable::new(scene.bands as usize, two_sided);
    let stats = match run {
        Run::Core => hr::solve(
            &view,
            settings,
            &mut ws,
            None::<&ObvhsVisibility>,
            &mut Sequential,
            &mut NoProgress,
            &mut table,
        ),
        Run::CoreThreads(threads) => {
            let mut exec = RayonExecutor::new(threads).unwrap();
            hr::solve(
                &view,
                settings,
                &mut ws,
                None::<&ObvhsVisibility>,
                &mut exec,
                &mut NoProgress,
                &mut table,
            )
        }
        Run::Obvhs(threads) => {
            let vis = ObvhsVisibility::new(&world_polygons(scene)).unwrap();
            let mut exec = RayonExecutor::new(threads).unwrap();
            run_exec(&view, settings, &mut ws, &vis, &mut exec, &mut table)
        }
    }
    .map_err(|e| match e {
        SolveError::Hr(h) => SolveError::Hr(h),
        SolveError::Sink(s) => SolveError::Sink(s.to_string()),
    })?;
    Ok((table, stats))
}

fn run_exec<E: Executor>(
    view: &hirad_core::image::SceneView<hirad_core::image::SliceSource<'_>>,
    settings: &Settings,
    ws: &mut [u8],
    vis: &ObvhsVisibility,
    exec: &mut E,
    table: &mut ResultsTable,
) -> Result<Stats, SolveError<anyhow::Error>> {
    hr::solve(view, settings, ws, Some(vis), exec, &mut NoProgress, table)
}

fn solve(name: &str, settings: &Settings, run: Run) -> (ResultsTable, Stats) {
    solve_with(&load(name), settings, run, None).unwrap()
}

#[test]
fn plate_form_factors_within_one_percent() {
    for run in [Run::Core, Run::Obvhs(2)] {
        for (name, expected) in [
            ("parallel_squares.hir", 0.199825f32),
            ("perpendicular_squares.hir", 0.200044),
        ] {
            let (t, _) = solve(name, &Settings::default(), run);
            let h = t.irradiance(1, 0)[0];
            assert!(
                (h / expected - 1.0).abs() < 0.01,
                "{name}: irradiance {h}, expected {expected}"
            );
            assert_eq!(t.radiosity(0, 0)[0], 1.0, "{name}: the emitter keeps E");
        }
    }
}

#[test]
fn closed_furnaces_hold_e_over_one_minus_rho() {
    for (name, expected) in [("furnace.hir", 2.0f32), ("furnace_099.hir", 100.0)] {
        let (t, stats) = solve(name, &Settings::default(), Run::Obvhs(2));
        for row in 0..t.len() {
            let b = t.radiosity(row, 0)[0];
            assert!(
                (b / expected - 1.0).abs() < 0.005,
                "{name}: polygon {row}: B = {b}, expected {expected}"
            );
        }
        assert!(!stats.iteration_capped, "{name}: converged");
    }
}

fn l2_percent(a: &ResultsTable, reference: &ResultsTable) -> f64 {
    hirad::output::compare(a, reference).unwrap().error_percent
}

#[test]
fn cornell_box_against_the_exact_solver() {
    let scene = load("cornell_box.hir");
    let mut exact = ResultsTable::new(3, false);
    let settings = ExactSettings {
        max_elements: 1000,
        rays: 4,
        ..ExactSettings::default()
    };
    solve_exact_obvhs(&scene, &settings, &mut exact).unwrap();
    let mut errors = Vec::new();
    for eps in [1e-2f32, 1e-3] {
        let (t, _) = solve_with(
            &scene,
            &Settings {
                epsilon: eps,
                ..Settings::default()
            },
            Run::Obvhs(2),
            None,
        )
        .unwrap();
        errors.push(l2_percent(&t, &exact));
    }
    assert!(errors[1] < 2.0, "{errors:?}");
    assert!(
        errors[1] < errors[0],
        "the error falls with epsilon: {errors:?}"
    );
}

#[test]
fn the_budget_limits_refinement_and_is_reported() {
    let scene = load("cornell_box.hir");
    let bytes = hirad::scene::compile(&scene).unwrap();
    let view = read_image(&bytes).unwrap();
    let settings = Settings {
        epsilon: 1e-4,
        ..Settings::default()
    };
    let mut scratch = vec![0u8; hr::census_scratch_bytes(&view)];
    let plan = hr::plan(&view, &settings, false, &mut scratch).unwrap();
    // At the minimum the coarsest solution fits, refinement stops early and says so.
    let (t, stats) = solve_with(
        &scene,
        &settings,
        Run::Obvhs(1),
        Some(plan.min_bytes as usize),
    )
    .unwrap();
    assert!(stats.budget_limited);
    assert!(stats.peak_bytes <= plan.min_bytes);
    assert_eq!(t.len(), 17);
    assert!(t.radiosity(0, 0)[0] > 0.0, "the floor is still lit");
    // Below it: a clear error that names the bytes needed.
    let e = solve_with(
        &scene,
        &settings,
        Run::Obvhs(1),
        Some(plan.min_bytes as usize / 2),
    )
    .unwrap_err();
    assert_eq!(
        e,
        SolveError::Hr(HrError::WorkspaceTooSmall {
            needed: plan.min_bytes
        })
    );
    // Even a workspace too small for the census is an error, not a panic.
    let e = solve_with(&scene, &settings, Run::Obvhs(1), Some(3)).unwrap_err();
    assert!(matches!(
        e,
        SolveError::Hr(HrError::WorkspaceTooSmall { .. })
    ));
}

fn same_bits(a: &ResultsTable, b: &ResultsTable) -> bool {
    (0..a.len()).all(|row| {
        (0..1 + a.two_sided as usize).all(|side| {
            a.radiosity(row, side)
                .iter()
                .zip(b.radiosity(row, side))
                .all(|(p, q)| p.to_bits() == q.to_bits())
        })
    })
}

#[test]
fn bit_identical_for_any_thread_count() {
    for name in ["cornell_box.hir", "small_plant.hir"] {
        let settings = Settings::default();
        let (a, _) = solve(name, &settings, Run::Obvhs(1));
        for run in [Run::Obvhs(2), Run::Obvhs(3)] {
            assert!(
                same_bits(&a, &solve(name, &settings, run).0),
                "{name}: obvhs, more threads"
            );
        }
        let (c, _) = solve(name, &settings, Run::Core);
        assert!(
            same_bits(&c, &solve(name, &settings, Run::CoreThreads(2)).0),
            "{name}: core BVH, sequential vs 2 threads"
        );
        // The two ray casters differ only where a ray grazes an edge.
        assert!(
            l2_percent(&c, &a) < 0.05,
            "{name}: core BVH vs obvhs: {}",
            l2_percent(&c, &a)
        );
    }
}

#[test]
fn the_same_scene_in_millimetres_gives_the_same_radiosity() {
    let scene = load("cornell_box.hir");
    let mut mm = scene.clone();
    fn scale(c: &mut hirad::scene::Cluster) {
        for v in &mut c.vertices {
            *v *= 1000.0;
        }
        for child in &mut c.children {
            scale(child);
        }
    }
    scale(&mut mm.root);
    // The hierarchy alone: the same to 1e-3.
    let settings = Settings {
        final_rays: 0,
        ..Settings::default()
    };
    let (a, _) = solve_with(&scene, &settings, Run::Obvhs(2), None).unwrap();
    let (b, _) = solve_with(&mm, &settings, Run::Obvhs(2), None).unwrap();
    for row in 0..a.len() {
        for (x, y) in a.radiosity(row, 0).iter().zip(b.radiosity(row, 0)) {
            assert!(
                (x - y).abs() <= 1e-3 * x.abs().max(1e-3),
                "row {row}: {x} m vs {y} mm"
            );
        }
    }
    // With the final gather (a Monte Carlo estimate whose samples follow the hierarchy's
    // leaves, which rounding moves a little): the same within its noise, a few percent on
    // the dimmest faces at the default epsilon (625 rays per side), well under 1% of the
    // lamp's radiosity in L2.
    let settings = Settings::default();
    let (a, _) = solve_with(&scene, &settings, Run::Obvhs(2), None).unwrap();
    let (b, _) = solve_with(&mm, &settings, Run::Obvhs(2), None).unwrap();
    let (mut sq, mut area, mut top) = (0.0f64, 0.0f64, 0.0f32);
    for row in 0..a.len() {
        for (x, y) in a.radiosity(row, 0).iter().zip(b.radiosity(row, 0)) {
            sq += a.areas[row] as f64 * ((x - y) as f64).powi(2);
            top = top.max(*x);
        }
        area += a.areas[row] as f64;
    }
    let l2 = 100.0 * (sq / area).sqrt() / top as f64;
    assert!(
        l2 < 0.05,
        "final gather: m vs mm differ by {l2:.4}% (L2, of the lamp)"
    );
    for row in 0..a.len() {
        for (x, y) in a.radiosity(row, 0).iter().zip(b.radiosity(row, 0)) {
            assert!(
                (x - y).abs() <= 0.08 * x.abs().max(1e-3),
                "final gather, row {row}: {x} m vs {y} mm"
            );
        }
    }
}

#[test]
fn a_sunlit_leaf_transmits_and_reflects() {
    // A horizontal translucent leaf (front up) in the sun straight above, nothing else.
    let text = "hirad 1\nbands 2\nmaterial leaf rho 0.1 0.4 back_rho 0.1 0.4 tau 0.05 0.45\n\
                sun from 0 0 1 irradiance 500 300\nscene {\n  quad leaf 0 0 0  1 0 0  1 1 0  0 1 0\n}\n";
    let scene = hirad::text::parse(text.as_bytes()).unwrap();
    let (t, _) = solve_with(&scene, &Settings::default(), Run::Core, None).unwrap();
    let h = t.irradiance(0, 0);
    assert!(
        (h[0] - 500.0).abs() < 1e-3 && (h[1] - 300.0).abs() < 1e-3,
        "front irradiance {h:?}"
    );
    assert_eq!(t.irradiance(0, 1), [0.0, 0.0], "nothing reaches the back");
    let (front, back) = (t.radiosity(0, 0), t.radiosity(0, 1));
    assert!(
        (front[0] - 50.0).abs() < 1e-3 && (front[1] - 120.0).abs() < 1e-3,
        "{front:?}"
    );
    assert!(
        (back[0] - 25.0).abs() < 1e-3 && (back[1] - 135.0).abs() < 1e-3,
        "{back:?}"
    );
}

#[test]
fn a_scene_without_light_is_refused() {
    let text =
        "hirad 1\nbands 1\nmaterial m rho 0.5\nscene {\n  quad m 0 0 0  1 0 0  1 1 0  0 1 0\n}\n";
    let scene = hirad::text::parse(text.as_bytes()).unwrap();
    let e = solve_with(&scene, &Settings::default(), Run::Core, None).unwrap_err();
    assert_eq!(e, SolveError::Hr(HrError::NoLight));
}

#[test]
fn settings_out_of_range_are_refused() {
    let scene = load("parallel_squares.hir");
    for bad in [
        Settings {
            epsilon: 0.0,
            ..Settings::default()
        },
        Settings {
            epsilon: f32::NAN,
            ..Settings::default()
        },
        Settings {
            rays: 0,
            ..Settings::default()
        },
        Settings {
            max_children: 1,
            ..Settings::default()
        },
        Settings {
            max_children: 17,
            ..Settings::default()
        },
        Settings {
            final_rays: Settings::MAX_FINAL_RAYS + 1,
            ..Settings::default()
        },
        Settings {
            final_passes: 0,
            ..Settings::default()
        },
        Settings {
            final_passes: 5,
            ..Settings::default()
        },
        Settings {
            min_area: 1.0,
            ..Settings::default()
        },
        Settings {
            tolerance: -1.0,
            ..Settings::default()
        },
    ] {
        let bytes = hirad::scene::compile(&scene).unwrap();
        let view = read_image(&bytes).unwrap();
        let mut scratch = vec![0u8; hr::census_scratch_bytes(&view)];
        assert!(matches!(
            hr::plan(&view, &bad, true, &mut scratch),
            Err(HrError::Settings(_))
        ));
        let mut ws = vec![0u8; 1 << 20];
        let e = hr::solve(
            &view,
            &bad,
            &mut ws,
            None::<&ObvhsVisibility>,
            &mut Sequential,
            &mut NoProgress,
            &mut ResultsTable::new(1, false),
        );
        assert!(matches!(e, Err(SolveError::Hr(HrError::Settings(_)))));
    }
}
