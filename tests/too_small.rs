//! Polygons too small for 32-bit floats at their position are refused by the same rule
//! everywhere they enter: the core's shape check, the binary image, the `.hir` text and OBJ
//! import. The rule (`hirad_core::geometry::polygon_shape`): the longest edge is below 2^-20
//! of the largest absolute corner coordinate, or the area is below the smallest normal f32.

use glam::{DVec3, Vec3};
use hirad::scene::{compile, read_image};
use hirad_core::geometry::{MIN_AREA, RESOLUTION_REL, ShapeError, polygon_shape};
use hirad_core::image::{Header, ImageError, ImageErrorKind, Section};
use proptest::prelude::*;

/// A one-band scene: polygon 0 spans the box [-1e18, 1e18]^3, so the image's stored bounding
/// box stays valid when the probe's corners are patched in (every probe lies inside it);
/// polygon 1 is the probe (a unit triangle here), vertices 3, 4, 5 are its corners.
const BASE: &str = "hirad 1
bands 1
material m rho 0.5 emit 1
scene {
  tri m -1e18 -1e18 -1e18  1e18 1e18 -1e18  1e18 -1e18 1e18
  tri m 0 0 0  1 0 0  0 1 0
}
";

fn header(bytes: &[u8]) -> Header {
    bytemuck::pod_read_unaligned(&bytes[..std::mem::size_of::<Header>()])
}

fn record_offset(bytes: &[u8], s: Section, index: u64) -> u64 {
    let e = header(bytes).section(s);
    e.offset + index * e.record_size as u64
}

/// The base image with the probe's corners replaced by `corners`.
fn image_with(corners: [Vec3; 3]) -> Vec<u8> {
    let scene = hirad::text::parse(BASE.as_bytes()).unwrap();
    let mut bytes = compile(&scene).unwrap();
    for (k, c) in corners.iter().enumerate() {
        let at = record_offset(&bytes, Section::Vertices, 3 + k as u64) as usize;
        for (j, v) in c.to_array().iter().enumerate() {
            bytes[at + 4 * j..at + 4 * j + 4].copy_from_slice(&v.to_le_bytes());
        }
    }
    bytes
}

/// Rust prints f32 in shortest round-trip form, so text and OBJ read back the same bits.
fn coords(c: Vec3) -> String {
    format!("{} {} {}", c.x, c.y, c.z)
}

/// The probe as a `.hir` scene: its `tri` is at 5:3.
fn text_with(corners: [Vec3; 3]) -> String {
    format!(
        "hirad 1\nbands 1\nmaterial m rho 0.5 emit 1\nscene {{\n  tri m {}  {}  {}\n}}\n",
        coords(corners[0]),
        coords(corners[1]),
        coords(corners[2])
    )
}

/// The probe as an OBJ: its face is on line 4.
fn obj_with(corners: [Vec3; 3]) -> String {
    format!(
        "v {}\nv {}\nv {}\nf 1 2 3\n",
        coords(corners[0]),
        coords(corners[1]),
        coords(corners[2])
    )
}

/// The rule computed independently, in f64: `Some(true)` too small, `Some(false)` large
/// enough, `None` within 0.1% of a threshold (where f32 and f64 may round differently).
fn model(c: [Vec3; 3]) -> Option<bool> {
    let d = c.map(|v| v.as_dvec3());
    let reach = d.iter().map(|v| v.abs().max_element()).fold(0.0, f64::max);
    let longest = (0..3)
        .map(|i| (d[(i + 1) % 3] - d[i]).length())
        .fold(0.0, f64::max);
    let area = 0.5 * (d[1] - d[0]).cross(d[2] - d[0]).length();
    let edge_limit = reach * f64::from(RESOLUTION_REL);
    let area_limit = f64::from(MIN_AREA);
    let near = |x: f64, limit: f64| (x - limit).abs() <= 1e-3 * limit;
    if near(longest, edge_limit) || near(area, area_limit) {
        return None;
    }
    Some(longest < edge_limit || area < area_limit)
}

