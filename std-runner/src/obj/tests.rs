//! Unit tests of the OBJ/MTL reader and writer: lexing, numbers, face splitting, statements,
//! materials, located errors, warnings and the writer's output.

use super::lex::{Lexer, Line, Pos};
use super::number::{parse_f32, resolve_index};
use super::split::{Piece, split};
use super::*;
use crate::scene::{Cluster, InstanceOf, Material, MaterialData, Similarity, quad, triangle};
use glam::{Quat, Vec3};
use hirad_core::geometry::polygon_shape;
use proptest::prelude::*;

fn v(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(x, y, z)
}

/// Imports `obj` with the MTL files `mtls` (name, text).
fn import_with(obj: &str, mtls: &[(&str, &str)]) -> Result<ObjImport, ObjError> {
    let mut load = |name: &str| -> Result<Vec<u8>, String> {
        mtls.iter()
            .find(|(n, _)| *n == name)
            .map(|(_, t)| t.as_bytes().to_vec())
            .ok_or_else(|| "no such file".to_string())
    };
    import(obj.as_bytes(), &mut load)
}

fn import_str(obj: &str) -> Result<ObjImport, ObjError> {
    import_with(obj, &[])
}

/// The error of an import that must fail, as `(file, line, column)`, and its message.
fn fails(obj: &str, mtls: &[(&str, &str)]) -> ((String, u32, u32), String) {
    match import_with(obj, mtls) {
        Ok(_) => panic!("import of {obj:?} should fail"),
        Err(e) => ((e.file, e.line, e.column), e.message),
    }
}

fn lines(src: &str) -> Vec<Vec<(String, u32, u32)>> {
    let mut lexer = Lexer::new(src.as_bytes());
    let mut line = Line::default();
    let mut out = Vec::new();
    while lexer.next_line(&mut line) {
        out.push(
            (0..line.len())
                .map(|i| {
                    let Pos { line: l, col } = line.pos(i);
                    (line.tok(i).to_string(), l, col)
                })
                .collect(),
        );
    }
    out
}

fn t(s: &str, line: u32, col: u32) -> (String, u32, u32) {
    (s.to_string(), line, col)
}

#[test]
fn lexer_locates_tokens_across_crlf_comments_and_continuations() {
    let src = "v 1 2 3\r\n# comment\r\n  f 1\t2 \\\r\n 3 # tail \\\nvt é 0\n\n";
    assert_eq!(
        lines(src),
        vec![
            vec![t("v", 1, 1), t("1", 1, 3), t("2", 1, 5), t("3", 1, 7)],
            vec![t("f", 3, 3), t("1", 3, 5), t("2", 3, 7), t("3", 4, 2)],
            vec![t("vt", 5, 1), t("é", 5, 4), t("0", 5, 6)],
        ]
    );
    // A backslash on the last line, and no final newline.
    assert_eq!(lines("f 1 \\"), vec![vec![t("f", 1, 1), t("1", 1, 3)]]);
    assert!(lines("").is_empty());
    assert!(lines("\n\r\n# x\n").is_empty());
}

#[test]
fn lexer_replaces_invalid_utf8() {
    let mut lexer = Lexer::new(b"o caf\xe9 bar\nv 0 0 0\n");
    let mut line = Line::default();
    assert!(lexer.next_line(&mut line));
    assert!(line.invalid_utf8);
    assert_eq!(line.tok(1), "caf\u{fffd}");
    assert_eq!(line.pos(2), Pos { line: 1, col: 8 });
    assert!(lexer.next_line(&mut line));
    assert!(!line.invalid_utf8);
}

