//! Light kept as a canopy grows (issue 15): `gen canopy` at growing sizes, the hierarchy
//! alone (no final gather), power balance in every band. Before links gathered from clusters
//! carried the radiosity of the polygons their samples met (their witnesses), the canopy
//! made more light the larger it grew (NIR: 3 x 12 +1.0%, 6 x 10 +0.9%, 20 x 30 -4.1%, the
//! default -6.5%): a cluster's coefficient times the mean radiosity of its polygons facing
//! the receiver, where what a receiver sees of a canopy (soil below: the dark lower leaves)
//! is not that mean.

use hirad::generate::canopy;
use hirad::output::Progress;
use hirad::scene::Scene;
use hirad::solve::{HrRun, VisibilityChoice, solve_hr};
use hirad_core::hr::Settings;
use hirad_core::sink::{PolygonResult, Sink};

fn canopy_scene(rows: u32, plants: u32) -> Scene {
    let (r, p) = (rows.to_string(), plants.to_string());
    let words = ["-o", "unused.hirb", "--rows", &r, "--plants-per-row", &p];
    canopy::generate(&canopy::Args::from_words(words.to_vec()).unwrap()).unwrap()
}

/// Takes the polygons and keeps nothing.
struct Discard;

impl Sink for Discard {
    type Error = anyhow::Error;
    fn polygon(&mut self, _: &PolygonResult<'_>) -> Result<(), Self::Error> {
        Ok(())
    }
}

/// Solves `scene` at the defaults with `final_rays` and `final_passes` (2 threads, obvhs).
fn solve(scene: &Scene, final_rays: u32, final_passes: u32) -> HrRun {
    let settings = Settings {
        final_rays,
        final_passes,
        ..Settings::default()
    };
    solve_hr(
        scene,
        &settings,
        2,
        None,
        VisibilityChoice::Obvhs,
        &Progress::new(true),
        &mut Discard,
    )
    .unwrap()
}

#[test]
fn a_growing_canopy_keeps_its_light_with_the_hierarchy_alone() {
    // Every size within 2% in every band (the acceptance bound of issue 15 for the hierarchy
    // alone), and the largest canopy's NIR imbalance no larger than the smallest's plus half
    // a point. Measured: NIR +1.27% (3 x 12), +1.44% (6 x 10), -0.03% (20 x 30); 12 x 25
    // +1.26%, the default canopy -1.28% (too slow here); PAR within 0.1%. Before: +1.01%,
    // +0.95%, -4.13%; -0.85%, -6.54%.
    let mut nir = Vec::new();
    for (rows, plants) in [(3, 12), (6, 10), (20, 30)] {
        let scene = canopy_scene(rows, plants);
        let run = solve(&scene, 0, Settings::default().final_passes);
        assert!(run.stats.converged, "{rows} x {plants}: not converged");
        let bands = scene.bands as usize;
        let e: Vec<f64> = (0..bands)
            .map(|b| run.stats.balance.relative_imbalance(b))
            .collect();
        eprintln!(
            "{rows} x {plants}: imbalance {}",
            e.iter()
                .map(|v| format!("{:+.2}%", 100.0 * v))
                .collect::<Vec<_>>()
                .join(" ")
        );
        for (b, v) in e.iter().enumerate() {
            assert!(
                v.abs() < 0.02,
                "{rows} x {plants}, band {b}: imbalance {:+.2}%",
                100.0 * v
            );
        }
        nir.push(e[bands - 1]);
    }
    let (first, last) = (nir[0], nir[nir.len() - 1]);
    assert!(
        last.abs() <= first.abs() + 0.005,
        "the imbalance grew with the canopy: {:+.2}% to {:+.2}%",
        100.0 * first,
        100.0 * last
    );
}

#[test]
fn the_gathers_first_correction_settles_a_canopy() {
    // The first relighting pass hands what it changed to the links, which carry it to all
    // it lights: one pass brings the light of a 6 x 10 canopy to its balance, where passes
    // that only re-gather (each a Jacobi step) moved 0.3 to 0.4% apiece and left NIR +0.41%
    // after one, +0.15% after three. Measured: +0.06% after one (moves 1.19%, then 0.09%);
    // automatic: 3 passes, the polygons' own included.
    let scene = canopy_scene(6, 10);
    let bands = scene.bands as usize;
    for (passes, what) in [(2, "one relighting pass"), (Settings::AUTO, "automatic")] {
        let run = solve(&scene, Settings::AUTO, passes);
        let nir = run.stats.balance.relative_imbalance(bands - 1);
        eprintln!(
            "{what}: {} passes, NIR {:+.3}%, last move {:.2}%",
            run.stats.final_passes,
            100.0 * nir,
            100.0 * run.stats.final_change
        );
        assert!(run.stats.converged, "{what}: not converged");
        assert!(
            nir.abs() < 0.002,
            "{what}: NIR imbalance {:+.3}%",
            100.0 * nir
        );
        assert!(run.stats.final_passes <= 3, "{what}: {:?}", run.stats);
    }
}
