//! A `tau` table baked to an error target: finer where the leaves make tau vary, and its
//! interpolation at directions off the grid within the target of the exact projection.

use super::bake::{BakeError, TauSettings, bake_tau_to_target};
use super::tau::interpolate_tau;
use super::tests_tau::{ball, projection, unit};
use glam::Vec3;

extern crate std;
use std::vec;

#[test]
fn a_table_meets_its_target_at_directions_off_the_grid() {
    let (leaves, lo, hi) = ball(60, 1.0, 0.4, Vec3::ZERO, 21);
    let settings = TauSettings {
        rays: 64,
        target: 0.04,
        checks: 64,
        seed: 5,
    };
    let mut out = vec![0.0f32; 64 * 64];
    let table = bake_tau_to_target(&leaves, lo, hi, 2, &settings, &mut out).unwrap();
    assert!(table.met, "{table:?}");
    assert!(
        table.grid.side() > 2,
        "a ball of leaves is not one value: {table:?}"
    );
    let values = &out[..table.grid.cells() as usize];
    for k in 0..20 {
        let d = unit(k, 77);
        let (want, _) = projection(&leaves, lo, hi, d, 400);
        let got = interpolate_tau(&table.grid, values, lo, hi, d);
        // The target, plus the noise of the check estimates (64 x 64 rays: about 0.008).
        assert!(
            (got - want).abs() < 0.06,
            "{d}: table {got}, projection {want}, {table:?}"
        );
    }
}

#[test]
fn an_empty_box_needs_one_cell_and_bad_settings_are_refused() {
    let (leaves, lo, hi) = ball(0, 1.0, 0.4, Vec3::ZERO, 1);
    let (lo, hi) = if leaves.0.is_empty() {
        (Vec3::splat(-1.0), Vec3::splat(1.0))
    } else {
        (lo, hi)
    };
    let mut out = vec![0.0f32; 16];
    let table = bake_tau_to_target(&leaves, lo, hi, 1, &TauSettings::default(), &mut out).unwrap();
    assert!(
        table.met && table.grid.side() == 1 && out[0] == 1.0,
        "{table:?}"
    );
    let bad = TauSettings {
        rays: 0,
        ..TauSettings::default()
    };
    assert_eq!(
        bake_tau_to_target(&leaves, lo, hi, 1, &bad, &mut out),
        Err(BakeError::Settings)
    );
    assert_eq!(
        bake_tau_to_target(&leaves, lo, hi, 8, &TauSettings::default(), &mut out),
        Err(BakeError::Storage { needed: 64 })
    );
}

#[test]
fn a_table_that_cannot_meet_its_target_says_so() {
    let (leaves, lo, hi) = ball(60, 1.0, 0.4, Vec3::ZERO, 21);
    let settings = TauSettings {
        rays: 32,
        target: 1e-4,
        checks: 4,
        seed: 2,
    };
    let mut out = vec![0.0f32; 16];
    let table = bake_tau_to_target(&leaves, lo, hi, 2, &settings, &mut out).unwrap();
    assert!(
        !table.met && table.grid.side() == 4 && table.error > 1e-4,
        "{table:?}"
    );
}

#[test]
fn opposite_directions_share_one_estimate() {
    use super::bake::bake_tau;
    use super::grid::DirectionGrid;
    let (leaves, lo, hi) = ball(40, 1.0, 0.4, Vec3::ZERO, 3);
    let grid = DirectionGrid::new(6).unwrap();
    let settings = TauSettings {
        rays: 16,
        ..TauSettings::default()
    };
    let mut out = vec![0.0f32; 36];
    let rays = bake_tau(&leaves, lo, hi, grid, &settings, &mut out);
    for c in 0..36 {
        assert_eq!(
            out[c as usize],
            out[grid.cell_of(-grid.direction(c)) as usize]
        );
    }
    // Half the cells estimated, each with at most 16 x 16 rays.
    assert!(rays <= 18 * 256, "{rays} rays");
}