#[test]
fn numbers() {
    assert_eq!(parse_f32("1.5"), Ok(1.5));
    assert_eq!(parse_f32("-2e-3"), Ok(-2e-3));
    assert_eq!(parse_f32("+.5"), Ok(0.5));
    assert_eq!(parse_f32("1e-50"), Ok(0.0));
    for bad in ["nan", "NaN", "inf", "-infinity"] {
        assert!(
            parse_f32(bad).unwrap_err().contains("not a finite number"),
            "{bad}"
        );
    }
    assert!(parse_f32("1e39").unwrap_err().contains("too large"));
    assert!(parse_f32("1,5").unwrap_err().contains("expected a number"));

    assert_eq!(resolve_index("1", "vertex", 3), Ok(0));
    assert_eq!(resolve_index("3", "vertex", 3), Ok(2));
    assert_eq!(resolve_index("-1", "vertex", 3), Ok(2));
    assert_eq!(resolve_index("-3", "vertex", 3), Ok(0));
    assert!(
        resolve_index("0", "vertex", 3)
            .unwrap_err()
            .contains("index 0")
    );
    assert!(
        resolve_index("4", "vertex", 3)
            .unwrap_err()
            .contains("out of range")
    );
    assert!(
        resolve_index("-4", "vertex", 3)
            .unwrap_err()
            .contains("out of range")
    );
    let huge = resolve_index("99999999999999999999999", "vertex", 3).unwrap_err();
    assert!(huge.contains("out of range"), "{huge}");
    assert!(
        resolve_index("x", "vertex", 3)
            .unwrap_err()
            .contains("expected")
    );
    assert!(
        resolve_index("-", "vertex", 3)
            .unwrap_err()
            .contains("expected")
    );
    assert!(
        resolve_index("", "normal", 3)
            .unwrap_err()
            .contains("missing normal")
    );
}

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

#[test]
fn clusters_follow_o_and_g_in_file_order() {
    let obj = "\
v 0 0 0
v 1 0 0
v 0 1 0
v 1 1 0
f 1 2 3
o chair
f 2 4 3
g seat cushion
f 1 2 3
f 2 4 3
g
g back
f 4 3 2
o empty
g nothing
o chair
g seat cushion
f 3 1 2
g top
f 3 2 1
";
    let s = import_str(obj).unwrap().scene;
    let root = &s.root;
    assert_eq!(root.name, None);
    assert_eq!(root.polygons.len(), 1);
    let names = |c: &Cluster| -> Vec<Option<String>> {
        c.children.iter().map(|k| k.name.clone()).collect()
    };
    assert_eq!(names(root), [Some("chair".into()), Some("chair".into())]);
    let first = &root.children[0];
    assert_eq!(first.polygons.len(), 1);
    assert_eq!(
        names(first),
        [Some("seat cushion".into()), Some("back".into())]
    );
    assert_eq!(first.children[0].polygons.len(), 2);
    // Local vertices in first-use order: 1 2 3, then 4.
    assert_eq!(
        first.children[0].vertices,
        [v(0., 0., 0.), v(1., 0., 0.), v(0., 1., 0.), v(1., 1., 0.)]
    );
    assert_eq!(first.children[0].polygons[1].corners, [1, 3, 2, u32::MAX]);
    let second = &root.children[1];
    assert!(second.polygons.is_empty());
    assert_eq!(
        names(second),
        [Some("seat cushion".into()), Some("top".into())]
    );
    // `g` before any `o` is a child of the root.
    let s = import_str("v 0 0 0\nv 1 0 0\nv 0 1 0\ng a\nf 1 2 3\no b\nf 1 2 3\n")
        .unwrap()
        .scene;
    assert_eq!(s.root.children.len(), 2);
    assert!(s.root.children.iter().all(|c| c.children.is_empty()));
}

#[test]
fn default_material_and_face_bookkeeping() {
    let obj = "\
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 2 0 0
f 1 2 3 4
f 1 2 2 3 3
f 1 1 2
f 1 2 5
l 1 2
l 2 3
p 1
curv 0 1 1 2
surf 0 1 0 1 1 2 3 4
mg 1
xyzzy
xyzzy
s 1
f 4 3 2 1
";
    let r = import_str(obj).unwrap();
    assert_eq!(r.scene.bands, 3);
    assert!(r.scene.band_names.is_empty());
    assert_eq!(r.scene.materials.len(), 1);
    assert_eq!(r.scene.materials[0].name, DEFAULT_MATERIAL);
    let d = &r.scene.materials[0].data;
    assert_eq!(&d.rho_front[..3], &[0.5; 3]);
    assert!(!d.two_sided);
    assert_eq!(
        r.warnings,
        [
            "8:1: degenerate face skipped",
            "9:1: degenerate face skipped",
            "10:1: line elements (l) ignored",
            "12:1: point elements (p) ignored",
            "13:1: free-form curves and surfaces (curv, ...) ignored",
            "15:1: statement 'mg' ignored",
            "16:1: statement 'xyzzy' ignored",
        ]
    );
    assert_eq!(
        r.counts,
        ObjCounts {
            vertices: 5,
            texture_coords: 0,
            normals: 0,
            faces: 5,
            polygons: 3,
            skipped_faces: 2,
        }
    );
    // `f 1 2 2 3 3` loses its repeated corners and is a triangle.
    assert_eq!(r.scene.root.polygons[1].corners, [0, 1, 2, u32::MAX]);
    crate::scene::compile(&r.scene).unwrap();
}

