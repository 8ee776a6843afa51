//! Direct light of suns and sky on soil under random canopies, against the exact answer
//! computed by projection, apart from every ray caster (`hirad_tests::canopy`): a soil point
//! is lit from a direction iff it misses the shadow of every leaf, the leaf's corners
//! projected along that direction onto the soil. Black leaves and soil, so the soil's
//! irradiance is its direct light alone. Swept over leaf sizes (5 cm to 0.5 m), leaf area
//! index (leaf counts from 1,400 to 29,000), sun zenith (0 to 70 degrees) and azimuth.

use hirad_core::hr::{NoProgress, Settings};
use hirad_tests::canopy::{RandomCanopy, direction, soil_reference};

/// Solves the canopy at the default settings; returns the central soil quads' mean error
/// (relative) and rms error (relative to the reference mean), and the worst quad's relative
/// error.
fn soil_error(c: &RandomCanopy) -> (f64, f64, f64) {
    let scene = hirad::text::parse(c.text().as_bytes()).unwrap();
    let (hr, stats) = hirad_tests::solve_hr(&scene, &Settings::default(), &mut NoProgress).unwrap();
    assert!(stats.converged);
    let want = soil_reference(c, 256);
    let side = c.soil_side();
    let (mut got_sum, mut want_sum, mut sq, mut worst) = (0.0, 0.0, 0.0, 0.0f64);
    for (k, &(i, j)) in c.central().iter().enumerate() {
        let g = hr.irradiance(j * side + i, 0)[0] as f64;
        got_sum += g;
        want_sum += want[k];
        sq += (g - want[k]).powi(2);
        worst = worst.max((g / want[k] - 1.0).abs());
    }
    let n = want.len() as f64;
    assert!(n >= 4.0, "too few central quads: {n}");
    (
        got_sum / want_sum - 1.0,
        (sq / n).sqrt() / (want_sum / n),
        worst,
    )
}

#[test]
fn sunlight_under_random_canopies_matches_the_projected_shadows() {
    // (leaf side m, LAI, half width m, sun zenith, azimuth, seed)
    let cases: [(f64, f64, f64, f64, f64, u32); 6] = [
        (0.05, 2.0, 3.0, 0.0, 0.0, 1),
        (0.07, 2.0, 3.5, 45.0, 200.0, 2),
        (0.1, 2.0, 4.0, 60.0, 40.0, 3),
        (0.15, 3.0, 4.0, 30.0, 100.0, 4),
        (0.2, 2.0, 4.5, 55.0, 300.0, 5),
        (0.3, 1.0, 4.0, 15.0, 250.0, 6),
    ];
    let mut failed = Vec::new();
    for (leaf, lai, half, zen, az, seed) in cases {
        let mut c = RandomCanopy::new(leaf, half, zen, az, seed);
        c.lai = lai;
        let (mean, rms, worst) = soil_error(&c);
        let line = format!(
            "leaves {} of {leaf} m (LAI {lai}), sun at {zen} deg: mean {:+.2}%, rms {:.2}%, worst quad {:.1}%",
            c.leaf_count(),
            100.0 * mean,
            100.0 * rms,
            100.0 * worst
        );
        eprintln!("{line}");
        if mean.abs() > 0.01 || rms > 0.05 {
            failed.push(line);
        }
    }
    assert!(failed.is_empty(), "{failed:#?}");
}

#[test]
fn leaves_as_large_as_the_soil_quads_cast_unbiased_shadows() {
    // 0.5 m leaves over 0.5 m soil quads: every quad is crossed by shadow edges of leaves
    // as large as itself, sampled on a grid sized by the scene's typical polygon (the quads
    // themselves), so the per-quad noise is larger; the mean holds.
    let c = RandomCanopy::new(0.5, 5.0, 40.0, 10.0, 7);
    let (mean, rms, worst) = soil_error(&c);
    eprintln!(
        "0.5 m leaves: mean {:+.2}%, rms {:.2}%, worst {:.1}%",
        100.0 * mean,
        100.0 * rms,
        100.0 * worst
    );
    assert!(
        mean.abs() < 0.01 && rms < 0.08,
        "mean {:+.2}%, rms {:.2}%",
        100.0 * mean,
        100.0 * rms
    );
}

#[test]
fn low_sun_under_a_random_canopy_is_unbiased() {
    // At 70 degrees a canopy of LAI 2 lets through about 5% of the sun: the per-quad noise
    // is relative to that (up to 8% rms); over 49 quads the mean stays within 1.5%.
    let c = RandomCanopy::new(0.12, 7.0, 70.0, 130.0, 8);
    let (mean, rms, worst) = soil_error(&c);
    eprintln!(
        "sun at 70 deg: mean {:+.2}%, rms {:.2}%, worst {:.1}%",
        100.0 * mean,
        100.0 * rms,
        100.0 * worst
    );
    assert!(
        mean.abs() < 0.01 && rms < 0.08,
        "mean {:+.2}%, rms {:.2}%",
        100.0 * mean,
        100.0 * rms
    );
}

#[test]
fn sky_light_under_random_canopies_matches_the_projected_shadows() {
    // Sky only: 18 directions on three rings (10, 40 and 70 degrees from the zenith). Each
    // sample of a side tests one direction, so the per-quad noise is a Monte Carlo one
    // (see `direct::sky_samples`); the mean must hold.
    let mut failed = Vec::new();
    for (leaf, half, seed) in [(0.06, 4.5, 11), (0.12, 5.0, 12), (0.25, 6.0, 13)] {
        let mut c = RandomCanopy::new(leaf, half, 0.0, 0.0, seed);
        c.sources.clear();
        c.suns = 0;
        for r in 0..3 {
            for a in 0..6 {
                let d = direction(10.0 + 30.0 * r as f64, 60.0 * a as f64 + 17.0 * r as f64);
                c.sources.push((d, 100.0));
            }
        }
        let (mean, rms, worst) = soil_error(&c);
        let line = format!(
            "sky, leaves of {leaf} m: mean {:+.2}%, rms {:.2}%, worst quad {:.1}%",
            100.0 * mean,
            100.0 * rms,
            100.0 * worst
        );
        eprintln!("{line}");
        if mean.abs() > 0.015 || rms > 0.08 {
            failed.push(line);
        }
    }
    assert!(failed.is_empty(), "{failed:#?}");
}
