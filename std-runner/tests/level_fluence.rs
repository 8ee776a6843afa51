//! A closed instance lit from below by the soil (issue 18): it takes the soil's light from
//! every direction the soil covers (its fluence, spread over the directions it comes from),
//! not the irradiance of a plane facing the soil's centre. The reference is a double
//! integral over the soil's lit part that shares no code with the solver.

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

/// The soil's reflectance (both bands) and the sun's irradiance (W/m^2).
const SOIL_RHO: f32 = 0.5;
const SUN: f32 = 100.0;

/// A square of side `s` at height `h`, facing down, over a soil of side `soil` lit by a
/// low sun (its shadow falls away from under it): what the square intercepts, against the
/// soil's light on its face by a double integral (minus the sun on its back), within 8%.
#[test]
fn a_closed_square_over_the_soil_takes_the_soil_light_its_face_sees() {
    for (s, h, soil) in [
        (1.0f32, 0.5f32, 12.0f32),
        (0.6, 1.2, 16.0),
        (1.5, 0.3, 10.0),
    ] {
        let sun = Vec3::new(1.0, 0.3, 0.35).normalize();
        let mut scene = Scene::new(2);
        let paper = diffuse(&mut scene, "paper", &[0.0, 0.0]);
        let ground = diffuse(&mut scene, "soil", &[SOIL_RHO, SOIL_RHO]);
        let mut square = Cluster::named("square");
        // Corners turning clockwise seen from above: the front faces down.
        let hs = 0.5 * s;
        add_quad(
            &mut square,
            [
                Vec3::new(-hs, -hs, 0.0),
                Vec3::new(-hs, hs, 0.0),
                Vec3::new(hs, hs, 0.0),
                Vec3::new(hs, -hs, 0.0),
            ],
            paper,
        );
        scene.originals.push(Original {
            name: "square".into(),
            root: square,
        });
        // The soil in tiles of 0.5 m (the shadow's edge is resolved by the hierarchy).
        let n = (soil / 0.5) as i32;
        let mut field = Cluster::named("soil");
        for i in 0..n {
            for j in 0..n {
                let (x, y) = (-0.5 * soil + 0.5 * i as f32, -0.5 * soil + 0.5 * j as f32);
                add_quad(
                    &mut field,
                    [
                        Vec3::new(x, y, 0.0),
                        Vec3::new(x + 0.5, y, 0.0),
                        Vec3::new(x + 0.5, y + 0.5, 0.0),
                        Vec3::new(x, y + 0.5, 0.0),
                    ],
                    ground,
                );
            }
        }
        scene.root.children.push(field);
        scene.root.children.push(Cluster {
            instance: Some(InstanceOf {
                original: 0,
                exact: true,
                transform: Similarity {
                    rotation: Quat::IDENTITY,
                    translation: Vec3::new(0.0, 0.0, h),
                    scale: 1.0,
                },
            }),
            ..Cluster::default()
        });
        scene.suns.push(LightData {
            towards: sun,
            irradiance: [SUN, SUN, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        });
        let settings = common::quick_tables();
        let mut exec = RayonExecutor::new(2).unwrap();
        let t = bake_original(&scene, 0, &settings, &mut exec, &mut |_, _, _| {}).unwrap();
        scene.tables = vec![t.to_scene()];
        let bytes = compile(&scene).unwrap();
        let view = SceneView::open(SliceSource(&bytes[..])).unwrap();
        let mut ws = vec![0u8; 64 << 20];
        let mut got = [0.0f64; 2];
        let solve = Settings {
            epsilon: 1e-4,
            ..Settings::default()
        };
        solve_level(
            &view,
            &solve,
            Instancing::Top,
            &mut ws,
            &mut exec,
            &mut common::Nothing,
            |l| {
                let c = l.instance(0);
                let r = Received::over(&c.placed, c.received).unwrap();
                got = [r.intercepted(0) as f64, r.intercepted(1) as f64];
            },
        )
        .unwrap();
        // The sun on its back (it blocks the sun: its tables' cross-section).
        let back = (SUN * sun.z * s * s) as f64;
        let want = soil_light(s, h, soil, sun);
        for (b, g) in got.iter().enumerate() {
            let from_soil = g - back;
            let e = from_soil / want - 1.0;
            println!("side {s} height {h}: band {b}: {from_soil:.3} W vs {want:.3} W ({e:+.3})");
            assert!(
                e.abs() <= 0.08,
                "side {s} height {h} band {b}: {from_soil} W from the soil vs {want} W"
            );
        }
    }
}

/// The soil's light on the square's face (W): the soil's radiosity (its reflectance times
/// the sun, nothing in the square's shadow) times the form factor from each soil point to
/// each point of the face, by the midpoint rule.
fn soil_light(s: f32, h: f32, soil: f32, sun: Vec3) -> f64 {
    let (s, h, soil) = (s as f64, h as f64, soil as f64);
    let sun = glam::DVec3::new(sun.x as f64, sun.y as f64, sun.z as f64);
    let b_lit = SOIL_RHO as f64 * SUN as f64 * sun.z;
    let (ns, nq) = (480usize, 12usize);
    let (da, dq) = (soil / ns as f64, s / nq as f64);
    let mut sum = 0.0f64;
    for i in 0..ns {
        for j in 0..ns {
            let x = glam::DVec3::new(
                -0.5 * soil + (i as f64 + 0.5) * da,
                -0.5 * soil + (j as f64 + 0.5) * da,
                0.0,
            );
            // In the square's shadow: the square seen from x towards the sun.
            let t = h / sun.z;
            let p = x + sun * t;
            if p.x.abs() <= 0.5 * s && p.y.abs() <= 0.5 * s {
                continue;
            }
            for k in 0..nq {
                for l in 0..nq {
                    let y = glam::DVec3::new(
                        -0.5 * s + (k as f64 + 0.5) * dq,
                        -0.5 * s + (l as f64 + 0.5) * dq,
                        h,
                    );
                    let d = y - x;
                    let r2 = d.length_squared();
                    // Both cosines are the height over the distance.
                    let c = h * h / r2;
                    sum += b_lit * c / (std::f64::consts::PI * r2) * da * da * dq * dq;
                }
            }
        }
    }
    sum
}
