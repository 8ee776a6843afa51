//! The exact reference solver on the fixtures with known answers (see fixtures/README.md):
//! plate form factors, closed furnaces, and the Cornell box's cost.

use hirad::exact::{ExactReport, ExactSettings, solve_exact_obvhs};
use hirad::scene::Scene;
use hirad_core::sink::{PolygonResult, Sink};
use hirad_tests::fixture;
use std::convert::Infallible;

/// Per polygon: area, radiosity and irradiance of the front side, band by band.
#[derive(Default)]
struct Fronts(Vec<(f32, Vec<f32>, Vec<f32>)>);

impl Sink for Fronts {
    type Error = Infallible;

    fn polygon(&mut self, p: &PolygonResult<'_>) -> Result<(), Infallible> {
        assert_eq!(p.id, self.0.len() as u64, "global-id order");
        self.0
            .push((p.area, p.radiosity[0].to_vec(), p.irradiance[0].to_vec()));
        Ok(())
    }
}

fn load(name: &str) -> Scene {
    hirad::files::load_scene(&fixture(name)).unwrap().scene
}

fn solve(name: &str, max_elements: usize) -> (Fronts, ExactReport) {
    let settings = ExactSettings {
        max_elements,
        ..ExactSettings::default()
    };
    let mut out = Fronts::default();
    let report = solve_exact_obvhs(&load(name), &settings, &mut out).unwrap();
    (out, report)
}

fn assert_near(value: f32, expect: f64, rel: f64, what: &str) {
    let err = (value as f64 / expect - 1.0).abs();
    assert!(
        err < rel,
        "{what}: {value} vs {expect} ({:.3}%)",
        err * 100.0
    );
}

#[test]
fn parallel_squares_form_factor() {
    let (out, report) = solve("parallel_squares.hir", 128);
    assert_eq!((report.polygons, report.elements), (2, 128));
    assert_near(out.0[1].2[0], 0.19982, 0.005, "receiver irradiance");
    assert_eq!(out.0[1].1[0], 0.0);
}

#[test]
fn perpendicular_squares_form_factor() {
    let (out, _) = solve("perpendicular_squares.hir", 128);
    assert_near(out.0[1].2[0], 0.20004, 0.005, "receiver irradiance");
}

#[test]
fn furnaces_reach_e_over_one_minus_rho() {
    for (name, expect) in [("furnace.hir", 2.0), ("furnace_099.hir", 100.0)] {
        let (out, report) = solve(name, 96);
        assert_eq!(out.0.len(), 24);
        for (k, (_, radiosity, _)) in out.0.iter().enumerate() {
            assert_near(radiosity[0], expect, 0.005, &format!("{name} polygon {k}"));
        }
        assert!(report.error <= 1e-7, "{report:?}");
    }
}

#[test]
fn cornell_box_small() {
    let (out, report) = solve("cornell_box.hir", 300);
    assert_eq!(report.polygons, 17);
    assert!(
        report.elements <= 300 && report.elements > 150,
        "{report:?}"
    );
    // The light: emitted exitance plus what it reflects from the room.
    let light = &out.0[6];
    assert!((light.0 - 0.01365).abs() < 1e-5, "{}", light.0);
    assert!(light.1[0] > 53.4 && light.1[0] < 60.0, "{:?}", light.1);
    // Every surface of the room is lit, red and green walls tint as their reflectances say.
    for (k, (_, b, h)) in out.0.iter().enumerate() {
        assert!(h.iter().all(|v| *v > 0.0), "polygon {k}: {h:?}");
        assert!(b.iter().all(|v| *v > 0.0), "polygon {k}: {b:?}");
    }
}

/// The reference size: run with
/// `cargo test --release --test exact -- --ignored --nocapture cornell_box_reference`.
#[test]
#[ignore = "seconds in release, minutes in debug"]
fn cornell_box_reference() {
    let (_, r) = solve("cornell_box.hir", 3000);
    println!(
        "cornell box: {} elements, {} form factors, {} entries, {} rays, {} iterations, \
         {:.2} s ({:.2} s matrix), {:.1} Mrays/s, {:.1} MB matrix",
        r.elements,
        r.form_factors,
        r.entries,
        r.rays,
        r.iterations,
        r.seconds,
        r.matrix_seconds,
        r.rays as f64 / r.matrix_seconds / 1e6,
        r.matrix_bytes as f64 / 1e6
    );
}

#[test]
fn polygons_placed_too_small_for_f32_are_refused() {
    // A 10 cm leaf, valid in its original's frame, placed 1e7 m from the origin where f32
    // coordinates are 1 m apart; scaled down instead, it stays valid (the rule is relative
    // to the position).
    let scene = |placement: &str| {
        hirad::text::parse(
            format!(
                "hirad 1\nbands 1\nmaterial m rho 0.5 emit 1\noriginal leaf {{\n  \
                 tri m 0 0 0  0.1 0 0  0 0.1 0\n}}\nscene {{\n  tri m 0 0 0  10 0 0  0 10 0\n  \
                 instance leaf exact {placement}\n}}\n"
            )
            .as_bytes(),
        )
        .unwrap()
    };
    let settings = ExactSettings {
        max_elements: 50,
        ..ExactSettings::default()
    };
    let e = solve_exact_obvhs(
        &scene("translate 1e7 0 0"),
        &settings,
        &mut Fronts::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains(
            "polygon 1: once placed by its instances, the polygon is too small for 32-bit \
             floats at its position: its longest edge, 0.1 m, is less than 2^-20"
        ),
        "{e}"
    );
    let mut out = Fronts::default();
    solve_exact_obvhs(&scene("scale 1e-3"), &settings, &mut out).unwrap();
    assert_near(out.0[1].0, 0.005e-6, 1e-5, "area of the scaled leaf");
}
