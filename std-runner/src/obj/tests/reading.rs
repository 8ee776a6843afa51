//! Statements, clusters, materials, located errors and warnings of the importer.

use super::*;

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
fn faces_too_small_for_f32_are_skipped_with_a_reason() {
    // Lines 1-3: 1 mm at 1e6 m (f32 steps 0.0625 m there); 4-6: 1 m there; 7-9: 1 um near
    // the origin; 10-12: 1e-30 m at the origin (its area underflows); 13-17: a pentagon of
    // 2 cm at 1e6 m.
    let obj = "\
v 1e6 1e6 0
v 1000000.001 1e6 0
v 1e6 1000000.001 0
v 1e6 1e6 1
v 1000001 1e6 1
v 1e6 1000001 1
v 1e-3 1e-3 0
v 1.001e-3 1e-3 0
v 1e-3 1.001e-3 0
v 0 0 0
v 1e-30 0 0
v 0 1e-30 0
v 1e6 1e6 3
v 1000000.01 1e6 3
v 1000000.01 1000000.01 3
v 1000000.005 1000000.02 3
v 1e6 1000000.01 3
f 1 2 3
f 4 5 6
f 7 8 9
f 10 11 12
f 13 14 15 16 17
";
    let r = import_str(obj).unwrap();
    assert_eq!(
        r.warnings,
        [
            "18:1: face too small for 32-bit floats at its position skipped",
            "21:1: face too small for 32-bit floats at its position skipped",
            "22:1: face too small for 32-bit floats at its position skipped",
        ]
    );
    assert_eq!(r.counts.skipped_faces, 3);
    assert_eq!(r.counts.polygons, 2);
    let areas: Vec<f32> = r
        .scene
        .root
        .polygons
        .iter()
        .map(|p| {
            let c = p
                .corners
                .map(|i| r.scene.root.vertices.get(i as usize).copied());
            polygon_shape(&[c[0].unwrap(), c[1].unwrap(), c[2].unwrap()])
                .unwrap()
                .area
        })
        .collect();
    assert_eq!(areas[0], 0.5);
    assert!((areas[1] / 0.5e-12 - 1.0).abs() < 1e-3, "{areas:?}");
    crate::scene::compile(&r.scene).unwrap();
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