/// Every loader gives the core's verdict on the probe; returns it.
fn check_everywhere(corners: [Vec3; 3]) -> Result<(), ShapeError> {
    let verdict = polygon_shape(&corners).map(|_| ());

    let bytes = image_with(corners);
    match (read_image(&bytes), verdict) {
        (Ok(_), Ok(())) => {}
        (Err(e), Err(error)) => assert_eq!(
            e,
            ImageError {
                offset: record_offset(&bytes, Section::Polygons, 1),
                kind: ImageErrorKind::Shape { polygon: 1, error }
            },
            "{corners:?}"
        ),
        (got, _) => panic!("{corners:?}: image {:?}, core {verdict:?}", got.map(|_| ())),
    }

    match (hirad::text::parse(text_with(corners).as_bytes()), verdict) {
        (Ok(_), Ok(())) => {}
        (Err(e), Err(error)) => {
            assert_eq!((e.line, e.column), (5, 3), "{corners:?}: {e}");
            if error == ShapeError::TooSmall {
                assert!(
                    e.message.starts_with(
                        "this triangle is too small for 32-bit floats at its position: "
                    ),
                    "{e}"
                );
            }
        }
        (got, _) => panic!("{corners:?}: text {:?}, core {verdict:?}", got.map(|_| ())),
    }

    let obj =
        hirad::obj::import(obj_with(corners).as_bytes(), &mut |_| Err("none".into())).unwrap();
    match verdict {
        Ok(()) => {
            assert_eq!(obj.counts.polygons, 1, "{corners:?}: {:?}", obj.warnings);
            assert!(obj.warnings.is_empty(), "{:?}", obj.warnings);
        }
        Err(error) => {
            assert_eq!(obj.counts.skipped_faces, 1, "{corners:?}");
            if error == ShapeError::TooSmall {
                assert_eq!(
                    obj.warnings,
                    ["4:1: face too small for 32-bit floats at its position skipped"]
                );
            }
        }
    }
    verdict
}

fn tri(at: Vec3, size: f32) -> [Vec3; 3] {
    [
        at,
        at + Vec3::new(size, 0.0, 0.0),
        at + Vec3::new(0.0, size, 0.0),
    ]
}

#[test]
fn the_examples_of_the_rule() {
    use ShapeError::TooSmall;
    // 1e-30 m at the origin: its area (5e-61 m^2) underflows.
    assert_eq!(check_everywhere(tri(Vec3::ZERO, 1e-30)), Err(TooSmall));
    // 1e-30 m at (1, 1, 1): the corners round to one point.
    assert_eq!(check_everywhere(tri(Vec3::ONE, 1e-30)), Err(TooSmall));
    // 1 um near the origin.
    assert_eq!(
        check_everywhere(tri(Vec3::new(1e-3, 0.0, 0.0), 1e-6)),
        Ok(())
    );
    assert_eq!(check_everywhere(tri(Vec3::ZERO, 1e-6)), Ok(()));
    // 1e6 m from the origin (f32 steps of 0.0625 m): 1 mm and 0.5 m refused, 1 m accepted.
    let far = Vec3::new(1e6, 0.0, 0.0);
    assert_eq!(check_everywhere(tri(far, 1e-3)), Err(TooSmall));
    assert_eq!(check_everywhere(tri(Vec3::splat(1e6), 1e-3)), Err(TooSmall));
    assert_eq!(check_everywhere(tri(far, 0.5)), Err(TooSmall));
    assert_eq!(check_everywhere(tri(far, 1.0)), Ok(()));
    assert_eq!(check_everywhere(tri(Vec3::splat(1e6), 1.0)), Ok(()));
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    /// Triangles of fair shape at every distance from the origin (10^-30 to 10^15 m) and of
    /// every size relative to it (10^-12 to 10^2 times the distance): every loader agrees
    /// with the core, and the core with the rule.
    #[test]
    fn every_loader_applies_the_rule_at_every_scale(
        position in -30.0f64..15.0,
        relative in -12.0f64..2.0,
        direction in prop::array::uniform3(-1.0f64..1.0),
        shape in prop::array::uniform2(prop::array::uniform3(-1.0f64..1.0)),
    ) {
        let dir = DVec3::from_array(direction);
        prop_assume!(dir.length() > 0.1);
        let at = dir.normalize() * 10f64.powf(position);
        let size = 10f64.powf(position + relative);
        let a = DVec3::from_array(shape[0]);
        let b = DVec3::from_array(shape[1]);
        // A triangle of fair shape, so that only its size can refuse it.
        let twice = a.cross(b).length();
        prop_assume!(twice > 0.2 * a.length_squared().max(b.length_squared()).max((a - b).length_squared()));
        let corners = [at, at + a * size, at + b * size].map(|p| p.as_vec3());
        let Some(small) = model(corners) else {
            return Ok(());
        };
        let verdict = check_everywhere(corners);
        match verdict {
            Err(ShapeError::TooSmall) => prop_assert!(small, "{corners:?}"),
            Ok(()) => prop_assert!(!small, "{corners:?}"),
            // Corners rounded onto a line: refused as degenerate, by every loader alike.
            Err(ShapeError::Degenerate) => {}
            Err(e) => prop_assert!(false, "{corners:?}: {e:?}"),
        }
    }
}
