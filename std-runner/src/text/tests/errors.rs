//! Every class of error, with its exact line:column.

use super::{doc, err, fails_at};
use crate::text::parse;

// Lines of `doc(body)`: 1 hirad, 2 bands, 3-4 materials, 5 `scene {`, body from line 6.

#[test]
fn bad_numbers() {
    fails_at(doc("v 1 2x 3"), 6, 5, "'2x' is not a number");
    fails_at(doc("v 1 . 3"), 6, 5, "'.' is not a number");
    fails_at(doc("v 1 2 -"), 6, 7, "'-' is not a number");
    fails_at(doc("v 1 1.2.3 3"), 6, 5, "not a number");
}

#[test]
fn non_finite_numbers() {
    fails_at(doc("v 1 nan 3"), 6, 5, "'nan' is not allowed");
    fails_at(doc("v 1 NaN 3"), 6, 5, "finite");
    fails_at(doc("v inf 0 0"), 6, 3, "'inf' is not allowed");
    fails_at(doc("v 0 0 infinity"), 6, 7, "finite");
    fails_at(doc("v 1 -inf 0"), 6, 5, "'-inf' is not allowed");
    fails_at(doc("v 1 +Infinity 0"), 6, 5, "finite");
    fails_at(doc("v 1 -nan 0"), 6, 5, "finite");
    fails_at(
        doc("v 1 1e39 0"),
        6,
        5,
        "'1e39' is too large for a 32-bit float",
    );
    fails_at(doc("v 1 -3.5e38 0"), 6, 5, "too large");
}

#[test]
fn wrong_value_counts() {
    fails_at(
        doc("v 1 2"),
        6,
        1,
        "expected 3 numbers after 'v' (x y z), found 2",
    );
    fails_at(doc("v 1 2 3 4"), 6, 1, "found 4");
    fails_at(
        "hirad 1\nbands 3\nmaterial m rho 0.1 0.2 emit 1 1 1\nscene {}",
        3,
        12,
        "expected 3 numbers after 'rho' (the scene has 3 bands), found 2",
    );
    fails_at(
        "hirad 1\nbands 1\nmaterial m rho 0.1 tau\nscene {}",
        3,
        20,
        "expected 1 number after 'tau' (the scene has 1 band), found 0",
    );
    fails_at(
        "hirad 1\nbands par nir\nsun from 0 0 1 irradiance 1 2 3\nscene {}",
        3,
        16,
        "expected 2 numbers after 'irradiance' (the scene has 2 bands), found 3",
    );
    fails_at(
        doc("tri white 0 1"),
        6,
        1,
        "expected 3 vertex indices or 9 corner coordinates after 'tri white', found 2 numbers",
    );
    fails_at(doc("quad white 0 1 2 3 4"), 6, 1, "4 vertex indices or 12");
    fails_at(
        doc("v 0 0 0\ntri white 0 1.5 2"),
        7,
        13,
        "vertex index (a whole number",
    );
    fails_at(doc("tri white 0 1 99999999999"), 6, 15, "too large");
}

#[test]
fn unknown_and_duplicate_names() {
    fails_at(
        doc("tri wood 0 0 0 1 0 0 0 1 0"),
        6,
        5,
        "unknown material 'wood'",
    );
    fails_at(
        doc("instance chair exact"),
        6,
        10,
        "unknown original 'chair'",
    );
    // The earliest unknown use is reported, whichever kind it is.
    fails_at(
        doc("instance chair exact\ntri wood 0 0 0 1 0 0 0 1 0"),
        6,
        10,
        "unknown original",
    );
    fails_at(
        "hirad 1\nbands 1\nmaterial a rho 0\nmaterial a rho 1\nscene {}",
        4,
        10,
        "material 'a' is already defined (at line 3, column 10)",
    );
    fails_at(
        "hirad 1\nbands 1\noriginal o {}\nscene {}\noriginal \"o\" {}",
        5,
        10,
        "original 'o' is already defined",
    );
}

