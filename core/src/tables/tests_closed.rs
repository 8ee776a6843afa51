//! A closed instance's received light: the sum it keeps against the tables' intensity beam
//! by beam, a leaf's energy against its closed form, the transform, and the box a ray
//! crosses.

use super::closed::{Placed, Received};
use super::directional::DirectionalTables;
use super::grid::DirectionGrid;
use super::phase::{PhaseTable, TableError};
use super::single::{SingleScatter, VISIBLE_ONE, shape_stride};
use crate::geometry::Similarity;
use core::f32::consts::PI;
use glam::{Quat, Vec3};

extern crate std;
use std::vec;
use std::vec::Vec;

/// Directions spread over the sphere (a Fibonacci lattice).
fn spread(n: u32, twist: f32) -> impl Iterator<Item = Vec3> {
    (0..n).map(move |i| {
        let z = 1.0 - (2.0 * i as f32 + 1.0) / n as f32;
        let r = libm::sqrtf((1.0 - z * z).max(0.0));
        let phi = i as f32 * 2.399_963 + twist;
        Vec3::new(r * libm::cosf(phi), r * libm::sinf(phi), z)
    })
}

/// A deterministic value in [0, 1) from two integers.
fn noise(a: u32, b: u32) -> f32 {
    let h = crate::sampling::hash3(a, b, 0x5eed);
    (h >> 8) as f32 / (1u32 << 24) as f32
}

/// Storage of synthetic tables: values that vary from cell to cell and polygon to polygon,
/// within the ranges the checks allow.
struct Storage {
    tau: Vec<f32>,
    albedo: Vec<f32>,
    shares: Vec<f32>,
    response: Vec<f32>,
    shape: Vec<f32>,
    visible: Vec<u8>,
}

const BANDS: usize = 2;

fn storage(tau_side: u32, in_side: u32, out_side: u32, single_side: u32, polys: u32) -> Storage {
    let tau_cells = tau_side * tau_side;
    let (n_in, n_out) = (in_side * in_side, out_side * out_side);
    let tau = (0..tau_cells).map(|c| 0.2 + 0.7 * noise(c, 1)).collect();
    let albedo = (0..tau_cells as usize * 2 * BANDS)
        .map(|i| 0.45 * noise(i as u32, 2))
        .collect();
    let shares = (0..n_in as usize * 2 * BANDS)
        .map(|i| {
            // Some cells leave a side unlit, as real tables do.
            let x = noise(i as u32, 3);
            if x < 0.15 { 0.0 } else { x }
        })
        .collect();
    let response = (0..(n_in * n_out) as usize * 2 * BANDS)
        .map(|i| 0.05 * noise(i as u32, 4))
        .collect();
    let mut shape = Vec::new();
    for p in 0..polys {
        let n = Vec3::new(
            noise(p, 5) - 0.5,
            noise(p, 6) - 0.5,
            noise(p, 7) - 0.5 + 0.1,
        )
        .normalize();
        shape.extend_from_slice(&[n.x, n.y, n.z, 0.01 + 0.05 * noise(p, 8)]);
        for b in 0..BANDS as u32 {
            for k in 0..3 {
                shape.push(0.5 * noise(p * 8 + b * 3 + k, 9));
            }
        }
    }
    let visible = (0..single_side * single_side * polys)
        .map(|i| (noise(i, 10) * 255.0) as u8)
        .collect();
    Storage {
        tau,
        albedo,
        shares,
        response,
        shape,
        visible,
    }
}

fn tables<'a>(s: &'a Storage, sides: (u32, u32, u32, u32), polys: usize) -> DirectionalTables<'a> {
    let (tau_side, in_side, out_side, single_side) = sides;
    let grid = |n| DirectionGrid::new(n).unwrap();
    let phase =
        PhaseTable::new(grid(in_side), grid(out_side), BANDS, &s.shares, &s.response).unwrap();
    let lo = Vec3::new(-0.3, -0.2, 0.0);
    let hi = Vec3::new(0.4, 0.25, 1.2);
    let t = DirectionalTables::new(lo, hi, grid(tau_side), &s.tau, &s.albedo, phase).unwrap();
    if polys == 0 {
        return t;
    }
    let single = SingleScatter::new(grid(single_side), BANDS, polys, &s.shape, &s.visible).unwrap();
    t.with_single(single).unwrap()
}

