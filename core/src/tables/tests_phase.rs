//! The light leaving a box: a polygon's visible fraction against the analytic shadow of a
//! blocker, the sum over surfaces against rays from an observer (two estimators that share
//! only the leaves' segment test), and the tables put together: their checks, and the
//! uniform form sending out exactly what is scattered.

use super::directional::DirectionalTables;
use super::grid::DirectionGrid;
use super::outgoing::{outgoing, visible_fraction};
use super::phase::{PhaseTable, TableError};
use super::tests_tau::{Leaves, ball, unit};
use crate::limits::MAX_BANDS;
use glam::Vec3;

extern crate std;
use std::vec;
use std::vec::Vec;

/// A unit square at z = 0 under a blocker over its half x < 0.5 at z = 1.
fn shaded_square() -> Leaves {
    Leaves(vec![
        [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ],
        [
            Vec3::new(-5.0, -5.0, 1.0),
            Vec3::new(0.5, -5.0, 1.0),
            Vec3::new(0.5, 5.0, 1.0),
            Vec3::new(-5.0, 5.0, 1.0),
        ],
    ])
}

#[test]
fn the_visible_fraction_follows_the_blockers_shadow() {
    let leaves = shaded_square();
    for k in [4u32, 8, 16] {
        for step in 0..10 {
            // Towards (sin t, 0, cos t): a point at x is blocked when x + tan t < 0.5.
            let t = step as f32 * 0.05;
            let d = Vec3::new(libm::sinf(t), 0.0, libm::cosf(t));
            let want = (0.5 + libm::tanf(t)).min(1.0);
            let got = visible_fraction(&leaves, &leaves.0[0], 0, d, 20.0, k, 3);
            assert!(
                (got - want).abs() <= 1.0 / k as f32 + 1e-6,
                "k {k}, angle {t}: {got} vs {want}"
            );
            // The blocker sees the sky whole, and nothing is seen from below its back.
            assert_eq!(
                visible_fraction(&leaves, &leaves.0[1], 1, d, 20.0, k, 3),
                1.0
            );
        }
    }
}

/// A radiance per leaf and side that varies from leaf to leaf (W/m^2/sr).
fn radiance(leaf: u32, front: bool) -> f32 {
    (1 + leaf % 7) as f32 * if front { 1.0 } else { 0.3 }
}

fn normal(q: &[Vec3; 4]) -> Vec3 {
    (q[1] - q[0]).cross(q[2] - q[0]).normalize()
}

#[test]
fn the_surfaces_sum_agrees_with_an_observers_rays() {
    for (count, radius, size, seed) in [
        (40u32, 1.0f32, 0.3f32, 2u32),
        (120, 2.0, 0.25, 7),
        (15, 0.2, 0.1, 9),
    ] {
        let (leaves, lo, hi) = ball(count, radius, size, Vec3::new(0.3, -1.0, 2.0), seed);
        let reach = 4.0 * (hi - lo).length();
        for k in 0..6 {
            let towards = unit(k, seed + 40);
            let by_rays = outgoing(
                &leaves,
                [lo, hi],
                towards,
                400,
                5,
                1,
                |poly, t, l: &mut [f32; MAX_BANDS]| {
                    let n = normal(&leaves.0[poly as usize]);
                    l[0] = radiance(poly, n.dot(t) > 0.0);
                },
            );
            let mut by_sum = 0.0f32;
            for (i, q) in leaves.0.iter().enumerate() {
                let n = normal(q);
                let area = (q[1] - q[0]).cross(q[3] - q[0]).length();
                let cos = n.dot(towards);
                let v = visible_fraction(&leaves, q, i as u32, towards, reach, 12, 11);
                by_sum += radiance(i as u32, cos > 0.0) * area * cos.abs() * v;
            }
            let rel = (by_rays.intensity[0] - by_sum).abs() / by_sum;
            assert!(
                rel < 0.03,
                "{count} leaves, direction {k}: rays {} vs sum {by_sum}",
                by_rays.intensity[0]
            );
        }
    }
}