#[test]
fn cycles_of_originals() {
    let src = "hirad 1 bands 1
original a {
  instance b exact
}
original b {
  cluster { instance a exact }
}
scene { instance a exact }";
    fails_at(src, 6, 13, "cycle of originals: a -> b -> a");
    fails_at(
        "hirad 1 bands 1\noriginal self { instance self approx { } }\nscene {}",
        2,
        17,
        "self -> self",
    );
}

#[test]
fn nesting_limits() {
    // 10,000 nested clusters: refused at the one that would be level 65, no stack overflow.
    let deep = format!("{}{}", "cluster {\n".repeat(10_000), "}\n".repeat(10_000));
    fails_at(doc(&deep), 6 + 63, 1, "nested deeper than 64 levels");
    // The same with approximate instances, unclosed.
    let deep = format!(
        "hirad 1 bands 1 original o {{}}\nscene {{\n{}",
        "instance o approx {\n".repeat(10_000)
    );
    fails_at(deep, 2 + 64, 1, "nested deeper than 64 levels");
    // Instancing depth through chains of exact instances: o_k instances o_(k-1), so o_k
    // has depth k; o65 is one too deep.
    let mut src = String::from(
        "hirad 1\nbands 1\nmaterial m rho 0\noriginal o0 { tri m 0 0 0 1 0 0 0 1 0 }\n",
    );
    for k in 1..=70 {
        src += &format!("original o{k} {{ instance o{} exact }}\n", k - 1);
    }
    src += "scene { instance o70 exact }\n";
    // o65 is on line 4 + 65.
    fails_at(&src, 69, 16, "instances are nested deeper than 64 levels");
    // Two instances per level: 2^64 polygons overflow at the second instance of o64.
    let mut src = String::from(
        "hirad 1\nbands 1\nmaterial m rho 0\noriginal o0 { tri m 0 0 0 1 0 0 0 1 0 }\n",
    );
    for k in 1..=64 {
        src += &format!(
            "original o{k} {{ instance o{p} exact instance o{p} exact }}\n",
            p = k - 1
        );
    }
    src += "scene { instance o64 exact }\n";
    let e = err(&src);
    assert_eq!(e.line, 68, "{e}");
    assert!(e.message.contains("more than 2^64 polygons"), "{e}");
}

#[test]
fn unterminated_input() {
    fails_at(doc("cluster a {\nv 0 0 0"), 5, 7, "never closed");
    fails_at(
        "hirad 1\nbands 1\nscene {\n  cluster {\n",
        4,
        11,
        "never closed",
    );
    fails_at(
        "hirad 1\nbands 1\nmaterial \"abc rho 0\nscene {}",
        3,
        10,
        "unterminated string",
    );
    fails_at("", 1, 1, "starts with 'hirad 1'");
    fails_at("hirad", 1, 6, "format version");
    fails_at("hirad 1\nbands 1\n", 3, 1, "no 'scene");
    fails_at("hirad 1\nscene {}", 2, 9, "no 'bands'");
    fails_at(
        "hirad 1 bands 1 material",
        1,
        25,
        "expected a material name, found the end",
    );
    fails_at("hirad 1 bands 1 scene", 1, 22, "expected '{'");
}

#[test]
fn truncated_documents_never_panic_and_point_inside() {
    let full = "hirad 1 # v1\nbands par nir\nmaterial leaf rho 0.1 0.45 tau 0.05 0.45\n\
        material \"the soil\" rho 0.1 0.2\nsun from 0 0 1 irradiance 800 700\n\
        camera c pos 0 -5 1 target 0 0 0 up 0 0 1 fovy 40\n\
        original twig axis 2 { v 0 0 0 v 1 0 0 v 1 1 0 v 0 1 0 quad leaf 0 1 2 3 }\n\
        scene { quad \"the soil\" -5 -5 0 5 -5 0 5 5 0 -5 5 0\n\
        instance twig exact translate 0 0 1 quat 1 0 0 0 scale 2\n\
        instance twig approx name a { tri leaf 0 0 0 1 0 0 0 1 0 }\n\
        cluster x { }\n}\n";
    parse(full.as_bytes()).unwrap();
    let lines = full.lines().count() as u32;
    for cut in 0..full.len() {
        let Some(prefix) = full.get(..cut) else {
            continue;
        };
        match parse(prefix.as_bytes()) {
            Ok(_) => assert!(prefix.trim_end().ends_with('}'), "{prefix}"),
            Err(e) => {
                assert!(e.line >= 1 && e.line <= lines + 1, "{e} for {prefix:?}");
                assert!(e.column >= 1);
            }
        }
    }
}