fn placements() -> [Similarity; 3] {
    [
        Similarity::IDENTITY,
        Similarity {
            rotation: Quat::from_axis_angle(Vec3::new(0.3, -0.5, 0.8).normalize(), 1.1),
            translation: Vec3::new(4.0, -2.0, 0.5),
            scale: 2.5,
        },
        Similarity {
            rotation: Quat::from_rotation_z(2.9),
            translation: Vec3::new(-10.0, 3.0, 0.0),
            scale: 0.07,
        },
    ]
}

#[test]
fn the_received_light_sends_the_sum_of_its_beams() {
    for (sides, polys) in [
        ((8, 4, 8, 8), 7usize),
        ((16, 8, 4, 4), 3),
        ((4, 2, 16, 16), 1),
        ((8, 4, 8, 8), 0),
    ] {
        let s = storage(sides.0, sides.1, sides.2, sides.3, polys.max(1) as u32);
        let t = tables(&s, sides, polys);
        for place in placements() {
            let placed = Placed::new(t, place);
            let mut values = vec![0.0f32; placed.received_len()];
            let mut received = Received::new(&placed, &mut values).unwrap();
            let beams: Vec<(Vec3, [f32; BANDS])> = spread(9, 0.4)
                .enumerate()
                .map(|(i, d)| (d, [1.0 + i as f32, 30.0 * noise(i as u32, 11)]))
                .collect();
            for (d, e) in &beams {
                received.receive(&placed, *d, e);
            }
            for band in 0..BANDS {
                let (mut intercepted, mut scattered) = (0.0, 0.0);
                for (d, e) in &beams {
                    intercepted += e[band] * placed.shadow(*d);
                    scattered += e[band] * placed.scattered(*d, band);
                }
                let close = |a: f32, b: f32| (a - b).abs() <= 1e-4 * b.abs().max(1e-6);
                assert!(close(received.intercepted(band), intercepted));
                assert!(close(received.scattered(band), scattered));
                assert!(close(received.absorbed(band), intercepted - scattered));
                for o in spread(50, 0.1) {
                    let want: f32 = beams
                        .iter()
                        .map(|(d, e)| e[band] * placed.intensity(*d, o, band))
                        .sum();
                    let got = received.intensity(&placed, o, band);
                    assert!(
                        (got - want).abs() <= 1e-4 * want.max(1e-6),
                        "{sides:?} {polys} band {band} towards {o}: {got} vs {want}"
                    );
                }
            }
            // The same beams received in two parts and added: the same light.
            let mut first = vec![0.0f32; placed.received_len()];
            let mut second = vec![0.0f32; placed.received_len()];
            let mut a = Received::new(&placed, &mut first).unwrap();
            let mut b = Received::new(&placed, &mut second).unwrap();
            for (k, (d, e)) in beams.iter().enumerate() {
                if k % 2 == 0 {
                    a.receive(&placed, *d, e);
                } else {
                    b.receive(&placed, *d, e);
                }
            }
            a.add(&b);
            for o in spread(10, 0.3) {
                let (x, y) = (
                    a.intensity(&placed, o, 1),
                    received.intensity(&placed, o, 1),
                );
                assert!((x - y).abs() <= 1e-4 * y.max(1e-6));
            }
            received.clear();
            assert_eq!(received.intensity(&placed, Vec3::Z, 0), 0.0);
            assert_eq!(received.intercepted(1), 0.0);
        }
    }
}

#[test]
fn the_transform_turns_and_scales_the_tables() {
    let sides = (8, 4, 8, 8);
    let s = storage(8, 4, 8, 8, 5);
    let t = tables(&s, sides, 5);
    for place in placements() {
        let placed = Placed::new(t, place);
        let s2 = place.scale * place.scale;
        for d in spread(12, 0.2) {
            let w = place.direction(d);
            let rel = |a: f32, b: f32| (a - b).abs() <= 2e-4 * b.abs().max(1e-5);
            assert!(rel(placed.tau(w), t.tau(d)));
            assert!(rel(placed.area(w), s2 * t.area(d)));
            assert!(rel(placed.shadow(w), s2 * t.shadow(d)));
            assert!(rel(placed.scattered(w, 1), s2 * t.scattered(d, 1)));
            for o in spread(7, 0.9) {
                let got = placed.intensity(w, place.direction(o), 0);
                assert!(rel(got, s2 * t.intensity(d, o, 0)), "{got}");
            }
        }
    }
}

