//! Turning faces into valid triangles and quads: quads, fans, ear clipping, straight runs.

use super::*;

/// Splits `pts` and checks every piece: accepted by the core and facing the polygon's side.
/// Returns the pieces and the number of dropped parts.
fn split_checked(pts: &[Vec3], normal: Vec3) -> (Vec<Piece>, usize) {
    let mut out = Vec::new();
    let skipped = split(pts, &mut out).expect("within the corner limit");
    for p in &out {
        let corners: Vec<Vec3> = p.corners().iter().map(|&k| pts[k]).collect();
        let shape = polygon_shape(&corners).expect("every piece is accepted");
        assert!(shape.normal.dot(normal) > 0.0, "piece {p:?} is flipped");
    }
    (out, skipped)
}

fn area(pts: &[Vec3], pieces: &[Piece]) -> f32 {
    pieces
        .iter()
        .map(|p| {
            let c: Vec<Vec3> = p.corners().iter().map(|&k| pts[k]).collect();
            polygon_shape(&c).unwrap().area
        })
        .sum()
}

#[test]
fn triangles_and_good_quads_stay() {
    let z = Vec3::Z;
    let tri = [v(0., 0., 0.), v(1., 0., 0.), v(0., 1., 0.)];
    assert_eq!(split_checked(&tri, z), (vec![Piece::Tri([0, 1, 2])], 0));
    let sq = [v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)];
    assert_eq!(split_checked(&sq, z), (vec![Piece::Quad([0, 1, 2, 3])], 0));
    let line = [v(0., 0., 0.), v(1., 0., 0.), v(2., 0., 0.)];
    assert_eq!(split_checked(&line, z), (vec![], 0));
}

#[test]
fn refused_quads_split_along_the_right_diagonal() {
    let z = Vec3::Z;
    let bent = [v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.3), v(0., 1., 0.)];
    let (p, s) = split_checked(&bent, z);
    assert_eq!((p.len(), s), (2, 0));
    // Reflex corner at 2: only the diagonal 0-2 gives two triangles facing up.
    let dart = [v(0., 0., 0.), v(2., 0., 0.), v(0.5, 0.5, 0.), v(0., 2., 0.)];
    let (p, s) = split_checked(&dart, z);
    assert_eq!(p, vec![Piece::Tri([0, 1, 2]), Piece::Tri([0, 2, 3])]);
    assert_eq!(s, 0);
    assert!((area(&dart, &p) - 1.0).abs() < 1e-6);
    // Reflex corner at 3: the diagonal 1-3.
    let dart = [v(0., 2., 0.), v(0., 0., 0.), v(2., 0., 0.), v(0.5, 0.5, 0.)];
    let (p, s) = split_checked(&dart, z);
    assert_eq!(p, vec![Piece::Tri([0, 1, 3]), Piece::Tri([1, 2, 3])]);
    assert_eq!(s, 0);
    // Three corners in a row: the middle one is dropped, a triangle is left.
    let straight = [v(0., 0., 0.), v(1., 0., 0.), v(2., 0., 0.), v(0., 1., 0.)];
    assert_eq!(
        split_checked(&straight, z),
        (vec![Piece::Tri([0, 2, 3])], 0)
    );
    // The same with a corner repeated in place.
    let repeated = [v(0., 0., 0.), v(2., 0., 0.), v(2., 0., 0.), v(0., 1., 0.)];
    assert_eq!(
        split_checked(&repeated, z),
        (vec![Piece::Tri([0, 2, 3])], 0)
    );
}

