//! OBJ/MTL import on files in the styles common tools write, located errors, truncated
//! files, round trips through the exporter, and property tests: arbitrary input never panics
//! the importer, random valid meshes survive import -> export -> import.

use glam::{Quat, Vec3};
use hirad::obj::{self, ObjError, ObjImport};
use hirad::scene::{
    Cluster, ExpandVisitor, ExpandedNode, InstanceOf, Material, MaterialData, Original, Scene,
    Similarity, Up, compile, expand, quad, triangle,
};
use hirad_core::geometry::polygon_shape;
use hirad_tests::fixture;
use proptest::prelude::*;
use std::path::Path;

/// Every OBJ fixture.
const FIXTURES: &[&str] = &[
    "blender_cube.obj",
    "max_groups.obj",
    "maya_plane.obj",
    "ngons.obj",
    "nonplanar_quad.obj",
    "crlf.obj",
    "continuation.obj",
    "cube.obj",
];

/// Imports `fixtures/obj/NAME` with its MTL files read from the same folder.
fn import_fixture(name: &str) -> ObjImport {
    let path = fixture(&format!("obj/{name}"));
    let bytes = std::fs::read(&path).unwrap();
    let dir = path.parent().unwrap();
    let r =
        obj::import(&bytes, &mut obj::load_mtl_from(dir)).unwrap_or_else(|e| panic!("{name}: {e}"));
    compile(&r.scene).unwrap_or_else(|e| panic!("{name}: does not compile: {e}"));
    r
}

/// Imports OBJ text with MTL files given as `(name, text)`.
fn import_with(obj: &str, mtls: &[(&str, &str)]) -> Result<ObjImport, ObjError> {
    let mut load = |name: &str| -> Result<Vec<u8>, String> {
        mtls.iter()
            .find(|(n, _)| *n == name)
            .map(|(_, t)| t.as_bytes().to_vec())
            .ok_or_else(|| format!("{name}: no such file"))
    };
    obj::import(obj.as_bytes(), &mut load)
}

/// A face of the expanded scene: world-space corners and material name.
#[derive(Clone, Debug, PartialEq)]
struct Face {
    corners: Vec<Vec3>,
    material: String,
}

struct Faces<'a> {
    scene: &'a Scene,
    out: Vec<Face>,
}

impl ExpandVisitor for Faces<'_> {
    type Error = ();
    fn node(&mut self, node: &ExpandedNode<'_>) -> Result<(), ()> {
        let c = node.cluster;
        for p in &c.polygons {
            let corners = p.corners[..p.corner_count()]
                .iter()
                .map(|&k| node.to_world.point(c.vertices[k as usize]))
                .collect();
            let material = self.scene.materials[p.material as usize].name.clone();
            self.out.push(Face { corners, material });
        }
        Ok(())
    }
}

/// The faces of a scene in global-id order.
fn faces(scene: &Scene) -> Vec<Face> {
    let mut f = Faces {
        scene,
        out: Vec::new(),
    };
    expand(scene, &mut f).unwrap();
    f.out
}

/// Exports `scene` and imports the result again.
fn round_trip(scene: &Scene) -> (ObjImport, obj::ObjExport, String) {
    let (mut o, mut m) = (Vec::new(), Vec::new());
    let e = obj::export(scene, Up::Y, "out.mtl", &mut o, &mut m).unwrap();
    let (o, m) = (String::from_utf8(o).unwrap(), String::from_utf8(m).unwrap());
    let r = import_with(&o, &[("out.mtl", &m)]).unwrap_or_else(|e| panic!("{e}\n{o}"));
    compile(&r.scene).unwrap();
    (r, e, o)
}

/// The material table of a scene as `(name, data)`, sorted by name.
fn materials(scene: &Scene) -> Vec<(String, MaterialData)> {
    let mut m: Vec<_> = scene
        .materials
        .iter()
        .map(|m| (m.name.clone(), m.data))
        .collect();
    m.sort_by(|a, b| a.0.cmp(&b.0));
    m
}