#[test]
fn tables_refuse_storage_that_does_not_fit() {
    let g = DirectionGrid::new(2).unwrap();
    // Two bands, two sides lit: 4 cells x 2 x 2 albedos, 4 x 4 x 2 x 2 responses.
    let ok = vec![0.25f32; 4 * 2 * 2];
    let bi = vec![0.1f32; 4 * 4 * 2 * 2];
    let shares = vec![0.5f32; 4 * 2 * 2];
    assert!(PhaseTable::new(g, g, 2, &shares, &bi).is_ok());
    assert_eq!(
        PhaseTable::new(g, g, 0, &shares, &bi),
        Err(TableError::Bands)
    );
    assert_eq!(
        PhaseTable::new(g, g, 9, &shares, &bi),
        Err(TableError::Bands)
    );
    assert_eq!(
        PhaseTable::new(g, g, 2, &shares, &bi[..63]),
        Err(TableError::Length {
            expected: 64,
            given: 63
        })
    );
    let mut neg = bi.clone();
    neg[31] = -1.0;
    assert_eq!(
        PhaseTable::new(g, g, 2, &shares, &neg),
        Err(TableError::Value { index: 31 })
    );
    neg[31] = f32::INFINITY;
    assert_eq!(
        PhaseTable::new(g, g, 2, &shares, &neg),
        Err(TableError::Value { index: 31 })
    );
    // The shares by side lit: one value per incoming cell, side and band, each a fraction.
    assert_eq!(
        PhaseTable::new(g, g, 2, &shares[..15], &bi),
        Err(TableError::Length {
            expected: 16,
            given: 15
        })
    );
    let mut bad = shares.clone();
    bad[3] = 1.5;
    assert_eq!(
        PhaseTable::new(g, g, 2, &bad, &bi),
        Err(TableError::Value { index: 3 })
    );
    let phase = PhaseTable::new(g, g, 2, &shares, &bi).unwrap();
    let tau = vec![0.5f32; 4];
    let new = |lo, hi, tau: &[f32], albedo: &[f32]| {
        DirectionalTables::new(lo, hi, g, tau, albedo, phase).map(|_| ())
    };
    assert_eq!(new(Vec3::ZERO, Vec3::ONE, &tau, &ok), Ok(()));
    assert_eq!(new(Vec3::ONE, Vec3::ZERO, &tau, &ok), Err(TableError::Box));
    assert_eq!(
        new(Vec3::ZERO, Vec3::splat(f32::INFINITY), &tau, &ok),
        Err(TableError::Box)
    );
    assert_eq!(
        new(Vec3::ZERO, Vec3::ONE, &[0.5, 0.5, 2.0, 0.5], &ok),
        Err(TableError::Value { index: 2 })
    );
    // The albedo lives on the tau grid, a value per cell and band, each a fraction.
    assert_eq!(
        new(Vec3::ZERO, Vec3::ONE, &tau, &ok[..15]),
        Err(TableError::Length {
            expected: 16,
            given: 15
        })
    );
    let mut bad = ok.clone();
    bad[5] = f32::NAN;
    assert_eq!(
        new(Vec3::ZERO, Vec3::ONE, &tau, &bad),
        Err(TableError::Value { index: 5 })
    );
    bad[5] = 1.5;
    assert_eq!(
        new(Vec3::ZERO, Vec3::ONE, &tau, &bad),
        Err(TableError::Value { index: 5 })
    );
}

