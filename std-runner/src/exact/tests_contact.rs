//! Buried points at contact lines: a box standing on a floor that runs on under it must be
//! lit as if the floor were cut around its footprint.

use super::tests::{Got, small, solve};
use super::*;

/// Footprint of the box `[x0, x1] x [y0, y1]` (m), its height, and the floor's side. The
/// footprint's edges cross the floor's elements (not on a cell boundary at any level the budgets
/// used give), so each straddling element has buried and exposed points.
const BOX: [f32; 4] = [0.41, 0.79, 0.26, 0.64];
const HEIGHT: f32 = 0.3;
const FLOOR: f32 = 1.2;

/// A grey box (one-sided faces pointing out of it, no bottom) on a white floor (`z = 0`, front
/// up) under a 0.8 m square lamp facing down at `z = 1`; the floor is one quad running on
/// under the box, or (`cut`) the 8 quads around the footprint. Polygons: the floor piece(s),
/// then the box's top and its -y, +x, +y, -x faces, then the lamp. `floor_two_sided` and
/// `box_two_sided` make those materials two-sided (rho 0.8 / 0.5 on both sides).
fn box_on_floor(cut: bool, floor_two_sided: bool, box_two_sided: bool) -> Scene {
    let [x0, x1, y0, y1] = BOX;
    let (h, l) = (HEIGHT, FLOOR);
    let quad = |m: &str, c: [[f32; 3]; 4]| {
        let v: Vec<String> = c
            .iter()
            .map(|p| format!("{} {} {}", p[0], p[1], p[2]))
            .collect();
        format!("  quad {m} {}\n", v.join("  "))
    };
    let back = |two_sided: bool, rho: f32| {
        if two_sided {
            format!(" back_rho {rho}")
        } else {
            String::new()
        }
    };
    let mut s = format!(
        "hirad 1\nbands 1\nmaterial floor rho 0.8{}\nmaterial box rho 0.5{}\n\
         material lamp rho 0 emit 1\nscene {{\n",
        back(floor_two_sided, 0.8),
        back(box_two_sided, 0.5)
    );
    if cut {
        let (xs, ys) = ([0.0, x0, x1, l], [0.0, y0, y1, l]);
        for j in 0..3 {
            for i in 0..3 {
                if (i, j) != (1, 1) {
                    let (a, b, c, d) = (xs[i], xs[i + 1], ys[j], ys[j + 1]);
                    s += &quad("floor", [[a, c, 0.], [b, c, 0.], [b, d, 0.], [a, d, 0.]]);
                }
            }
        }
    } else {
        s += &quad(
            "floor",
            [[0., 0., 0.], [l, 0., 0.], [l, l, 0.], [0., l, 0.]],
        );
    }
    s += &quad("box", [[x0, y0, h], [x1, y0, h], [x1, y1, h], [x0, y1, h]]);
    s += &quad(
        "box",
        [[x0, y0, 0.], [x1, y0, 0.], [x1, y0, h], [x0, y0, h]],
    );
    s += &quad(
        "box",
        [[x1, y0, 0.], [x1, y1, 0.], [x1, y1, h], [x1, y0, h]],
    );
    s += &quad(
        "box",
        [[x1, y1, 0.], [x0, y1, 0.], [x0, y1, h], [x1, y1, h]],
    );
    s += &quad(
        "box",
        [[x0, y1, 0.], [x0, y0, 0.], [x0, y0, h], [x0, y1, h]],
    );
    let (a, b, z) = (0.2, 1.0, 1.0);
    s += &quad("lamp", [[a, a, z], [a, b, z], [b, b, z], [b, a, z]]);
    s += "}\n";
    crate::text::parse(s.as_bytes()).unwrap()
}

/// Power onto the floor pieces (W): area times mean irradiance.
fn floor_power(floor: &[Got]) -> f64 {
    floor
        .iter()
        .map(|p| p.area as f64 * p.irradiance[0][0] as f64)
        .sum()
}

#[test]
fn a_box_on_a_floor_running_under_it_is_lit_as_on_a_floor_cut_around_it() {
    // 2500 elements: at 1500 the dim -y face is 2.5% bright against a particle tracer on
    // the one-quad floor (0.7% on the cut one) from its coarse grazing view of the floor.
    let settings = small(2500);
    let (one, r_one) = solve(&box_on_floor(false, false, false), &settings);
    let (cut, r_cut) = solve(&box_on_floor(true, false, false), &settings);
    assert_eq!((one.len(), cut.len()), (7, 14));
    // Only the floor under the box is buried; the cut floor has nothing under it.
    assert!(r_one.buried_points > 0, "{r_one:?}");
    assert_eq!(r_cut.buried_points, 0, "{r_cut:?}");
    // The box's side faces see the floor right beside them at large form factors: an
    // element straddling the footprint must give them its exposed part's radiosity, not
    // its area mean with the dark part under the box (which made them 3.5-4.2 % too dark).
    for face in 2..6 {
        let (a, b) = (one[face].radiosity[0][0], cut[face + 7].radiosity[0][0]);
        assert!(a > 0.0 && b > 0.0);
        let rel = (a / b - 1.0).abs();
        assert!(rel < 0.01, "face {face}: {a} vs {b} ({:.2} %)", rel * 100.0);
    }
    // The table counts the buried part as unlit: the one-quad floor's mean irradiance over
    // its whole area is the cut floor's power over the same area.
    let (p_one, p_cut) = (floor_power(&one[..1]), floor_power(&cut[..8]));
    let rel = (p_one / p_cut - 1.0).abs();
    assert!(
        rel < 0.005,
        "floor power {p_one} vs {p_cut} ({:.3} %)",
        rel * 100.0
    );
    let footprint = ((BOX[1] - BOX[0]) * (BOX[3] - BOX[2])) as f64;
    let cut_area: f64 = cut[..8].iter().map(|p| p.area as f64).sum();
    assert!((one[0].area as f64 - cut_area - footprint).abs() < 1e-5);
    // Radiosity is E + rho H of those means (the floor does not emit).
    let (b, h) = (one[0].radiosity[0][0], one[0].irradiance[0][0]);
    assert!((b / (0.8 * h) - 1.0).abs() < 1e-5, "{b} vs 0.8 x {h}");
}

#[test]
fn two_sided_materials_are_never_buried_and_never_bury() {
    let settings = small(300);
    let (_, one_sided) = solve(&box_on_floor(false, false, false), &settings);
    assert!(one_sided.buried_points > 0, "{one_sided:?}");
    // A leaf-like floor under the box: its points are never buried.
    let (two, r) = solve(&box_on_floor(false, true, false), &settings);
    assert_eq!(r.buried_points, 0, "{r:?}");
    assert!(two[0].two_sided);
    // A two-sided box: its faces' backs do not bury the floor under it.
    let (_, r) = solve(&box_on_floor(false, false, true), &settings);
    assert_eq!(r.buried_points, 0, "{r:?}");
}