const MTL: &str = "\
# test materials
newmtl white
Ka 1 1 1
Kd 0.8
Ks 0.5 0.5 0.5
Ns 96
illum 2
map_Kd white.png

newmtl lamp
Kd 0 0 0
Ke 20 15 10
newmtl leaf
Kd 0.1 0.4 0.1
Tf 0.05 0.4 0.05
newmtl max default
Kd 0.5 0.5 0.5
Tf 1.0 1.0 1.0
newmtl bare
Ni 1.5
";

#[test]
fn mtl_statements() {
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl max default\nf 1 2 3\n";
    let r = import_with(obj, &[("m.mtl", MTL)]).unwrap();
    let m = &r.scene.materials;
    let names: Vec<&str> = m.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["white", "lamp", "leaf", "max default", "bare"]);
    assert_eq!(&m[0].data.rho_front[..3], &[0.8; 3]);
    assert!(!m[0].data.two_sided);
    assert_eq!(&m[1].data.emit_front[..3], &[20., 15., 10.]);
    let leaf = &m[2].data;
    assert!(leaf.two_sided);
    assert_eq!(&leaf.rho_back[..3], &leaf.rho_front[..3]);
    assert_eq!(&leaf.tau[..3], &[0.05, 0.4, 0.05]);
    assert!(!m[3].data.two_sided);
    assert_eq!(&m[4].data.rho_front[..3], &[0.5; 3]);
    assert_eq!(
        r.warnings,
        [
            "m.mtl:18:4: Tf 1 1 1 (what Maya and 3ds Max write for opaque materials) ignored: \
             the materials that have it are opaque",
            "m.mtl:19:8: material 'bare' has no Kd: reflectance 0.5 assumed",
        ]
    );
    assert_eq!(r.scene.root.polygons[0].material, 3);
}

#[test]
fn mtllib_lists_names_with_spaces_and_repeats() {
    let one = "newmtl a\nKd 0.1\n";
    let two = "newmtl b\nKd 0.2\nnewmtl a\nKd 0.9\n";
    let obj = "mtllib one.mtl two.mtl\nmtllib one.mtl\nmtllib my materials.mtl\n\
               v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\nusemtl c\nf 1 2 3\n";
    let spaced = "newmtl c\nKd 0.3\n";
    let r = import_with(
        obj,
        &[
            ("one.mtl", one),
            ("two.mtl", two),
            ("my materials.mtl", spaced),
        ],
    )
    .unwrap();
    let names: Vec<&str> = r.scene.materials.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["a", "b", "c"]);
    assert_eq!(r.scene.materials[0].data.rho_front[0], 0.1);
    assert_eq!(
        r.warnings,
        ["two.mtl:3:8: material 'a' is defined again; the first definition is kept"]
    );
}

#[test]
fn an_mtl_may_define_default() {
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    let r = import_with(obj, &[("m.mtl", "newmtl default\nKd 0.25\n")]).unwrap();
    assert_eq!(r.scene.materials.len(), 1);
    assert_eq!(r.scene.materials[0].data.rho_front[0], 0.25);
}

