//! What the hierarchical solver's shortcuts must not break (issue 8): few visibility rays,
//! solutions between refinement rounds taken to a looser tolerance, the power balance on a
//! fixed ray budget, and phases reported before their work so that their time is theirs.

use glam::Vec3;
use hirad::output::ResultsTable;
use hirad::scene::Scene;
use hirad_core::formfactor::point_polygon;
use hirad_core::hr::{NoProgress, Progress, Settings, Stats};

fn solve_with<P: Progress>(
    scene: &Scene,
    settings: &Settings,
    progress: &mut P,
) -> (ResultsTable, Stats) {
    hirad_tests::solve_hr(scene, settings, progress).unwrap()
}

fn solve(scene: &Scene, settings: &Settings) -> (ResultsTable, Stats) {
    solve_with(scene, settings, &mut NoProgress)
}

fn hierarchy_only(rays: u32) -> Settings {
    Settings {
        rays,
        final_rays: 0,
        ..Settings::default()
    }
}

fn assert_balanced(stats: &Stats, bands: usize, within: f64, what: &str) {
    for b in 0..bands {
        let e = stats.balance.relative_imbalance(b);
        assert!(
            e.abs() < within,
            "{what}: band {b} imbalance {:+.2}%",
            100.0 * e
        );
    }
    assert!(stats.converged, "{what}: did not converge");
    assert!(
        stats.remaining_change <= Settings::default().tolerance,
        "{what}: converged with {} still to come",
        stats.remaining_change
    );
}

/// A cluster is seen through a few sample points on its surfaces. When they all land where
/// the emitter cannot send light (behind a one-sided lamp), the link used to look dark and
/// was dropped, and everything in the cluster that faces the lamp lost its light (a room
/// sampled once on its ceiling, behind the ceiling lamp, lost 66% of the light). Here a
/// 0.1 m plate hangs 1 m over a lamp facing up, in one cluster with a 100 m floor half a
/// metre under the lamp: almost every sample of the cluster lands on the floor.
#[test]
fn a_cluster_seen_only_behind_its_emitter_still_gets_the_light_in_front() {
    let scene = hirad::text::parse(
        b"hirad 1\nbands 1\nmaterial lamp rho 0 emit 1\nmaterial grey rho 0.5\n\
          scene {\n\
            quad lamp -0.5 -0.5 0  0.5 -0.5 0  0.5 0.5 0  -0.5 0.5 0\n\
            cluster c {\n\
              quad grey -50 -50 -0.5  50 -50 -0.5  50 50 -0.5  -50 50 -0.5\n\
              quad grey -0.05 -0.05 1  -0.05 0.05 1  0.05 0.05 1  0.05 -0.05 1\n\
            }\n\
          }\n",
    )
    .unwrap();
    let lamp = [
        Vec3::new(-0.5, -0.5, 0.0),
        Vec3::new(0.5, -0.5, 0.0),
        Vec3::new(0.5, 0.5, 0.0),
        Vec3::new(-0.5, 0.5, 0.0),
    ];
    // The plate is small: the form factor at its centre is its mean within 0.1%.
    let want = point_polygon(Vec3::new(0.0, 0.0, 1.0), -Vec3::Z, &lamp) as f64;
    for rays in [1, 2, 4] {
        let (t, stats) = solve(&scene, &hierarchy_only(rays));
        let got = t.irradiance(2, 0)[0] as f64;
        assert!(
            (got / want - 1.0).abs() < 0.02,
            "rays {rays}: the plate gets {got} W/m^2, the lamp sends it {want}"
        );
        assert_balanced(&stats, 1, 0.01, &format!("rays {rays}"));
    }
}

/// The same on the Cornell box as 32 triangles: with one visibility ray per point the room
/// kept its light (66% of it was lost), and every face is close to what four rays give.
#[test]
fn the_cornell_box_keeps_its_light_with_one_ray_per_point() {
    let scene = hirad::files::load_scene(&hirad_tests::fixture("obj/cornell_triangles.obj"))
        .unwrap()
        .scene;
    let (four, stats) = solve(&scene, &hierarchy_only(4));
    assert_balanced(&stats, 3, 0.02, "rays 4");
    for rays in [1, 2] {
        let (t, stats) = solve(&scene, &hierarchy_only(rays));
        assert_balanced(&stats, 3, 0.02, &format!("rays {rays}"));
        // Area-weighted L2 over the walls (not the lamp, faces 10 and 11), in % of the
        // largest radiosity.
        let (mut num, mut den, mut top) = (0.0f64, 0.0f64, 0.0f64);
        for row in (0..t.len()).filter(|r| *r != 10 && *r != 11) {
            let a = t.areas[row] as f64;
            for (g, r) in t.radiosity(row, 0).iter().zip(four.radiosity(row, 0)) {
                num += a * (*g as f64 - *r as f64).powi(2);
                den += a;
                top = top.max(*r as f64);
            }
        }
        let l2 = 100.0 * (num / den).sqrt() / top;
        assert!(l2 < 1.0, "rays {rays}: {l2:.3}% from four rays");
    }
}

/// Every phase is announced before its work (so that a caller timing phases by their
/// reports, as the runner's stats do, charges the work to it): the first report of each
/// counted phase says nothing is done yet. (The power balance's rays were once all charged
/// to "solving", and the first iteration of each solution to the phase before.)
#[test]
fn phases_are_announced_before_their_work() {
    struct Log(Vec<(String, u64)>);
    impl Progress for Log {
        fn report(&mut self, what: &str, done: u64, _: u64) {
            self.0.push((what.to_string(), done));
        }
    }
    let scene = hirad::files::load_scene(&hirad_tests::fixture("obj/cornell_triangles.obj"))
        .unwrap()
        .scene;
    let mut log = Log(Vec::new());
    let (_, stats) = solve_with(&scene, &Settings::default(), &mut log);
    // Every ray counted is charged to one phase, and each phase cast some.
    let r = stats.rays_by_phase;
    assert_eq!(r.lighting + r.links + r.final_gather, stats.rays, "{r:?}");
    assert!(r.lighting > 0 && r.links > 0 && r.final_gather > 0, "{r:?}");
    for phase in [
        "lighting patches",
        "evaluating links",
        "solving (iterations)",
        "power balance (patches)",
        "final gather: relighting patches (patches)",
        "final gather: polygons and output (polygons)",
    ] {
        let first = log.0.iter().find(|(w, _)| w == phase);
        assert_eq!(
            first.map(|f| f.1),
            Some(0),
            "{phase}: first report {first:?} in {:?}",
            log.0.iter().map(|l| l.0.as_str()).collect::<Vec<_>>()
        );
    }
}