#[test]
fn bad_utf8() {
    fails_at(
        b"hirad 1\nbands 1\n# caf\xc3\x28\n".as_slice(),
        3,
        6,
        "not valid UTF-8",
    );
    fails_at(
        b"hirad 1 \"\xc3\xa9\xff\"".as_slice(),
        1,
        11,
        "not valid UTF-8",
    );
    fails_at(b"\xff".as_slice(), 1, 1, "UTF-8");
    // A byte-order mark takes no column.
    fails_at("\u{feff}hirad 2", 1, 7, "version 2");
    fails_at(b"\xef\xbb\xbfhi\xff".as_slice(), 1, 3, "UTF-8");
}

#[test]
fn bad_shapes() {
    fails_at(
        doc("tri white 0 0 0 1 0 0 2 0 0"),
        6,
        1,
        "this triangle has no area",
    );
    fails_at(
        doc("v 0 0 0\n  quad white 0 0 0 1 0 0 1 1 0.5 0 1 0"),
        7,
        3,
        "not planar; split it into two triangles",
    );
    fails_at(
        doc("quad white 0 0 0 2 0 0 0.5 0.5 0 0 2 0"),
        6,
        1,
        "not strictly convex",
    );
    fails_at(
        doc("quad white 0 0 0 1 1 0 1 0 0 0 1 0"),
        6,
        1,
        "this quad has no area",
    );
    fails_at(
        doc("tri white -3e38 0 0 3e38 0 0 0 3e38 0"),
        6,
        1,
        "too large",
    );
}

#[test]
fn polygons_too_small_for_f32_at_their_position() {
    // 1e-30 m at (1, 1, 1): the corners round to one point.
    fails_at(
        doc(
            "v 0 0 0\n  tri white 1 1 1  1.000000000000000000000000000001 1 1  1 1.000000000000000000000000000001 1",
        ),
        7,
        3,
        "this triangle is too small for 32-bit floats at its position: its corners round to \
         one point at its largest corner coordinate, 1 m, where 32-bit floats are 1.192e-7 m \
         apart; move the scene nearer the origin",
    );
    // 1e-30 m at the origin: distinct corners, but the area (5e-61 m^2) underflows.
    fails_at(
        doc("tri white 0 0 0 1e-30 0 0 0 1e-30 0"),
        6,
        1,
        "this triangle is too small for 32-bit floats at its position: its area, 5e-61 m^2, \
         is below the smallest normal 32-bit float, 1.175e-38 m^2",
    );
    // 1 mm at 1e6 m, where f32 coordinates are 0.0625 m apart.
    fails_at(
        doc("v 1e6 1e6 0\nv 1000000.001 1e6 0\nv 1e6 1000000.001 0\ntri white 0 1 2"),
        9,
        1,
        "its corners round to one point at its largest corner coordinate, 1e6 m, where \
         32-bit floats are 0.0625 m apart",
    );
    fails_at(
        doc("tri white 1e6 0 0  1000000.25 0 0  1e6 0.25 0"),
        6,
        1,
        "its longest edge, 0.3536 m, is less than 2^-20 (about 1e-6) of its largest corner \
         coordinate, 1e6 m",
    );
    // Inside an approximate instance's body too (its own frame).
    let src = "hirad 1\nbands 1\nmaterial m rho 0.5\noriginal o {\n  tri m 0 0 0 1 0 0 0 1 0\n}\n\
               scene {\n  instance o approx {\n    tri m 1e6 0 0 1000000.001 0 0 1e6 0.001 0\n  }\n}\n";
    fails_at(src, 9, 5, "too small for 32-bit floats");
    // Accepted: 1 um near the origin, 1 m at 1e6 m.
    let s = super::ok(&doc(
        "tri white 1e-3 2e-3 0  1.001e-3 2e-3 0  1e-3 2.001e-3 0",
    ));
    assert_eq!(s.root.polygons.len(), 1);
    let s = super::ok(&doc("tri white 1e6 1e6 0  1000001 1e6 0  1e6 1000001 0"));
    assert_eq!(s.root.polygons.len(), 1);
}