#[test]
fn convex_polygons_fan_and_concave_ones_are_ear_clipped() {
    let z = Vec3::Z;
    let pentagon = [
        v(0., 0., 0.),
        v(2., 0., 0.),
        v(2.5, 1.5, 0.),
        v(1., 2.5, 0.),
        v(-0.5, 1.5, 0.),
    ];
    let (p, s) = split_checked(&pentagon, z);
    assert_eq!(
        p,
        vec![
            Piece::Tri([0, 1, 2]),
            Piece::Tri([0, 2, 3]),
            Piece::Tri([0, 3, 4])
        ]
    );
    assert_eq!(s, 0);
    let l = [
        v(0., 0., 0.),
        v(2., 0., 0.),
        v(2., 1., 0.),
        v(1., 1., 0.),
        v(1., 2., 0.),
        v(0., 2., 0.),
    ];
    let (p, s) = split_checked(&l, z);
    assert_eq!((p.len(), s), (4, 0));
    assert!((area(&l, &p) - 3.0).abs() < 1e-5);
    // The same L tilted and moved far away, in millimetres and in kilometres.
    for scale in [1e-3f32, 1.0, 1e3] {
        let r = Quat::from_axis_angle(v(1., 2., 3.).normalize(), 0.9);
        let moved: Vec<Vec3> = l
            .iter()
            .map(|q| r * (*q * scale) + v(5., -3., 2.) * scale)
            .collect();
        // Rounding may let an ear touch the reflex corner: 3 triangles, the same area.
        let (p, s) = split_checked(&moved, r * z);
        assert!(p.len() <= 4 && s == 0, "scale {scale}: {p:?}");
        assert!((area(&moved, &p) / (3.0 * scale * scale) - 1.0).abs() < 1e-3);
    }
}

#[test]
fn straight_corners_and_stars() {
    let z = Vec3::Z;
    // A square with a corner in the middle of every edge: not strictly convex.
    let sq = [
        v(0., 0., 0.),
        v(1., 0., 0.),
        v(2., 0., 0.),
        v(2., 1., 0.),
        v(2., 2., 0.),
        v(1., 2., 0.),
        v(0., 2., 0.),
        v(0., 1., 0.),
    ];
    assert_eq!(split_checked(&sq, z), (vec![Piece::Quad([0, 2, 4, 6])], 0));
    // The same starting in the middle of an edge.
    let mut shifted = sq.to_vec();
    shifted.rotate_left(1);
    assert_eq!(
        split_checked(&shifted, z),
        (vec![Piece::Quad([1, 3, 5, 7])], 0)
    );
    // An L with extra corners along its edges: still 4 triangles of area 3.
    let l = [
        v(0., 0., 0.),
        v(1., 0., 0.),
        v(2., 0., 0.),
        v(2., 1., 0.),
        v(1.5, 1., 0.),
        v(1., 1., 0.),
        v(1., 2., 0.),
        v(0., 2., 0.),
        v(0., 1., 0.),
    ];
    let (p, s) = split_checked(&l, z);
    assert_eq!((p.len(), s), (4, 0));
    assert!((area(&l, &p) - 3.0).abs() < 1e-5);
    // A fine circle keeps its shape: corners are only dropped within the core's tolerance.
    let circle: Vec<Vec3> = (0..2000)
        .map(|k| {
            let a = k as f32 * std::f32::consts::TAU / 2000.0;
            v(a.cos(), a.sin(), 0.)
        })
        .collect();
    let (p, s) = split_checked(&circle, z);
    assert_eq!(s, 0);
    assert!((area(&circle, &p) / std::f32::consts::PI - 1.0).abs() < 1e-3);
    // A pentagram turns the same way at every corner but is not convex: no fan.
    let star: Vec<Vec3> = (0..5)
        .map(|k| {
            let a = (k * 2) as f32 * std::f32::consts::TAU / 5.0;
            v(a.cos(), a.sin(), 0.)
        })
        .collect();
    let (p, _) = split_checked(&star, z);
    assert!(!p.is_empty());
    assert_ne!(p[0], Piece::Tri([0, 1, 2]));
    // All corners on a line: degenerate as a whole.
    let line: Vec<Vec3> = (0..6).map(|k| v(k as f32, 0., 0.)).collect();
    assert_eq!(split_checked(&line, z), (vec![], 0));
}

