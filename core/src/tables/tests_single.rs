//! The polygons' first scattering kept apart: closed forms for a leaf seen whole, the
//! interpolation of a visible fraction that changes with direction, the sides (reflected
//! towards the side lit, transmitted towards the other) and the checks of its storage.

use super::grid::DirectionGrid;
use super::phase::TableError;
use super::single::{SingleScatter, VISIBLE_ONE, shape_stride};
use glam::Vec3;

extern crate std;
use std::vec;
use std::vec::Vec;

/// One leaf of `area` facing `normal`, two bands: front reflectance, back reflectance and
/// transmittance per band.
fn leaf(normal: Vec3, area: f32, m: [[f32; 3]; 2]) -> Vec<f32> {
    let mut s = vec![normal.x, normal.y, normal.z, area];
    for b in m {
        s.extend_from_slice(&b);
    }
    s
}

/// Directions spread over the sphere (a Fibonacci lattice), none on a grid's creases.
fn spread(n: u32) -> impl Iterator<Item = Vec3> {
    (0..n).map(move |i| {
        let z = 1.0 - (2.0 * i as f32 + 1.0) / n as f32;
        let r = libm::sqrtf((1.0 - z * z).max(0.0));
        let phi = i as f32 * 2.399_963;
        Vec3::new(r * libm::cosf(phi), r * libm::sinf(phi), z)
    })
}

#[test]
fn a_leaf_seen_whole_sends_its_closed_form() {
    let grid = DirectionGrid::new(8).unwrap();
    let m = [[0.3, 0.2, 0.1], [0.45, 0.4, 0.35]];
    for (normal, area) in [
        (Vec3::Z, 2.0),
        (Vec3::new(0.6, 0.0, 0.8), 0.5),
        (Vec3::new(-0.36, 0.48, -0.8), 0.01),
    ] {
        let shape = leaf(normal, area, m);
        let visible = vec![VISIBLE_ONE; grid.cells() as usize];
        let s = SingleScatter::new(grid, 2, 1, &shape, &visible).unwrap();
        for d in spread(40) {
            for o in spread(37) {
                let (cd, co) = (normal.dot(d), normal.dot(o));
                for (b, [rf, rb, t]) in m.iter().copied().enumerate() {
                    let k = if cd > 0.0 && co > 0.0 {
                        rf
                    } else if cd < 0.0 && co < 0.0 {
                        rb
                    } else {
                        t
                    };
                    let want = area * (cd * co).abs() * k / core::f32::consts::PI;
                    let got = s.intensity(d, o, b);
                    assert!(
                        (got - want).abs() <= 1e-5 * want.max(1e-3),
                        "{normal} {d} {o} band {b}: {got} vs {want}"
                    );
                }
            }
        }
    }
}

#[test]
fn visible_fractions_are_interpolated_per_polygon() {
    // Two leaves facing up and down, each seen from a share of the directions that changes
    // smoothly: V_0(d) = (1 + d.x) / 2, V_1(d) = (1 - d.y) / 2. The interpolated product
    // converges on the closed form as the grid is refined (errors relative to 0.3 m^2/sr,
    // about the largest intensity).
    let m = [[0.5, 0.4, 0.1], [0.5, 0.4, 0.1]];
    let mut shape = leaf(Vec3::Z, 1.0, m);
    shape.extend(leaf(-Vec3::Z, 2.0, m));
    let v0 = |d: Vec3| (1.0 + d.x) / 2.0;
    let v1 = |d: Vec3| (1.0 - d.y) / 2.0;
    let mut last = f32::INFINITY;
    for side in [8u32, 16, 32, 64] {
        let grid = DirectionGrid::new(side).unwrap();
        let mut visible = Vec::new();
        for c in 0..grid.cells() {
            let d = grid.direction(c);
            for f in [v0(d), v1(d)] {
                visible.push(libm::roundf(f * VISIBLE_ONE as f32) as u8);
            }
        }
        let s = SingleScatter::new(grid, 2, 2, &shape, &visible).unwrap();
        let mut worst = 0.0f32;
        for d in spread(30) {
            for o in spread(31) {
                let mut want = 0.0;
                for (n, a, v) in [
                    (Vec3::Z, 1.0, &v0 as &dyn Fn(Vec3) -> f32),
                    (-Vec3::Z, 2.0, &v1),
                ] {
                    let (cd, co) = (n.dot(d), n.dot(o));
                    let k = if (cd > 0.0) == (co > 0.0) {
                        if cd > 0.0 { 0.5 } else { 0.4 }
                    } else {
                        0.1
                    };
                    want += a * (cd * co).abs() * k * v(d) * v(o) / core::f32::consts::PI;
                }
                worst = worst.max((s.intensity(d, o, 0) - want).abs() / 0.3);
            }
        }
        // Second order until the fractions' 1/255 steps are what is left.
        if side <= 32 {
            assert!(worst < 0.6 * last, "side {side}: {worst} after {last}");
        }
        last = worst;
    }
    assert!(last < 0.003, "{last}");
}

#[test]
fn storage_is_checked() {
    let grid = DirectionGrid::new(4).unwrap();
    let m = [[0.3, 0.2, 0.1], [0.45, 0.4, 0.35]];
    let shape = leaf(Vec3::Z, 1.0, m);
    let visible = vec![0u8; 16];
    assert!(SingleScatter::new(grid, 2, 1, &shape, &visible).is_ok());
    assert_eq!(
        SingleScatter::new(grid, 2, 1, &shape, &visible[..15]),
        Err(TableError::Length {
            expected: 16,
            given: 15
        })
    );
    assert_eq!(
        SingleScatter::new(grid, 2, 1, &shape[..9], &visible),
        Err(TableError::Length {
            expected: shape_stride(2) as u64,
            given: 9
        })
    );
    assert_eq!(
        SingleScatter::new(grid, 0, 1, &shape, &visible),
        Err(TableError::Bands)
    );
    // (value changed, to what, index reported): a normal off unit length is reported at
    // its first component.
    for (k, bad, want) in [
        (0usize, 0.5f32, 0u64),
        (2, f32::NAN, 2),
        (3, -1.0, 3),
        (4, 1.5, 4),
        (9, -0.1, 9),
    ] {
        let mut s = shape.clone();
        s[k] = bad;
        assert_eq!(
            SingleScatter::new(grid, 2, 1, &s, &visible),
            Err(TableError::Value { index: want }),
            "value {k} = {bad}"
        );
    }
}
