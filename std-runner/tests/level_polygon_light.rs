//! The sun on each polygon of a closed instance (issue 18): where the rest of the level
//! shades one of its polygons and not another, the shaded one's first light is nothing and
//! the other's is the whole sun, not both half of it (one lit fraction for the instance
//! spread over its polygons as if it stood alone put a dense canopy's shaded lower leaves
//! in the sun, and the soil under them took 20% too much NIR). The reference is the
//! geometry itself: a roof above one of two squares, its shadow covering that square whole.

mod common;

use glam::{Quat, Vec3};
use hirad::generate::palette::diffuse;
use hirad::generate::shapes::add_quad;
use hirad::scene::{Cluster, InstanceOf, Original, Scene, Similarity, compile};
use hirad::solve::RayonExecutor;
use hirad::tables::bake_original;
use hirad_core::hr::level_probe::solve_level;
use hirad_core::hr::{Instancing, Settings};
use hirad_core::image::{LightData, SceneView, SliceSource};
use hirad_core::tables::closed::Received;

const SUN: f32 = 100.0;
/// Side of each square and the distance between their centres (m, the original's frame).
const SIDE: f32 = 0.4;
const APART: f32 = 1.2;

fn square(c: &mut Cluster, centre: Vec3, side: f32, material: u32) {
    let h = 0.5 * side;
    // Counter-clockwise seen from above: the front faces up.
    add_quad(
        c,
        [
            centre + Vec3::new(-h, -h, 0.0),
            centre + Vec3::new(h, -h, 0.0),
            centre + Vec3::new(h, h, 0.0),
            centre + Vec3::new(-h, h, 0.0),
        ],
        material,
    );
}

/// Two squares side by side, one closed instance of them turned, scaled and moved; a black
/// roof high above the first square, where the sun's ray from it passes: the first square's
/// first light is 0, the second's the sun on its face, and all the instance intercepts is
/// the second square's cross-section times the sun.
#[test]
fn a_shaded_polygon_of_a_closed_instance_takes_no_sun_and_its_lit_neighbour_all() {
    for (turn, scale, sun) in [
        (0.0f32, 1.0f32, Vec3::new(0.0, 0.0, 1.0)),
        (0.7, 1.3, Vec3::new(0.5, 0.2, 0.85)),
        (2.2, 0.8, Vec3::new(-0.3, 0.6, 0.75)),
        (4.0, 1.1, Vec3::new(0.2, -0.7, 0.5)),
    ] {
        let sun = sun.normalize();
        let mut scene = Scene::new(2);
        let leaf = diffuse(&mut scene, "leaf", &[0.3, 0.6]);
        let black = diffuse(&mut scene, "black", &[0.0, 0.0]);
        let mut pair = Cluster::named("pair");
        square(&mut pair, Vec3::ZERO, SIDE, leaf);
        square(&mut pair, Vec3::new(APART, 0.0, 0.0), SIDE, leaf);
        scene.originals.push(Original {
            name: "pair".into(),
            root: pair,
        });
        let place = Similarity {
            rotation: Quat::from_rotation_z(turn),
            translation: Vec3::new(0.3, -0.2, 0.5),
            scale,
        };
        let first = place.translation;
        // The roof 2 m above, centred on the sun's ray from the first square's centre, wide
        // enough for that square's shadow and clear of the second's.
        let roof_at = first + sun * (2.0 / sun.z);
        let mut roof = Cluster::named("roof");
        square(&mut roof, roof_at, 0.5 * APART * scale, black);
        scene.root.children.push(roof);
        scene.root.children.push(Cluster {
            instance: Some(InstanceOf {
                original: 0,
                exact: true,
                transform: place,
            }),
            ..Cluster::default()
        });
        scene.suns.push(LightData {
            towards: sun,
            irradiance: [SUN, SUN, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        });
        let mut exec = RayonExecutor::new(2).unwrap();
        let t = bake_original(
            &scene,
            0,
            &common::quick_tables(),
            &mut exec,
            &mut |_, _, _| {},
        )
        .unwrap();
        scene.tables = vec![t.to_scene()];
        let bytes = compile(&scene).unwrap();
        let view = SceneView::open(SliceSource(&bytes[..])).unwrap();
        let mut ws = vec![0u8; 64 << 20];
        let mut got = None;
        solve_level(
            &view,
            &Settings::default(),
            Instancing::Top,
            &mut ws,
            &mut exec,
            &mut common::Nothing,
            |l| {
                // The roof is black: the instance's light is the sun's alone.
                let c = l.instance(0);
                let r = Received::over(&c.placed, c.received).unwrap();
                got = Some((
                    [r.first_irradiance(0, 0, 0), r.first_irradiance(0, 0, 1)],
                    [r.first_irradiance(1, 0, 0), r.first_irradiance(1, 0, 1)],
                    [r.intercepted(0), r.intercepted(1)],
                ));
            },
        )
        .unwrap();
        let (shaded, lit, intercepted) = got.unwrap();
        let on_face = SUN * sun.z;
        let cross_section = on_face * SIDE * SIDE * scale * scale;
        for b in 0..2 {
            println!(
                "turn {turn} scale {scale} band {b}: shaded {:.2}, lit {:.2} (sun on the face {on_face:.2}), intercepted {:.3} W ({cross_section:.3})",
                shaded[b], lit[b], intercepted[b]
            );
            assert!(shaded[b] <= 0.01 * on_face, "shaded square: {}", shaded[b]);
            assert!(
                (lit[b] / on_face - 1.0).abs() <= 0.03,
                "lit square: {} vs {on_face}",
                lit[b]
            );
            assert!(
                (intercepted[b] / cross_section - 1.0).abs() <= 0.05,
                "intercepted {} W vs {cross_section} W",
                intercepted[b]
            );
        }
    }
}