#[test]
fn located_errors() {
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    let cases: Vec<(String, (&str, u32, u32), &str)> = vec![
        (
            "mtllib missing.mtl\n".into(),
            ("", 1, 8),
            "cannot read material library 'missing.mtl': no such file",
        ),
        (
            format!("{tri}usemtl  nowhere\n"),
            ("", 4, 9),
            "unknown material 'nowhere'",
        ),
        (
            format!("{tri}f 1 0 3\n"),
            ("", 4, 5),
            "vertex index 0 is invalid",
        ),
        (
            format!("{tri}f 1 2 4\n"),
            ("", 4, 7),
            "vertex index 4 is out of range",
        ),
        (
            format!("{tri}f -1 -2 -4\n"),
            ("", 4, 9),
            "vertex index -4 is out of range",
        ),
        (
            format!("{tri}vt 0 0\nf 1/1 2/2 3/1\n"),
            ("", 5, 9),
            "texture coordinate index 2",
        ),
        (
            format!("{tri}vn 0 0 1\nf 1//1 2//1 3//-2\n"),
            ("", 5, 16),
            "normal index -2",
        ),
        (
            format!("{tri}f 1/ 2 3\n"),
            ("", 4, 5),
            "missing texture coordinate index",
        ),
        (
            format!("{tri}vt 0 0\nvn 0 0 1\nf 1/1/1/1 2 3\n"),
            ("", 6, 8),
            "a face corner is",
        ),
        (
            format!("{tri}f 1 2\n"),
            ("", 4, 1),
            "at least 3 corners, found 2",
        ),
        (
            "v 0 nan 0\n".into(),
            ("", 1, 5),
            "'nan' is not a finite number",
        ),
        ("v 0 0 -inf\n".into(), ("", 1, 7), "not a finite number"),
        ("v 1e39 0 0\n".into(), ("", 1, 3), "too large"),
        ("v 0 0\n".into(), ("", 1, 6), "v needs x y z coordinates"),
        // Truncated in the middle of statements.
        (format!("{tri}f 1 2"), ("", 4, 1), "at least 3 corners"),
        (
            format!("{tri}f 1 2 3/"),
            ("", 4, 9),
            "missing texture coordinate index",
        ),
        ("v 0 0 1.5e".into(), ("", 1, 7), "expected a number"),
        (
            format!("{tri}usemtl"),
            ("", 4, 7),
            "usemtl needs a material name",
        ),
        (
            "o ".to_string() + &"x".repeat(2000),
            ("", 1, 3),
            "longer than",
        ),
    ];
    for (obj, (file, line, col), msg) in cases {
        let ((f, l, c), m) = fails(&obj, &[]);
        assert_eq!((f.as_str(), l, c), (file, line, col), "{obj:?}: {m}");
        assert!(m.contains(msg), "{obj:?}: {m}");
    }
}

#[test]
fn located_mtl_errors() {
    let obj = "# header\nmtllib bad.mtl\n";
    let cases = [
        (
            "newmtl a\nKd 1.5 0.5 0.5\n",
            (2, 4),
            "Kd: band 0: reflectance must lie in 0..=1",
        ),
        ("newmtl a\nKd 0.5 0.5 -0.1\n", (2, 12), "reflectance"),
        ("newmtl a\nKd 0.6\nTf 0.3 0.5 0.3\n", (3, 8), "exceeds 1"),
        ("newmtl a\nTf 0.3 0.5 0.3\nKd 0.6\n", (3, 4), "exceeds 1"),
        ("newmtl a\nTf 1.5\n", (2, 4), "transmittance"),
        (
            "newmtl a\nKe 1 -1 1\n",
            (2, 6),
            "emitted exitance must be >= 0",
        ),
        ("newmtl a\nKd 0.5 0.5\n", (2, 11), "needs 1 or 3 values"),
        ("newmtl a\nKd\n", (2, 3), "needs 1 or 3 values"),
        ("newmtl a\nTf spectral leaf.rfl\n", (2, 4), "not supported"),
        ("newmtl a\nKd xyz 0.5 0.5 0.5\n", (2, 4), "not supported"),
        ("newmtl a\nKd 0.5 nan 0.5\n", (2, 8), "not a finite number"),
        ("Kd 0.5\n", (1, 1), "before any newmtl"),
        ("newmtl\n", (1, 7), "needs a material name"),
        ("newmtl a\nKd 0.5 0.", (2, 10), "needs 1 or 3 values"),
        ("newmtl a\rKd 0.5\r\n", (1, 9), "carriage return"),
    ];
    for (mtl, (line, col), msg) in cases {
        let ((f, l, c), m) = fails(obj, &[("bad.mtl", mtl)]);
        assert_eq!((f.as_str(), l, c), ("bad.mtl", line, col), "{mtl:?}: {m}");
        assert!(m.contains(msg), "{mtl:?}: {m}");
    }
}

#[test]
fn error_display_names_the_file() {
    let e = import_with("mtllib m.mtl\n", &[("m.mtl", "newmtl a\nKd 2\n")]).unwrap_err();
    assert_eq!(
        e.to_string(),
        "m.mtl:2:4: material 'a': Kd: band 0: reflectance must lie in 0..=1"
    );
    let e = import_str("f 1 2 3\n").unwrap_err();
    assert_eq!(
        e.to_string(),
        "1:3: vertex index 1 is out of range (0 defined so far)"
    );
}