/// One leaf seen whole from everywhere, tables that keep its first scattering and nothing
/// more: what leaves the instance over the sphere is `E A |n.d| (rho + tau)`, the reflected
/// part towards the lit side's hemisphere, the transmitted part towards the other.
#[test]
fn a_leaf_sends_out_what_it_reflects_and_transmits() {
    let (area, rho_f, rho_b, tau_leaf) = (0.3f32, 0.4f32, 0.25f32, 0.15f32);
    let normal = Vec3::new(0.0, 0.6, 0.8);
    let shape = [normal.x, normal.y, normal.z, area, rho_f, rho_b, tau_leaf];
    assert_eq!(shape.len(), shape_stride(1));
    let g = DirectionGrid::new(8).unwrap();
    let visible = vec![VISIBLE_ONE; g.cells() as usize];
    let tau = vec![0.5; g.cells() as usize];
    let albedo = vec![0.0; g.cells() as usize * 2];
    let shares = vec![0.0; g.cells() as usize * 2];
    let response = vec![0.0; (g.cells() * g.cells()) as usize * 2];
    let phase = PhaseTable::new(g, g, 1, &shares, &response).unwrap();
    let t = DirectionalTables::new(Vec3::splat(-1.0), Vec3::splat(1.0), g, &tau, &albedo, phase)
        .unwrap()
        .with_single(SingleScatter::new(g, 1, 1, &shape, &visible).unwrap())
        .unwrap();
    for place in placements() {
        let placed = Placed::new(t, place);
        let s2 = place.scale * place.scale;
        let mut values = vec![0.0f32; placed.received_len()];
        let mut received = Received::new(&placed, &mut values).unwrap();
        let beams = [
            (Vec3::new(0.3, 0.2, 0.9), 500.0f32),
            (Vec3::new(-0.2, -0.9, -0.1), 80.0),
        ];
        let mut want = [0.0f32; 2];
        for (d, e) in beams {
            let d = d.normalize();
            let w = place.direction(d);
            received.receive(&placed, w, &[e]);
            let cd = normal.dot(d);
            let (rho, lit_front) = if cd > 0.0 {
                (rho_f, true)
            } else {
                (rho_b, false)
            };
            // Reflected towards the lit side, transmitted towards the other: by the side
            // of the leaf's plane the observer is on.
            let p = e * area * cd.abs() * s2;
            want[usize::from(!lit_front)] += p * rho;
            want[usize::from(lit_front)] += p * tau_leaf;
        }
        // Over the sphere, by the side of the leaf's plane the observer is on.
        let n = 20_000u32;
        let mut got = [0.0f32; 2];
        for o in spread(n, 0.0) {
            let side = usize::from(normal.dot(o) < 0.0);
            got[side] += received.intensity(&placed, place.direction(o), 0) * 4.0 * PI / n as f32;
        }
        for side in 0..2 {
            assert!(
                (got[side] - want[side]).abs() <= 5e-3 * want[side],
                "side {side}: {} vs {}",
                got[side],
                want[side]
            );
        }
    }
}