/// Asserts that `after` holds the same faces (world corners exactly, materials by name) in
/// the same order as `before`, and the same materials.
fn assert_same(before: &Scene, after: &Scene, what: &str) {
    let (a, b) = (faces(before), faces(after));
    assert_eq!(a.len(), b.len(), "{what}: polygon count");
    for (k, (x, y)) in a.iter().zip(&b).enumerate() {
        assert_eq!(x, y, "{what}: face {k}");
    }
    assert_eq!(materials(before), materials(after), "{what}: materials");
}

fn names(c: &Cluster) -> Vec<&str> {
    c.children
        .iter()
        .map(|k| k.name.as_deref().unwrap_or("?"))
        .collect()
}

fn normal(c: &Cluster, polygon: usize) -> Vec3 {
    let p = &c.polygons[polygon];
    let corners: Vec<Vec3> = p.corners[..p.corner_count()]
        .iter()
        .map(|&k| c.vertices[k as usize])
        .collect();
    polygon_shape(&corners).unwrap().normal
}

fn total_area(c: &Cluster) -> f32 {
    (0..c.polygons.len())
        .map(|i| {
            let p = &c.polygons[i];
            let corners: Vec<Vec3> = p.corners[..p.corner_count()]
                .iter()
                .map(|&k| c.vertices[k as usize])
                .collect();
            polygon_shape(&corners).unwrap().area
        })
        .sum()
}

#[test]
fn blender_cube_and_lamp() {
    let r = import_fixture("blender_cube.obj");
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    let s = &r.scene;
    assert_eq!(s.bands, 3);
    assert!(s.root.polygons.is_empty());
    assert_eq!(names(&s.root), ["Cube", "Lamp"]);
    let cube = &s.root.children[0];
    assert_eq!((cube.vertices.len(), cube.polygons.len()), (8, 6));
    assert!(cube.polygons.iter().all(|p| p.corner_count() == 4));
    // The first face is the top, counter-clockwise seen from above.
    assert_eq!(normal(cube, 0), Vec3::Y);
    let lamp = &s.root.children[1];
    assert_eq!(normal(lamp, 0), Vec3::NEG_Y);
    let m: Vec<&str> = s.materials.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(m, ["Emission", "Material"]);
    assert_eq!(lamp.polygons[0].material, 0);
    assert_eq!(&s.materials[0].data.emit_front[..3], &[100., 90., 80.]);
    assert_eq!(&s.materials[1].data.rho_front[..3], &[0.8; 3]);
    assert_eq!(
        (r.counts.vertices, r.counts.texture_coords, r.counts.normals),
        (12, 18, 7)
    );
}

#[test]
fn max_groups_with_relative_indices() {
    let r = import_fixture("max_groups.obj");
    assert_eq!(
        r.warnings,
        [
            "max_groups.mtl:9:5: Tf 1 1 1 (what Maya and 3ds Max write for opaque materials) \
          ignored: the materials that have it are opaque"
        ]
    );
    let s = &r.scene;
    assert_eq!(names(&s.root), ["Floor", "Wall", "Light"]);
    let [floor, wall, light] = &s.root.children[..] else {
        panic!()
    };
    assert_eq!(floor.polygons.len(), 1);
    assert_eq!(normal(floor, 0), Vec3::Z);
    assert_eq!(wall.polygons.len(), 2);
    assert_eq!(wall.vertices.len(), 4);
    assert_eq!(normal(wall, 0), Vec3::NEG_Y);
    assert_eq!(normal(wall, 1), Vec3::NEG_Y);
    assert_eq!(normal(light, 0), Vec3::NEG_Z);
    assert!(s.materials.iter().all(|m| !m.data.two_sided));
    let lamp = &s.materials[light.polygons[0].material as usize];
    assert_eq!(lamp.name, "Light_Mat");
    assert_eq!(&lamp.data.emit_front[..3], &[50., 45., 40.]);
}