#[test]
fn faces_beyond_f32_are_skipped_with_a_reason() {
    let r = import_str("v -3e38 0 0\nv 3e38 0 0\nv 0 3e38 0\nf 1 2 3\n").unwrap();
    assert_eq!(
        r.warnings,
        ["4:1: face too large to measure in 32-bit floats skipped"]
    );
}

#[test]
fn warnings_are_capped() {
    let mut obj = String::from("v 0 0 0\nv 1 0 0\n");
    for _ in 0..MAX_WARNINGS + 5 {
        obj.push_str("f 1 2 2\n");
    }
    let r = import_str(&obj).unwrap();
    assert_eq!(r.warnings.len(), MAX_WARNINGS + 1);
    assert_eq!(
        r.warnings.last().unwrap(),
        "... and 5 more warnings not shown"
    );
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

/// A scene with an instance, two materials and a two-sided one, for the writer.
fn export_scene() -> Scene {
    let mut s = Scene::new(3);
    let mut grey = MaterialData::black(3);
    grey.rho_front[..3].copy_from_slice(&[0.5, 0.25, 0.125]);
    let mut lamp = MaterialData::black(3);
    lamp.emit_front[..3].copy_from_slice(&[10., 10., 5.]);
    let mut leaf = MaterialData::black(3);
    leaf.two_sided = true;
    leaf.rho_front[..3].copy_from_slice(&[0.1, 0.4, 0.1]);
    leaf.rho_back[..3].copy_from_slice(&[0.1, 0.3, 0.1]);
    leaf.tau[..3].copy_from_slice(&[0.05, 0.4, 0.05]);
    s.materials = vec![
        Material {
            name: "grey".into(),
            data: grey,
        },
        Material {
            name: "warm lamp".into(),
            data: lamp,
        },
        Material {
            name: "leaf".into(),
            data: leaf,
        },
    ];
    let mut twig = Cluster::named("twig");
    let a = twig.vertex(v(0., 0., 0.));
    let b = twig.vertex(v(1., 0., 0.));
    let c = twig.vertex(v(1., 1., 0.));
    let d = twig.vertex(v(0., 1., 0.));
    twig.polygons = vec![quad(a, b, c, d, 2)];
    s.originals = vec![crate::scene::Original {
        name: "twig".into(),
        root: twig,
    }];
    let root = &mut s.root;
    let a = root.vertex(v(0., 0., 0.));
    let b = root.vertex(v(2., 0., 0.));
    let c = root.vertex(v(0., 2., 0.));
    root.polygons = vec![triangle(a, b, c, 0), triangle(a, c, b, 1)];
    root.children.push(Cluster {
        name: Some("tw#1".into()),
        instance: Some(InstanceOf {
            original: 0,
            exact: true,
            transform: Similarity {
                rotation: Quat::IDENTITY,
                translation: v(0., 0., 3.),
                scale: 2.0,
            },
        }),
        ..Cluster::default()
    });
    root.children.push(Cluster {
        instance: Some(InstanceOf {
            original: 0,
            exact: true,
            transform: Similarity::IDENTITY,
        }),
        ..Cluster::default()
    });
    s
}

fn export_strings(s: &Scene) -> (String, String, ObjExport) {
    let (mut obj, mut mtl) = (Vec::new(), Vec::new());
    let e = export(s, "out.mtl", &mut obj, &mut mtl).unwrap();
    (
        String::from_utf8(obj).unwrap(),
        String::from_utf8(mtl).unwrap(),
        e,
    )
}

#[test]
fn export_writes_world_vertices_in_global_id_order() {
    let (obj, mtl, e) = export_strings(&export_scene());
    assert_eq!(
        obj,
        "\
# hirad flatten: 4 polygons, 11 vertices, 3 materials
# Face k (1-based, in file order) is the polygon with global id k-1.
mtllib out.mtl
g scene
v 0 0 0
v 2 0 0
v 0 2 0
usemtl grey
f 1 2 3
usemtl warm_lamp
f 1 3 2
g scene/tw_1
v 0 0 3
v 2 0 3
v 2 2 3
v 0 2 3
usemtl leaf
f 4 5 6 7
g scene/_1
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
f 8 9 10 11
"
    );
    assert_eq!(
        mtl,
        "\
# hirad materials: Kd = front reflectance, Ke = emitted exitance
# (W/m^2), Tf = diffuse transmittance of a two-sided material (back = Kd).
# Materials: 3

newmtl grey
Kd 0.5 0.25 0.125

newmtl warm_lamp
Kd 0 0 0
Ke 10 10 5

newmtl leaf
Kd 0.1 0.4 0.1
Tf 0.05 0.4 0.05
"
    );
    assert_eq!((e.faces, e.vertices), (4, 11));
    assert_eq!(e.warnings.len(), 3, "{:?}", e.warnings);
    assert!(e.warnings[0].contains("'warm lamp' written as 'warm_lamp'"));
    assert!(e.warnings[1].contains("'leaf': its back reflectance differs"));
    assert!(e.warnings[2].contains("cluster names with '#'"));
}

/// Changes the band count of `m`, zeroing the values past it (the scene check wants that).
fn set_bands(m: &mut MaterialData, bands: u8) {
    m.bands = bands;
    for v in [
        &mut m.rho_front,
        &mut m.emit_front,
        &mut m.rho_back,
        &mut m.tau,
        &mut m.emit_back,
    ] {
        v[usize::from(bands)..].fill(0.0);
    }
}

#[test]
fn export_converts_bands_and_warns_about_what_it_loses() {
    let mut s = export_scene();
    s.bands = 2;
    s.band_names = vec!["par".into(), "nir".into()];
    for m in &mut s.materials {
        set_bands(&mut m.data, 2);
    }
    s.suns.push(crate::scene::light(Vec3::NEG_Z, &[100., 50.]));
    let (_, mtl, e) = export_strings(&s);
    assert!(mtl.contains("newmtl grey\nKd 0.5 0.25 0.25\n"), "{mtl}");
    let w = e.warnings.join("\n");
    assert!(w.contains("1 sun(s) cannot be written"), "{w}");
    assert!(w.contains("band names (par, nir)"), "{w}");
    assert!(
        w.contains(
            "2 bands and MTL colours are r g b: written as bands 1 ('par'), 2 ('nir'), 2 ('nir')"
        ),
        "{w}"
    );

    let mut s = export_scene();
    s.bands = 5;
    for m in &mut s.materials {
        set_bands(&mut m.data, 5);
    }
    let (_, mtl, e) = export_strings(&s);
    assert!(mtl.contains("newmtl grey\nKd 0.5 0.25 0.125\n"), "{mtl}");
    assert!(e.warnings.iter().any(|w| w.contains("bands 4, 5 are lost")));

    let mut s = export_scene();
    s.bands = 1;
    for m in &mut s.materials {
        set_bands(&mut m.data, 1);
    }
    let (_, mtl, _) = export_strings(&s);
    assert!(mtl.contains("newmtl grey\nKd 0.5 0.5 0.5\n"), "{mtl}");
}

#[test]
fn export_makes_material_names_unique() {
    let mut s = export_scene();
    s.materials[0].name = "warm_lamp".into();
    s.materials[2].name = "".into();
    let (obj, mtl, e) = export_strings(&s);
    assert!(mtl.contains("newmtl warm_lamp\n"));
    assert!(mtl.contains("newmtl warm_lamp_2\n"));
    assert!(mtl.contains("newmtl unnamed\n"));
    assert!(obj.contains("usemtl warm_lamp_2\n"));
    assert_eq!(
        e.warnings
            .iter()
            .filter(|w| w.contains("written as"))
            .count(),
        2
    );
}

#[test]
fn export_refuses_bad_input() {
    let mut s = export_scene();
    s.root.polygons[0].material = 9;
    let err = export(&s, "x.mtl", &mut Vec::new(), &mut Vec::new()).unwrap_err();
    assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
    let s = export_scene();
    let err = export(&s, "a#b.mtl", &mut Vec::new(), &mut Vec::new()).unwrap_err();
    assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
}

#[test]
fn exported_scene_reads_back() {
    let s = export_scene();
    let (obj, mtl, _) = export_strings(&s);
    let r = import_with(&obj, &[("out.mtl", &mtl)]).unwrap();
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    assert_eq!(r.counts.polygons, 4);
    let names: Vec<&str> = r.scene.materials.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["grey", "warm_lamp", "leaf"]);
    let leaf = &r.scene.materials[2].data;
    assert!(leaf.two_sided);
    assert_eq!(&leaf.tau[..3], &s.materials[2].data.tau[..3]);
    assert_eq!(r.scene.root.children.len(), 3);
    assert_eq!(r.scene.root.children[1].name.as_deref(), Some("scene/tw_1"));
}