#[test]
fn a_segment_crosses_the_placed_box_or_not() {
    let s = storage(4, 2, 2, 2, 1);
    let t = tables(&s, (4, 2, 2, 2), 0);
    // Box (-0.3, -0.2, 0) .. (0.4, 0.25, 1.2) in the original's frame.
    for place in placements() {
        let placed = Placed::new(t, place);
        let w = |x: Vec3| place.point(x);
        let through = [
            (Vec3::new(0.0, 0.0, -1.0), Vec3::new(0.0, 0.0, 2.0)),
            (Vec3::new(-5.0, 0.1, 0.6), Vec3::new(5.0, 0.1, 0.6)),
            // Starts inside.
            (Vec3::new(0.1, 0.1, 0.5), Vec3::new(3.0, 4.0, 5.0)),
            // Parallel to a face, inside the slab.
            (Vec3::new(0.2, -3.0, 1.0), Vec3::new(0.2, 3.0, 1.0)),
        ];
        for (a, b) in through {
            assert!(placed.crosses(w(a), w(b)), "{a} {b}");
        }
        let beside = [
            (Vec3::new(0.5, 0.0, -1.0), Vec3::new(0.5, 0.0, 2.0)),
            // Stops short of the box.
            (Vec3::new(0.0, 0.0, -2.0), Vec3::new(0.0, 0.0, -0.1)),
            // Passes a corner.
            (Vec3::new(-1.0, 0.0, 2.0), Vec3::new(0.0, 1.0, 2.0)),
            // Parallel to a face, outside the slab.
            (Vec3::new(0.2, -3.0, 1.3), Vec3::new(0.2, 3.0, 1.3)),
        ];
        for (a, b) in beside {
            assert!(!placed.crosses(w(a), w(b)), "{a} {b}");
        }
    }
}

#[test]
fn storage_of_the_wrong_length_is_refused() {
    let s = storage(4, 2, 2, 2, 3);
    let t = tables(&s, (4, 2, 2, 2), 3);
    let placed = Placed::new(t, Similarity::IDENTITY);
    // Two totals per band, two sides per band for 3 polygons and 4 incoming cells.
    assert_eq!(placed.received_len(), 2 * BANDS + 2 * BANDS * (3 + 4));
    let mut short = vec![0.0f32; placed.received_len() - 1];
    assert_eq!(
        Received::new(&placed, &mut short).unwrap_err(),
        TableError::Length {
            expected: placed.received_len() as u64,
            given: placed.received_len() as u64 - 1,
        }
    );
    // Light that is not a number, negative, or from no direction adds nothing.
    let mut values = vec![0.0f32; placed.received_len()];
    let mut r = Received::new(&placed, &mut values).unwrap();
    r.receive(&placed, Vec3::ZERO, &[1.0, 1.0]);
    r.receive(&placed, Vec3::Z, &[f32::NAN, -3.0]);
    r.receive(&placed, Vec3::X, &[f32::INFINITY]);
    assert!((0..BANDS).all(|b| r.intercepted(b) == 0.0 && r.scattered(b) == 0.0));
    assert!(spread(20, 0.0).all(|o| r.intensity(&placed, o, 0) == 0.0));
}

/// Tables laid out as an image stores them come back as the same tables, and a record
/// that does not match its storage is refused.
#[test]
fn tables_come_back_from_their_record() {
    use crate::image::TableRecord;
    let sides = (8u32, 4u32, 8u32, 4u32);
    let polys = 3usize;
    let s = storage(sides.0, sides.1, sides.2, sides.3, polys as u32);
    let t = tables(&s, sides, polys);
    let (lo, hi) = t.bounds();
    let record = TableRecord {
        original: 0,
        bands: BANDS as u32,
        tau_side: sides.0,
        incoming_side: sides.1,
        outgoing_side: sides.2,
        lo: lo.to_array(),
        hi: hi.to_array(),
        scatterers: polys as u32,
        single_side: sides.3,
        ..TableRecord::default()
    };
    let mut values = Vec::new();
    for part in [&s.tau, &s.albedo, &s.shares, &s.response, &s.shape] {
        values.extend_from_slice(part);
    }
    let back = DirectionalTables::from_record(&record, &values, &s.visible).unwrap();
    assert_eq!(back, t);
    let short = &values[..values.len() - 1];
    assert!(matches!(
        DirectionalTables::from_record(&record, short, &s.visible),
        Err(TableError::Length { .. })
    ));
    assert!(matches!(
        DirectionalTables::from_record(&record, &values, &s.visible[1..]),
        Err(TableError::Length { .. })
    ));
    let no_grid = TableRecord {
        tau_side: 0,
        ..record
    };
    // Lengths follow the sides, so a side of 0 is caught by its grid, not by a length.
    let mut fewer = values.clone();
    fewer.drain(..(sides.0 * sides.0) as usize * (1 + 2 * BANDS));
    assert_eq!(
        DirectionalTables::from_record(&no_grid, &fewer, &s.visible),
        Err(TableError::Grid)
    );
    let mut bad = values.clone();
    bad[3] = f32::NAN;
    assert!(matches!(
        DirectionalTables::from_record(&record, &bad, &s.visible),
        Err(TableError::Value { index: 3 })
    ));
}