#[test]
fn maya_plane_in_a_group_with_two_names() {
    let r = import_fixture("maya_plane.obj");
    assert_eq!(r.warnings.len(), 1, "{:?}", r.warnings);
    let s = &r.scene;
    // `g default` holds no face and is dropped.
    assert_eq!(names(&s.root), ["pPlane1 group1"]);
    let plane = &s.root.children[0];
    assert_eq!(plane.polygons.len(), 1);
    assert_eq!(normal(plane, 0), Vec3::Y);
    assert_eq!(total_area(plane), 10000.0);
    assert_eq!(s.materials[1].name, "lambert2SG");
    assert_eq!(&s.materials[1].data.rho_front[..3], &[0.64, 0.32, 0.16]);
}

#[test]
fn wings_ngons() {
    let r = import_fixture("ngons.obj");
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    let s = &r.scene;
    assert_eq!(names(&s.root), ["pentagon", "L_shape"]);
    let pentagon = &s.root.children[0].children[0];
    assert_eq!(pentagon.name.as_deref(), Some("pentagon_default"));
    assert_eq!(pentagon.polygons.len(), 3);
    let l = &s.root.children[1].children[0];
    assert!(l.polygons.len() <= 4);
    assert!((total_area(l) - 3.0).abs() < 1e-5);
    for c in [pentagon, l] {
        for i in 0..c.polygons.len() {
            assert_eq!(normal(c, i), Vec3::Z);
        }
    }
    // The MTL defines `default` itself.
    assert_eq!(s.materials.len(), 1);
    assert_eq!(s.materials[0].data.rho_front[0], 0.789_853_8);
}

#[test]
fn meshlab_quads_planar_or_not() {
    let r = import_fixture("nonplanar_quad.obj");
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    let root = &r.scene.root;
    let kinds: Vec<usize> = root.polygons.iter().map(|p| p.corner_count()).collect();
    assert_eq!(kinds, [3, 3, 3, 3, 3, 3, 4]);
    // The darts keep their area (2 - 0.5 * 1.5 ... the notch): both orientations alike.
    let dart_area = |from: usize| -> f32 {
        (from..from + 2)
            .map(|i| {
                let p = &root.polygons[i];
                let c: Vec<Vec3> = p.corners[..3]
                    .iter()
                    .map(|&k| root.vertices[k as usize])
                    .collect();
                polygon_shape(&c).unwrap().area
            })
            .sum()
    };
    assert!((dart_area(2) - 1.0).abs() < 1e-6);
    assert!((dart_area(4) - 1.0).abs() < 1e-6);
    assert_eq!(r.scene.materials[0].name, obj::DEFAULT_MATERIAL);
}

#[test]
fn crlf_and_continuations() {
    let r = import_fixture("crlf.obj");
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    assert_eq!(names(&r.scene.root), ["object_1", "object_2"]);
    assert_eq!(r.scene.root.children[1].polygons.len(), 1);

    let r = import_fixture("continuation.obj");
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    assert_eq!(names(&r.scene.root), ["long group name"]);
    let g = &r.scene.root.children[0];
    assert_eq!((g.vertices.len(), g.polygons.len()), (5, 3));
    assert_eq!(g.vertices[0], Vec3::ZERO);
}

#[test]
fn cube_room_with_lamp_and_leaf() {
    let r = import_fixture("cube.obj");
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    let s = &r.scene;
    assert_eq!(names(&s.root), ["walls", "lamp", "leaf"]);
    let walls = &s.root.children[0];
    assert_eq!(walls.polygons.len(), 6);
    // Seen from inside: every wall faces the centre.
    for i in 0..6 {
        let p = &walls.polygons[i];
        let centre = p
            .corners
            .iter()
            .map(|&k| walls.vertices[k as usize])
            .sum::<Vec3>()
            / 4.0;
        assert!(
            normal(walls, i).dot(Vec3::splat(0.5) - centre) > 0.0,
            "wall {i}"
        );
    }
    let leaf = &s.materials[s.material_index("leaf").unwrap()].data;
    assert!(leaf.two_sided);
    assert_eq!(&leaf.rho_back[..3], &[0.1, 0.4, 0.1]);
    assert_eq!(&leaf.tau[..3], &[0.05, 0.4, 0.05]);
    let lamp = &s.materials[s.material_index("lamp").unwrap()].data;
    assert_eq!(&lamp.emit_front[..3], &[10.0; 3]);
    assert!(!lamp.two_sided);
}