proptest! {
    /// Star-shaped polygons (random radii at increasing angles) split into valid pieces that
    /// cover exactly their area.
    #[test]
    fn star_shaped_polygons_split_exactly(
        radii in prop::collection::vec(0.2f32..2.0, 5..40),
        tilt in 0.0f32..3.0,
    ) {
        let n = radii.len();
        let r = Quat::from_axis_angle(v(0.3, 1., 0.2).normalize(), tilt);
        let pts: Vec<Vec3> = radii
            .iter()
            .enumerate()
            .map(|(k, &rad)| {
                let a = k as f32 * std::f32::consts::TAU / n as f32;
                r * v(rad * a.cos(), rad * a.sin(), 0.)
            })
            .collect();
        let mut expected = 0.0;
        for k in 0..n {
            let (a, b) = (pts[k], pts[(k + 1) % n]);
            expected += 0.5 * a.cross(b).length();
        }
        let (p, _) = split_checked(&pts, r * Vec3::Z);
        prop_assert!((area(&pts, &p) / expected - 1.0).abs() < 1e-3);
    }

    /// Any points: splitting never panics and every piece it returns is valid.
    #[test]
    fn arbitrary_polygons_give_valid_pieces(
        pts in prop::collection::vec((-4i8..4, -4i8..4, -1i8..2), 3..30),
    ) {
        let pts: Vec<Vec3> = pts
            .iter()
            .map(|&(x, y, z)| v(f32::from(x), f32::from(y), f32::from(z) * 0.1))
            .collect();
        let mut out = Vec::new();
        let _ = split(&pts, &mut out);
        for p in &out {
            let c: Vec<Vec3> = p.corners().iter().map(|&k| pts[k]).collect();
            prop_assert!(polygon_shape(&c).is_ok());
        }
    }
}

/// A comb: a straight bottom edge and a saw-tooth top with `teeth` teeth, as OBJ text with
/// one face. Area `1.5 teeth - 0.5`.
fn comb(teeth: usize) -> String {
    let mut obj = format!("v 0 0 0\nv {teeth} 0 0\n");
    for k in (0..teeth).rev() {
        obj.push_str(&format!("v {} 2 0\nv {}.5 1 0\n", k + 1, k));
    }
    obj.push('f');
    for k in 1..=2 + 2 * teeth {
        obj.push_str(&format!(" {k}"));
    }
    obj.push('\n');
    obj
}

#[test]
fn large_concave_faces_are_clipped_up_to_the_limit() {
    let r = import_str(&comb(1000)).unwrap();
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    let c = &r.scene.root;
    assert!(c.polygons.len() <= 2000);
    let total: f32 = c
        .polygons
        .iter()
        .map(|p| {
            let k: Vec<Vec3> = p.corners[..3]
                .iter()
                .map(|&i| c.vertices[i as usize])
                .collect();
            polygon_shape(&k).unwrap().area
        })
        .sum();
    assert!((total / 1499.5 - 1.0).abs() < 1e-5, "{total}");

    let teeth = MAX_CLIPPED_CORNERS / 2;
    let ((_, l, c), m) = fails(&comb(teeth), &[]);
    assert_eq!((l, c), (2 * teeth as u32 + 3, 1));
    assert!(m.contains("not convex and planar"), "{m}");
}

#[test]
fn straight_runs_do_not_count_as_corners() {
    // A rectangle with 3000 corners on each long side.
    let n = 3000;
    let mut obj = String::new();
    for k in 0..n {
        obj.push_str(&format!("v {k} 0 0\n"));
    }
    for k in (0..n).rev() {
        obj.push_str(&format!("v {k} 1 0\n"));
    }
    obj.push('f');
    for k in 1..=2 * n {
        obj.push_str(&format!(" {k}"));
    }
    obj.push('\n');
    let r = import_str(&obj).unwrap();
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    assert_eq!(r.scene.root.polygons.len(), 1);
    assert_eq!(r.scene.root.vertices.len(), 4);
}