/// A segment through the whole box lets `tau` through; one that starts halfway along the
/// chord, `tau^0.5`; one that misses, everything.
#[test]
fn a_segment_is_attenuated_by_the_share_of_the_chord_it_runs() {
    let s = storage(4, 2, 2, 2, 1);
    let t = tables(&s, (4, 2, 2, 2), 0);
    // Box (-0.3, -0.2, 0) .. (0.4, 0.25, 1.2) in the original's frame.
    for place in placements() {
        let placed = Placed::new(t, place);
        let w = |x: Vec3| place.point(x);
        let d = Vec3::Z;
        let tau = placed.tau(place.direction(d));
        let through =
            placed.transmittance(w(Vec3::new(0.1, 0.0, -1.0)), w(Vec3::new(0.1, 0.0, 3.0)));
        assert!((through - tau).abs() < 1e-6, "{through} vs {tau}");
        let half = placed.transmittance(w(Vec3::new(0.1, 0.0, 0.6)), w(Vec3::new(0.1, 0.0, 3.0)));
        assert!((half - libm::powf(tau, 0.5)).abs() < 1e-4, "{half}");
        let inside = placed.transmittance(w(Vec3::new(0.1, 0.0, 0.3)), w(Vec3::new(0.1, 0.0, 0.9)));
        assert!((inside - libm::powf(tau, 0.5)).abs() < 1e-4, "{inside}");
        let miss = placed.transmittance(w(Vec3::new(0.5, 0.0, -1.0)), w(Vec3::new(0.5, 0.0, 3.0)));
        assert_eq!(miss, 1.0);
    }
}

/// A beam received spread (no first scattering) and its polygons' light added where it
/// lands is the beam received whole, when what is added is what the beam would have given
/// each polygon; without it, the first scattering is missing and nothing else.
#[test]
fn a_beam_spread_and_its_polygons_lit_apart_is_the_beam() {
    let sides = (8, 4, 8, 8);
    let polys = 5usize;
    let s = storage(sides.0, sides.1, sides.2, sides.3, polys as u32);
    let t = tables(&s, sides, polys);
    for place in placements() {
        let placed = Placed::new(t, place);
        for (i, d) in spread(6, 0.7).enumerate() {
            let e = [2.0 + i as f32, 40.0 * noise(i as u32, 3)];
            let mut whole_v = vec![0.0f32; placed.received_len()];
            let mut whole = Received::new(&placed, &mut whole_v).unwrap();
            whole.receive(&placed, d, &e);
            let mut spread_v = vec![0.0f32; placed.received_len()];
            let mut parts = Received::new(&placed, &mut spread_v).unwrap();
            parts.receive_spread(&placed, d, &e);
            // Nothing on the polygons yet: the rest and the totals only.
            for band in 0..BANDS {
                assert_eq!(parts.intercepted(band), whole.intercepted(band));
                assert_eq!(parts.scattered(band), whole.scattered(band));
                for p in 0..polys {
                    for side in 0..2 {
                        assert_eq!(parts.first_irradiance(p, side, band), 0.0);
                    }
                }
            }
            let mut lit = 0.0f32;
            for band in 0..BANDS {
                for p in 0..polys {
                    for side in 0..2 {
                        let v = whole.first_irradiance(p, side, band);
                        lit += v;
                        parts.add_first(p, side, band, v);
                    }
                }
            }
            assert!(lit > 0.0, "the beam lights some polygon");
            for band in 0..BANDS {
                for o in spread(20, 0.2) {
                    let (a, b) = (
                        parts.intensity(&placed, o, band),
                        whole.intensity(&placed, o, band),
                    );
                    assert!((a - b).abs() <= 1e-5 * b.abs().max(1e-6), "{a} vs {b}");
                }
            }
            assert_eq!(parts.first_range(), whole.first_range());
            assert_eq!(parts.first_range().len(), polys * 2 * BANDS);
        }
    }
}