#[test]
fn every_fixture_survives_a_round_trip() {
    for name in FIXTURES {
        let first = import_fixture(name);
        let (second, e, _) = round_trip(&first.scene);
        assert!(second.warnings.is_empty(), "{name}: {:?}", second.warnings);
        assert_eq!(e.faces, first.counts.polygons, "{name}");
        assert_same(&first.scene, &second.scene, name);
    }
}

#[test]
fn missing_mtl_on_disk_is_located() {
    let dir = tempfile::tempdir().unwrap();
    let obj = "# test\nv 0 0 0\nmtllib  missing.mtl\n";
    let e = obj::import(obj.as_bytes(), &mut obj::load_mtl_from(dir.path())).unwrap_err();
    assert_eq!((e.file.as_str(), e.line, e.column), ("", 3, 9));
    assert!(e.message.contains("'missing.mtl'"), "{e}");
}

#[cfg(unix)]
#[test]
fn devices_are_not_read_as_mtl_files() {
    let dir = tempfile::tempdir().unwrap();
    let e = obj::import(b"mtllib /dev/zero\n", &mut obj::load_mtl_from(dir.path())).unwrap_err();
    assert_eq!((e.line, e.column), (1, 8));
    assert!(e.message.contains("not a regular file"), "{e}");
}

#[test]
fn mtl_named_by_a_foreign_absolute_path_is_found_beside_the_obj() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("m.mtl"), "newmtl a\nKd 0.25\n").unwrap();
    let obj = "mtllib C:\\Users\\me\\models\\m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";
    let r = obj::import(obj.as_bytes(), &mut obj::load_mtl_from(dir.path())).unwrap();
    assert_eq!(r.scene.materials[0].data.rho_front[0], 0.25);
}

#[test]
fn located_errors() {
    let mtl = "newmtl white\nKd 0.8\nnewmtl bad\nKd 1.5 0.5 0.5\n";
    let conserve = "newmtl leaf\nKd 0.6 0.6 0.6\nTf 0.2 0.5 0.2\n";
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n";
    let cases: Vec<(String, (&str, u32, u32), &str)> = vec![
        ("mtllib gone.mtl\n".into(), ("", 1, 8), "gone.mtl"),
        (
            format!("mtllib ok.mtl\n{tri}usemtl whte\nf 1 2 3\n"),
            ("", 7, 8),
            "unknown material 'whte'",
        ),
        (format!("{tri}f 0 1 2\n"), ("", 6, 3), "index 0"),
        (
            format!("{tri}f 1 2 7\n"),
            ("", 6, 7),
            "vertex index 7 is out of range",
        ),
        (format!("{tri}f -1 -2 -5\n"), ("", 6, 9), "vertex index -5"),
        (
            format!("{tri}f 1/1 2/2 3/1\n"),
            ("", 6, 9),
            "texture coordinate index 2",
        ),
        (
            format!("{tri}f 1//1 2//-2 3//1\n"),
            ("", 6, 11),
            "normal index -2",
        ),
        (
            "v 0 0 0\nv 1 NaN 0\n".into(),
            ("", 2, 5),
            "not a finite number",
        ),
        ("v inf 0 0\n".into(), ("", 1, 3), "not a finite number"),
        (format!("{tri}f 1 2\n"), ("", 6, 1), "at least 3 corners"),
        ("mtllib bad.mtl\n".into(), ("bad.mtl", 4, 4), "reflectance"),
        ("mtllib leaf.mtl\n".into(), ("leaf.mtl", 3, 8), "exceeds 1"),
    ];
    let mtls = [
        ("ok.mtl", "newmtl white\nKd 0.8\n"),
        ("bad.mtl", mtl),
        ("leaf.mtl", conserve),
    ];
    for (text, (file, line, col), msg) in cases {
        let e = import_with(&text, &mtls).unwrap_err();
        assert_eq!(
            (e.file.as_str(), e.line, e.column),
            (file, line, col),
            "{text:?}: {e}"
        );
        assert!(e.message.contains(msg), "{text:?}: {e}");
    }
}

