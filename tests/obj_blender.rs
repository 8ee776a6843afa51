//! OBJ files written by Blender 3.4 itself (its C++ exporter and its legacy Python one; see
//! fixtures/gen/blender_export.py): a monkey with non-planar quads, a cylinder with 24-gon
//! caps, a UV sphere with triangle fans, a torus, a floor and an emitting panel facing down.
//! The imported area of every object matches the area Blender measured, fronts face where
//! Blender's normals point (its exporters write Y up), and `Ke` emits.

use glam::Vec3;
use hirad::scene::{Cluster, Scene};
use hirad_core::geometry::polygon_shape;
use hirad_tests::fixture;
use std::collections::BTreeMap;

fn import(name: &str) -> Scene {
    let path = fixture(&format!("obj/blender/{name}"));
    let dir = path.parent().unwrap().to_path_buf();
    let bytes = std::fs::read(&path).unwrap();
    let imported = hirad::obj::import(&bytes, &mut hirad::obj::load_mtl_from(&dir)).unwrap();
    assert!(imported.warnings.is_empty(), "{:?}", imported.warnings);
    hirad::scene::compile(&imported.scene).unwrap();
    imported.scene
}

/// Area and area-weighted normal of a cluster's polygons (its own, no instances in OBJ).
fn measure(c: &Cluster) -> (f64, Vec3) {
    let mut area = 0.0f64;
    let mut n = Vec3::ZERO;
    for p in &c.polygons {
        let corners: Vec<Vec3> = p.corners[..p.corner_count()]
            .iter()
            .map(|&i| c.vertices[i as usize])
            .collect();
        let s = polygon_shape(&corners).unwrap();
        area += s.area as f64;
        n += s.normal * s.area;
    }
    (area, n)
}

/// Per object: faces, Blender's polygon area, least and greatest triangulated area (m^2).
fn reference() -> BTreeMap<String, (usize, f64, f64, f64)> {
    let text = std::fs::read_to_string(fixture("obj/blender/blender_scene.areas.txt")).unwrap();
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            let num = |i: usize| f[i].parse::<f64>().unwrap();
            (
                f[0].to_string(),
                (f[1].parse().unwrap(), num(2), num(3), num(4)),
            )
        })
        .collect()
}

fn check(name: &str) {
    let scene = import(name);
    let reference = reference();
    assert_eq!(scene.bands, 3);
    assert_eq!(
        scene.root.children.len(),
        reference.len(),
        "one cluster per Blender object"
    );
    for (object, &(_faces, area, tri_min, tri_max)) in &reference {
        let c = scene
            .root
            .children
            .iter()
            .find(|c| {
                c.name
                    .as_deref()
                    .is_some_and(|n| n == object || n.starts_with(&format!("{object}_")))
            })
            .unwrap_or_else(|| panic!("{name}: no cluster for {object}"));
        let (a, n) = measure(c);
        // Non-planar quads are split into two triangles, so the imported surface lies within
        // the range of Blender's own triangulations (coordinates are written with 6 decimals).
        let slack = 2e-5 * area;
        assert!(
            a >= tri_min - slack && a <= tri_max + slack,
            "{name}: {object}: area {a}, Blender's triangulations {tri_min}..{tri_max}"
        );
        if (tri_max - tri_min) <= 1e-7 * area {
            assert!(
                (a - area).abs() <= slack,
                "{name}: {object}: area {a}, Blender says {area}"
            );
        }
        if object == "Light_Panel" {
            assert!(
                n.normalize().dot(Vec3::NEG_Y) > 0.999,
                "the panel faces down: {n}"
            );
            let m = c.polygons[0].material as usize;
            assert_eq!(scene.materials[m].name, "Lamp");
            assert_eq!(scene.materials[m].data.emit_front[..3], [5.0, 5.0, 4.0]);
        }
        if object == "Floor" {
            assert!(
                n.normalize().dot(Vec3::Y) > 0.999,
                "the floor faces up: {n}"
            );
        }
    }
    let red = scene
        .material_index("Red_Paint")
        .expect("Blender writes Red_Paint");
    assert_eq!(scene.materials[red].data.rho_front[..3], [0.6, 0.05, 0.05]);
}

#[test]
fn blender_34_exporter() {
    check("blender34_scene.obj");
}

#[test]
fn blender_legacy_exporter() {
    check("blender_legacy_scene.obj");
}

#[test]
fn both_exporters_give_the_same_polygons() {
    let a = import("blender34_scene.obj");
    let b = import("blender_legacy_scene.obj");
    let count = |s: &Scene| {
        s.root
            .children
            .iter()
            .map(|c| c.polygons.len())
            .sum::<usize>()
    };
    assert_eq!(count(&a), count(&b));
}