#[test]
fn vertex_indices_out_of_range() {
    fails_at(
        doc("v 0 0 0\nv 1 0 0\nv 0 1 0\ntri white 0 1 3"),
        9,
        15,
        "vertex index 3 is out of range: this body has 3 vertices, 0 to 2",
    );
    // Vertices of the parent body do not count inside a cluster.
    fails_at(
        doc("v 0 0 0\nv 1 0 0\nv 0 1 0\ncluster { tri white 0 1 2 }"),
        9,
        21,
        "this body has no vertices",
    );
}

#[test]
fn instances() {
    let base = "hirad 1\nbands 1\noriginal o {}\nscene {\n";
    fails_at(
        format!("{base}instance o exact {{ }}\n}}"),
        5,
        18,
        "exact instance",
    );
    fails_at(format!("{base}instance o approx\n}}"), 6, 1, "expected '{'");
    fails_at(
        format!("{base}instance o\n}}"),
        6,
        1,
        "expected 'exact' or 'approx'",
    );
    fails_at(
        format!("{base}instance o exact scale 0\n}}"),
        5,
        24,
        "scale must be a positive",
    );
    fails_at(
        format!("{base}instance o exact scale -1\n}}"),
        5,
        24,
        "positive",
    );
    fails_at(
        format!("{base}instance o exact scale 1e-40\n}}"),
        5,
        24,
        "positive",
    );
    fails_at(
        format!("{base}instance o exact rotate 0 0 0 30\n}}"),
        5,
        18,
        "axis must not be zero",
    );
    fails_at(
        format!("{base}instance o exact quat 0 0 0 0\n}}"),
        5,
        18,
        "must not be zero",
    );
    fails_at(
        format!("{base}instance o exact quat 1 0 0\n}}"),
        5,
        18,
        "expected 4 numbers after 'quat' (w x y z)",
    );
    fails_at(
        format!("{base}instance o exact translate 1 2 3 translate 1 2 3\n}}"),
        5,
        34,
        "'translate' is given twice",
    );
    fails_at(
        format!("{base}instance o exact axis 4294967295\n}}"),
        5,
        23,
        "reserved",
    );
    fails_at(
        format!("{base}instance o exact axis -1\n}}"),
        5,
        23,
        "whole number",
    );
    fails_at(
        format!("{base}instance o exact age -1\n}}"),
        5,
        22,
        "age must be >= 0",
    );
    fails_at(
        format!("{base}instance rho exact\n}}"),
        5,
        10,
        "keyword 'rho'",
    );
}