#[test]
fn truncated_files_never_panic_and_errors_stay_inside() {
    for name in FIXTURES {
        let path = fixture(&format!("obj/{name}"));
        let bytes = std::fs::read(&path).unwrap();
        let dir = path.parent().unwrap();
        let lines = bytes.iter().filter(|&&b| b == b'\n').count() as u32 + 1;
        for cut in 0..bytes.len() {
            match obj::import(&bytes[..cut], &mut obj::load_mtl_from(dir)) {
                Ok(r) => {
                    compile(&r.scene).unwrap();
                }
                Err(e) => {
                    assert!(e.file.is_empty(), "{name}[..{cut}]: {e}");
                    assert!(e.line >= 1 && e.line <= lines, "{name}[..{cut}]: {e}");
                    assert!(e.column >= 1, "{name}[..{cut}]: {e}");
                }
            }
        }
    }
    // Truncated MTL files likewise.
    let mtl = std::fs::read_to_string(fixture("obj/cube.mtl")).unwrap();
    let obj = "mtllib m.mtl\n";
    for cut in 0..mtl.len() {
        if let Err(e) = import_with(obj, &[("m.mtl", &mtl[..cut])]) {
            assert_eq!(e.file, "m.mtl", "{e}");
        }
    }
}

/// A scene with instances (exact, rotated and scaled, and approximate) and every material
/// kind that OBJ/MTL can hold.
fn instanced_scene() -> Scene {
    let mut s = Scene::new(3);
    let mut white = MaterialData::black(3);
    white.rho_front[..3].copy_from_slice(&[0.7, 0.6, 0.5]);
    let mut lamp = MaterialData::black(3);
    lamp.emit_front[..3].copy_from_slice(&[5.0, 4.0, 3.0]);
    let mut leaf = MaterialData::black(3);
    leaf.two_sided = true;
    leaf.rho_front[..3].copy_from_slice(&[0.1, 0.45, 0.1]);
    leaf.rho_back[..3].copy_from_slice(&[0.1, 0.45, 0.1]);
    leaf.tau[..3].copy_from_slice(&[0.05, 0.45, 0.05]);
    s.materials = vec![
        Material {
            name: "white".into(),
            data: white,
        },
        Material {
            name: "lamp".into(),
            data: lamp,
        },
        Material {
            name: "leaf".into(),
            data: leaf,
        },
    ];
    let mut twig = Cluster::named("twig");
    let a = twig.vertex(Vec3::new(0., 0., 0.));
    let b = twig.vertex(Vec3::new(0.1, 0., 0.));
    let c = twig.vertex(Vec3::new(0.1, 0.1, 0.));
    let d = twig.vertex(Vec3::new(0., 0.1, 0.));
    twig.polygons = vec![quad(a, b, c, d, 2), triangle(a, c, d, 0)];
    s.originals = vec![Original {
        name: "twig".into(),
        root: twig,
    }];
    let mut floor = Cluster::named("floor");
    let a = floor.vertex(Vec3::new(-1., -1., 0.));
    let b = floor.vertex(Vec3::new(1., -1., 0.));
    let c = floor.vertex(Vec3::new(1., 1., 0.));
    let d = floor.vertex(Vec3::new(-1., 1., 0.));
    floor.polygons = vec![quad(a, b, c, d, 0)];
    let mut light = Cluster::named("light");
    let a = light.vertex(Vec3::new(0., 0., 2.));
    let b = light.vertex(Vec3::new(0., 0.5, 2.));
    let c = light.vertex(Vec3::new(0.5, 0., 2.));
    light.polygons = vec![triangle(a, b, c, 1)];
    s.root.children = vec![floor, light];
    for k in 0..5 {
        s.root.children.push(Cluster {
            name: Some(format!("twig {k}")),
            instance: Some(InstanceOf {
                original: 0,
                exact: true,
                transform: Similarity {
                    rotation: Quat::from_axis_angle(Vec3::new(0.2, 0.3, 1.).normalize(), k as f32),
                    translation: Vec3::new(0.3 * k as f32, 0.1, 0.5),
                    scale: 1.0 + 0.25 * k as f32,
                },
            }),
            ..Cluster::default()
        });
    }
    // An approximate instance with geometry of its own.
    let mut approx = Cluster::named("approx");
    let a = approx.vertex(Vec3::new(0., 0., 0.));
    let b = approx.vertex(Vec3::new(0.1, 0., 0.));
    let c = approx.vertex(Vec3::new(0., 0.1, 0.));
    approx.polygons = vec![triangle(a, b, c, 2)];
    approx.instance = Some(InstanceOf {
        original: 0,
        exact: false,
        transform: Similarity {
            rotation: Quat::IDENTITY,
            translation: Vec3::new(0., 0., 1.),
            scale: 2.0,
        },
    });
    s.root.children.push(approx);
    s
}

