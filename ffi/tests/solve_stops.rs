//! How a solve through the C functions ends early or not right: progress cancels at every
//! point (hr and hi) leaving a prefix handed over, a failing sink stops it with its code, and
//! a solve that does not converge or balance hands everything over and says NOT_RIGHT.

mod common;

use common::*;
use hirad_ffi::*;

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
