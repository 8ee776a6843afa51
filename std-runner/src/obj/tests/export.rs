//! The writer: world vertices in global-id order, bands, names, refusals, reading back.

use super::*;

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
    let e = export(s, Up::Y, "out.mtl", &mut obj, &mut mtl).unwrap();
    (
        String::from_utf8(obj).unwrap(),
        String::from_utf8(mtl).unwrap(),
        e,
    )
}

/// A z-up scene is written y up (OBJ's convention) by a rotation: (x, y, z) -> (x, z, -y),
/// without negative zeros, said in the header; faces keep their corner order (a rotation
/// keeps which side is the front).
#[test]
fn export_writes_a_z_up_scene_y_up() {
    let s = export_scene();
    let (mut obj, mut mtl) = (Vec::new(), Vec::new());
    export(&s, Up::Z, "out.mtl", &mut obj, &mut mtl).unwrap();
    let obj = String::from_utf8(obj).unwrap();
    let (y_up, _, _) = export_strings(&s);
    assert!(
        obj.contains("# The scene's +z axis is written as +y"),
        "{obj}"
    );
    assert!(!obj.contains("-0 ") && !obj.contains("-0\n"), "{obj}");
    let vertices = |t: &str| -> Vec<[f32; 3]> {
        t.lines()
            .filter_map(|l| l.strip_prefix("v "))
            .map(|l| {
                let v: Vec<f32> = l.split(' ').map(|x| x.parse().unwrap()).collect();
                [v[0], v[1], v[2]]
            })
            .collect()
    };
    let (rotated, plain) = (vertices(&obj), vertices(&y_up));
    assert_eq!(rotated.len(), plain.len());
    for (r, p) in rotated.iter().zip(&plain) {
        assert_eq!(*r, [p[0], p[2], 0.0 - p[1]]);
    }
    let faces = |t: &str| -> Vec<String> {
        t.lines()
            .filter(|l| l.starts_with("f "))
            .map(String::from)
            .collect()
    };
    assert_eq!(faces(&obj), faces(&y_up));
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
    let err = export(&s, Up::Y, "x.mtl", &mut Vec::new(), &mut Vec::new()).unwrap_err();
    assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
    let s = export_scene();
    let err = export(&s, Up::Y, "a#b.mtl", &mut Vec::new(), &mut Vec::new()).unwrap_err();
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