#[test]
fn materials_checked_at_the_value() {
    let m = |s: &str| format!("hirad 1\nbands 2\nmaterial m {s}\nscene {{}}");
    fails_at(
        m("rho 0.5 1.5"),
        3,
        20,
        "band 1: reflectance must lie in 0..=1",
    );
    fails_at(m("rho 0.5 0.5 back_rho -0.1 0"), 3, 33, "reflectance");
    fails_at(m("rho 0.5 0.5 tau 0.2 0.6"), 3, 32, "exceeds 1");
    fails_at(
        m("rho 0.5 0.5 tau 1.2 0"),
        3,
        28,
        "transmittance must lie in 0..=1",
    );
    fails_at(
        m("rho 0 0 emit 1 -1"),
        3,
        27,
        "emitted exitance must be >= 0",
    );
    fails_at(m("emit 1 1"), 3, 1, "needs 'rho'");
    fails_at(m("rho 0 0 rho 0 0"), 3, 20, "'rho' is given twice");
    fails_at(
        "hirad 1\nmaterial m rho 0\nbands 1\nscene {}",
        2,
        1,
        "'bands' must come before the first material",
    );
    fails_at(
        "hirad 1\nbands 1\nbands 1\nscene {}",
        3,
        1,
        "only be given once",
    );
    fails_at("hirad 1\nbands 0\nscene {}", 2, 7, "1 to 8 bands");
    fails_at("hirad 1\nbands 9\nscene {}", 2, 7, "1 to 8 bands");
    fails_at(
        "hirad 1\nbands a b c d e f g h i\nscene {}",
        2,
        23,
        "too many band names",
    );
    fails_at(
        "hirad 1\nbands {\nscene {}",
        2,
        7,
        "expected the number of bands or their names",
    );
}

#[test]
fn lights_and_cameras() {
    let head = "hirad 1\nbands 1\n";
    fails_at(
        format!("{head}sun from 0 0 0 irradiance 1\nscene {{}}"),
        3,
        5,
        "must not be zero",
    );
    fails_at(
        format!("{head}sky from 0 0 1 irradiance -1\nscene {{}}"),
        3,
        27,
        "irradiance must be >= 0",
    );
    fails_at(
        format!("{head}sun from 0 0 1\nscene {{}}"),
        4,
        1,
        "expected 'irradiance'",
    );
    fails_at(
        format!("{head}camera pos 0 0 0 target 0 0 0 up 0 1 0 fovy 40\nscene {{}}"),
        3,
        1,
        "unusable camera",
    );
    fails_at(
        format!("{head}camera pos 0 0 0 target 0 0 1 up 0 0 1 fovy 40\nscene {{}}"),
        3,
        1,
        "unusable camera",
    );
    fails_at(
        format!("{head}camera pos 0 0 0 target 0 0 1 up 0 1 0 fovy 180\nscene {{}}"),
        3,
        1,
        "0 < fovy < 180",
    );
    fails_at(
        format!("{head}camera pos 0 0 0 target 0 0 1 up 0 1 0\nscene {{}}"),
        4,
        1,
        "expected 'fovy'",
    );
}

#[test]
fn lexical_errors() {
    fails_at(doc("v 0 0 0 @"), 6, 9, "unexpected character '@'");
    fails_at(doc("cluster \"a\\qb\" {}"), 6, 11, "unknown escape");
    fails_at(
        doc("cluster \"a\\u{d800}\" {}"),
        6,
        11,
        "not a Unicode scalar value",
    );
    fails_at(doc("cluster \"a\\u{}\" {}"), 6, 11, "malformed");
    let long = "x".repeat(1025);
    fails_at(
        doc(&format!("cluster {long} {{}}")),
        6,
        9,
        "at most 1024 bytes",
    );
    parse(doc(&format!("cluster {} {{}}", "x".repeat(1024))).as_bytes()).unwrap();
    fails_at("hirad 2\n", 1, 7, "version 2 is not supported");
    fails_at("hirad 1 hirad 1", 1, 9, "only appear once");
    fails_at("bands 1", 1, 1, "starts with 'hirad 1'");
    fails_at(
        "hirad 1 bands 1 scene {} scene {}",
        1,
        26,
        "only be given once",
    );
    fails_at("hirad 1 bands 1 { }", 1, 17, "expected a statement");
    fails_at(doc("v 0 0 0 }"), 7, 1, "expected a statement");
    fails_at(
        doc("foo"),
        6,
        1,
        "expected v, tri, quad, cluster, instance or '}'",
    );
}
