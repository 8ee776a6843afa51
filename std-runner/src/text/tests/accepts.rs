//! What the parser builds from valid documents.

use super::{doc, ok};
use crate::scene::{compile, read_image};
use glam::{Quat, Vec3};
use hirad_core::limits::NONE;

#[test]
fn minimal_scene() {
    let s = ok(&doc(
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nquad white 0 1 2 3",
    ));
    assert_eq!(s.bands, 3);
    assert!(s.band_names.is_empty());
    assert_eq!(s.materials.len(), 2);
    assert_eq!(s.materials[1].data.emit_front[..3], [10.0; 3]);
    assert!(!s.materials[0].data.two_sided);
    assert_eq!(s.root.vertices.len(), 4);
    assert_eq!(s.root.polygons[0].corners, [0, 1, 2, 3]);
    assert_eq!(s.root.polygons[0].material, 0);
    compile(&s).unwrap();
}

#[test]
fn forward_references_resolve() {
    let src = "hirad 1 bands 1
        scene { instance thing exact translate 1 2 3
                tri late 0 1 2 v 0 0 0 v 1 0 0 v 0 1 0 }
        original thing { tri early 0 0 0 1 0 0 0 1 0 }
        material late rho 0.5
        material early rho 0.25";
    let s = ok(src);
    // Materials are numbered in definition order, not order of use.
    assert_eq!(s.root.polygons[0].material, 0);
    assert_eq!(s.originals[0].root.polygons[0].material, 1);
    let inst = s.root.children[0].instance.unwrap();
    assert_eq!(inst.original, 0);
    assert!(inst.exact);
    assert_eq!(inst.transform.translation, Vec3::new(1., 2., 3.));
    // Inline corners become vertices.
    assert_eq!(s.originals[0].root.vertices.len(), 3);
    assert_eq!(s.originals[0].root.polygons[0].corners, [0, 1, 2, NONE]);
    let info = *read_image(&compile(&s).unwrap()).unwrap().info();
    assert_eq!(info.expanded_polygons, 2);
    assert_eq!(info.instancing_depth, 1);
}

#[test]
fn inline_corners_interleave_with_vertices() {
    let s = ok(&doc(
        "v 5 5 5\ntri white 0 0 0 1 0 0 0 1 0\nv 6 6 6\ntri white 1 2 3",
    ));
    assert_eq!(s.root.vertices.len(), 5);
    assert_eq!(s.root.vertices[4], Vec3::splat(6.0));
    assert_eq!(s.root.polygons[0].corners, [1, 2, 3, NONE]);
}

#[test]
fn band_names_and_two_sided_defaults() {
    let s = ok("hirad 1\nbands par \"near infrared\"\n\
        material leaf rho 0.1 0.45 tau 0.05 0.45\n\
        material glow rho 0.1 0.2 back_emit 1 2\n\
        scene { tri leaf 0 0 0 1 0 0 0 1 0 }");
    assert_eq!(s.band_names, ["par", "near infrared"]);
    let leaf = &s.materials[0].data;
    assert!(leaf.two_sided);
    assert_eq!(leaf.rho_back[..2], [0.1, 0.45]);
    assert_eq!(leaf.tau[..2], [0.05, 0.45]);
    let glow = &s.materials[1].data;
    assert!(glow.two_sided);
    assert_eq!(glow.emit_back[..2], [1.0, 2.0]);
    assert_eq!(glow.tau[..2], [0.0, 0.0]);
}