#[test]
fn the_uniform_form_sends_out_what_is_scattered() {
    // Tables of a made-up original: tau and albedo varying with direction.
    let (lo, hi) = (Vec3::new(-1.0, -0.5, 0.0), Vec3::new(1.0, 0.5, 3.0));
    let g = DirectionGrid::new(16).unwrap();
    let tau: Vec<f32> = (0..g.cells())
        .map(|c| 0.3 + 0.4 * g.direction(c).z.abs())
        .collect();
    // Fronts scatter more when lit from +z, backs from -z.
    let albedo: Vec<f32> = (0..g.cells())
        .flat_map(|c| {
            let d = g.direction(c);
            [0.1 + 0.05 * d.x + 0.05 * d.z, 0.1 - 0.05 * d.z]
        })
        .collect();
    let out = DirectionGrid::new(4).unwrap();
    let response = vec![0.05f32; (g.cells() * out.cells() * 2) as usize];
    let shares = vec![0.5f32; (g.cells() * 2) as usize];
    let phase = PhaseTable::new(g, out, 1, &shares, &response).unwrap();
    let t = DirectionalTables::new(lo, hi, g, &tau, &albedo, phase).unwrap();
    for k in 0..5 {
        let source = unit(k, 71);
        // The intensity of the uniform form summed over the sphere, on a grid of its own.
        let fine = DirectionGrid::new(64).unwrap();
        let total: f32 = (0..fine.cells())
            .map(|c| t.uniform_intensity(source, fine.direction(c), 0))
            .sum::<f32>()
            * fine.solid_angle();
        let want = t.scattered(source, 0);
        assert!((total - want).abs() < 0.01 * want, "{total} vs {want}");
        // Scattered power is the albedo times the shadow, the albedo within the range of
        // the cells around; the bidirectional intensity is the response times the
        // scattered power and the shadow seen.
        let shadow = (1.0 - t.tau(source)) * t.area(source);
        assert!((t.shadow(source) - shadow).abs() < 1e-5);
        assert!((want - t.albedo(source, 0) * shadow).abs() < 1e-5);
        let near: Vec<f32> = g
            .weights(source)
            .iter()
            .map(|&(c, _)| albedo[2 * c as usize] + albedo[2 * c as usize + 1])
            .collect();
        let (lo_a, hi_a) = near
            .iter()
            .fold((1.0f32, 0.0f32), |(a, b), &x| (a.min(x), b.max(x)));
        let a = t.albedo(source, 0);
        assert!(
            a >= lo_a - 0.02 && a <= hi_a + 0.02,
            "{a} outside {lo_a}..{hi_a}"
        );
        let observer = unit(k, 72);
        let i = t.intensity(source, observer, 0);
        assert!((i - 0.05 * want * t.shadow(observer)).abs() < 1e-5 * (1.0 + i));
    }
}

#[test]
fn a_sides_response_is_interpolated_over_the_cells_where_that_side_is_lit() {
    // Fronts lit from the upper hemisphere only: there their response is 0.3 (0 below, where
    // it is undefined); backs the other way round, response 0.1.
    let g = DirectionGrid::new(8).unwrap();
    let out = DirectionGrid::new(4).unwrap();
    let mut shares = Vec::new();
    let mut response = vec![0.0f32; (g.cells() * out.cells() * 2) as usize];
    for c in 0..g.cells() {
        let up = g.direction(c).z > 0.0;
        shares.extend(if up { [1.0, 0.0] } else { [0.0, 1.0] });
        for o in 0..out.cells() {
            let at = ((c * out.cells() + o) * 2) as usize;
            if up {
                response[at] = 0.3;
            } else {
                response[at + 1] = 0.1;
            }
        }
    }
    let phase = PhaseTable::new(g, out, 1, &shares, &response).unwrap();
    for k in 0..200 {
        let source = unit(k, 91);
        let observer = unit(k, 92);
        // Near the equator the cells around mix both hemispheres; a side's response stays
        // its own wherever one of them has it lit.
        let lit_up = g
            .weights(source)
            .iter()
            .any(|&(c, w)| w > 0.0 && g.direction(c).z > 0.0);
        let lit_down = g
            .weights(source)
            .iter()
            .any(|&(c, w)| w > 0.0 && g.direction(c).z <= 0.0);
        let front = phase.response(source, observer, 0, 0);
        let back = phase.response(source, observer, 1, 0);
        let want = |lit: bool, r: f32| if lit { r } else { 0.0 };
        assert!(
            (front - want(lit_up, 0.3)).abs() < 1e-6,
            "{source}: {front}"
        );
        assert!(
            (back - want(lit_down, 0.1)).abs() < 1e-6,
            "{source}: {back}"
        );
    }
}