#[test]
fn instanced_scene_flattens_and_reads_back() {
    let s = instanced_scene();
    compile(&s).unwrap();
    let (r, e, text) = round_trip(&s);
    assert!(e.warnings.is_empty(), "{:?}", e.warnings);
    assert_eq!(e.faces, 2 + 5 * 2 + 1);
    assert!(text.contains("\ng scene/twig 3\n"), "{text}");
    assert_same(&s, &r.scene, "instanced scene");
    // And once more: the flattened scene is a fixed point.
    let (r2, _, text2) = round_trip(&r.scene);
    assert_same(&r.scene, &r2.scene, "second round trip");
    assert_eq!(faces(&r2.scene).len(), faces(&s).len());
    let _ = text2;
}

#[test]
fn export_writes_through_files() {
    let dir = tempfile::tempdir().unwrap();
    let s = instanced_scene();
    let (op, mp) = (dir.path().join("flat.obj"), dir.path().join("flat.mtl"));
    let mut o = std::fs::File::create(&op).unwrap();
    let mut m = std::fs::File::create(&mp).unwrap();
    obj::export(&s, Up::Y, "flat.mtl", &mut o, &mut m).unwrap();
    drop((o, m));
    let bytes = std::fs::read(&op).unwrap();
    let r = obj::import(&bytes, &mut obj::load_mtl_from(Path::new(dir.path()))).unwrap();
    assert_same(&s, &r.scene, "through files");
}

/// One random OBJ statement line from a vocabulary close to real files, with faults.
fn soup_line() -> impl Strategy<Value = String> {
    let word = prop_oneof![
        Just("v".to_string()),
        Just("vt".to_string()),
        Just("vn".to_string()),
        Just("f".to_string()),
        Just("o".to_string()),
        Just("g".to_string()),
        Just("s".to_string()),
        Just("l".to_string()),
        Just("usemtl".to_string()),
        Just("mtllib".to_string()),
        Just("m.mtl".to_string()),
        Just("newmtl".to_string()),
        Just("Kd".to_string()),
        Just("Ke".to_string()),
        Just("Tf".to_string()),
        Just("a".to_string()),
        Just("nan".to_string()),
        Just("1e39".to_string()),
        Just("\\".to_string()),
        Just("#".to_string()),
        Just("/".to_string()),
        Just("//".to_string()),
        (-6i32..8).prop_map(|i| i.to_string()),
        (-6i32..8, -3i32..4).prop_map(|(a, b)| format!("{a}/{b}")),
        (-6i32..8, -3i32..4).prop_map(|(a, b)| format!("{a}//{b}")),
        (-6i32..8, -3i32..4, -3i32..4).prop_map(|(a, b, c)| format!("{a}/{b}/{c}")),
        (-2.0f32..2.0).prop_map(|x| x.to_string()),
        (0.0f32..1.0).prop_map(|x| x.to_string()),
    ];
    (
        prop::collection::vec(word, 0..8),
        prop_oneof![Just("\n"), Just("\r\n"), Just(" \\\n")],
    )
        .prop_map(|(words, end)| words.join(" ") + end)
}