#[test]
fn quaternions_kept_as_written_or_normalised() {
    let src =
        |q: &str| format!("hirad 1 bands 1 original o {{ }} scene {{ instance o exact {q} }}");
    // Within tolerance of unit length: stored bit for bit.
    let s = ok(&src("quat 0.70710677 0 0 0.70710677"));
    let r = s.root.children[0].instance.unwrap().transform.rotation;
    assert_eq!(r.to_array(), [0.0, 0.0, 0.70710677, 0.70710677]);
    // Far from unit: normalised.
    let s = ok(&src("quat 2 0 0 0"));
    let r = s.root.children[0].instance.unwrap().transform.rotation;
    assert_eq!(r, Quat::IDENTITY);
    // Rotations compose in written order: the later one is applied after the earlier.
    let s = ok(&src("rotate 0 0 1 90 rotate 1 0 0 90"));
    let r = s.root.children[0].instance.unwrap().transform.rotation;
    let expected =
        Quat::from_rotation_x(90f32.to_radians()) * Quat::from_rotation_z(90f32.to_radians());
    assert!(r.abs_diff_eq(expected, 1e-6), "{r:?}");
    // x -> y (about z), then y -> z (about x).
    assert!((r * Vec3::X).abs_diff_eq(Vec3::Z, 1e-6));
    let s = ok(&src("scale 2.5 translate 1 0 0"));
    let t = s.root.children[0].instance.unwrap().transform;
    assert_eq!(t.point(Vec3::X), Vec3::new(3.5, 0., 0.));
}

#[test]
fn lights_cameras_and_attributes() {
    let s = ok("hirad 1 bands 2
        sun from 0 0 2 irradiance 800 700
        sky irradiance 1 2 from 0.6 0 0.8
        camera main fovy 40 up 0 0 1 target 0 0 0 pos 0 -5 1
        camera pos 1 1 1 target 0 0 0 up 0 0 1 fovy 30
        original twig name twig-root axis 2 age 1.5 { }
        scene root axis 0 age 10 { cluster branch axis 1 age 2 { } cluster { } }");
    assert_eq!(s.suns[0].towards, Vec3::Z);
    assert_eq!(s.suns[0].irradiance[..3], [800.0, 700.0, 0.0]);
    assert_eq!(s.sky[0].towards, Vec3::new(0.6, 0.0, 0.8));
    assert_eq!(s.cameras[0].name.as_deref(), Some("main"));
    assert_eq!(s.cameras[0].fovy_deg, 40.0);
    assert_eq!(s.cameras[1].name, None);
    let o = &s.originals[0].root;
    assert_eq!(
        (o.name.as_deref(), o.axis, o.age),
        (Some("twig-root"), Some(2), Some(1.5))
    );
    assert_eq!(
        (s.root.name.as_deref(), s.root.axis, s.root.age),
        (Some("root"), Some(0), Some(10.0))
    );
    let b = &s.root.children[0];
    assert_eq!(
        (b.name.as_deref(), b.axis, b.age),
        (Some("branch"), Some(1), Some(2.0))
    );
    assert_eq!(s.root.children[1].name, None);
}

#[test]
fn comments_strings_and_number_forms() {
    let src = "\u{feff}# a comment\nhirad 1 # trailing\nbands 1#tight\n\
        material \"rho\" rho .5e0 # a keyword as a quoted name\n\
        material \"odd \\\"name\\\"\\\\\\n\\t\\r\\u{1F600}\" rho +0.25\n\
        scene{v -0 0 0 v 1e0 0. 0 v 0 1E+0 -0.0 tri \"rho\" 0 1 2}";
    let s = ok(src);
    assert_eq!(s.materials[0].name, "rho");
    assert_eq!(s.materials[0].data.rho_front[0], 0.5);
    assert_eq!(s.materials[1].name, "odd \"name\"\\\n\t\r\u{1F600}");
    assert_eq!(s.root.vertices[0].x.to_bits(), (-0.0f32).to_bits());
    assert_eq!(s.root.vertices[2].z.to_bits(), (-0.0f32).to_bits());
}

#[test]
fn tiny_values_underflow_to_zero() {
    let s = ok(&doc("v 1e-50 0 0 v 1e9 0 0 v 0 1e9 0 tri white 0 1 2"));
    assert_eq!(s.root.vertices[0].x, 0.0);
    assert_eq!(s.root.vertices[1].x, 1e9);
}

#[test]
fn deep_but_allowed_nesting() {
    // The scene body is level 1: 63 nested clusters reach level 64.
    let body = format!("{}{}", "cluster {\n".repeat(63), "}\n".repeat(63));
    let s = ok(&doc(&body));
    compile(&s).unwrap();
}