/// Faces of a random valid mesh: corners around random centres in random planes.
#[derive(Clone, Debug)]
struct RandomFace {
    centre: (i8, i8, i8),
    corners: usize,
    radius: u8,
    tilt: u8,
    material: usize,
    group: Option<u8>,
}

fn random_face() -> impl Strategy<Value = RandomFace> {
    (
        (-20i8..20, -20i8..20, -20i8..20),
        3usize..8,
        1u8..10,
        0u8..8,
        0usize..3,
        prop::option::of(0u8..3),
    )
        .prop_map(
            |(centre, corners, radius, tilt, material, group)| RandomFace {
                centre,
                corners,
                radius,
                tilt,
                material,
                group,
            },
        )
}

/// OBJ text for `faces`: regular polygons (convex, planar) with a material library.
fn mesh_text(faces: &[RandomFace]) -> String {
    let mut s = String::from("mtllib m.mtl\n");
    let mut next = 1;
    for (i, f) in faces.iter().enumerate() {
        match f.group {
            Some(0) => s.push_str(&format!("o part{i}\n")),
            Some(1) => s.push_str(&format!("g group {i}\n")),
            _ => {}
        }
        let rot = Quat::from_axis_angle(Vec3::new(1., 0.5, 0.25).normalize(), f32::from(f.tilt));
        let c = Vec3::new(
            f32::from(f.centre.0),
            f32::from(f.centre.1),
            f32::from(f.centre.2),
        );
        for k in 0..f.corners {
            let a = k as f32 * std::f32::consts::TAU / f.corners as f32;
            let p = c + rot * (Vec3::new(a.cos(), a.sin(), 0.) * f32::from(f.radius));
            s.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
        }
        s.push_str(&format!("usemtl m{}\nf", f.material));
        for k in 0..f.corners {
            // Mix absolute and relative indices.
            if k % 2 == 0 {
                s.push_str(&format!(" {}", next + k));
            } else {
                s.push_str(&format!(" {}", k as i64 - f.corners as i64));
            }
        }
        s.push('\n');
        next += f.corners;
    }
    s
}

const MESH_MTL: &str = "newmtl m0\nKd 0.5\nnewmtl m1\nKd 0.2 0.3 0.4\nKe 1 2 3\n\
                        newmtl m2\nKd 0.1 0.4 0.1\nTf 0.3 0.5 0.3\n";

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..400)) {
        let mut load = |_: &str| -> Result<Vec<u8>, String> { Ok(bytes.clone()) };
        if let Ok(r) = obj::import(&bytes, &mut load) {
            prop_assert!(compile(&r.scene).is_ok());
        }
    }

    #[test]
    fn token_soup_never_panics(
        obj_lines in prop::collection::vec(soup_line(), 0..40),
        mtl_lines in prop::collection::vec(soup_line(), 0..10),
    ) {
        let obj = obj_lines.concat();
        let mtl = mtl_lines.concat();
        match import_with(&obj, &[("m.mtl", &mtl)]) {
            Ok(r) => prop_assert!(compile(&r.scene).is_ok()),
            Err(e) => prop_assert!(e.line >= 1 && e.column >= 1),
        }
    }

    #[test]
    fn random_meshes_survive_import_export_import(
        faces in prop::collection::vec(random_face(), 1..30),
    ) {
        let text = mesh_text(&faces);
        let first = import_with(&text, &[("m.mtl", MESH_MTL)]).unwrap();
        prop_assert!(first.warnings.is_empty(), "{:?}", first.warnings);
        let expected: usize = faces.iter().map(|f| if f.corners == 4 { 1 } else { f.corners - 2 }).sum();
        prop_assert_eq!(first.counts.polygons as usize, expected);
        let (second, _, _) = round_trip(&first.scene);
        prop_assert!(second.warnings.is_empty(), "{:?}", second.warnings);
        assert_same(&first.scene, &second.scene, "random mesh");
    }
}
