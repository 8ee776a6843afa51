//! Light between closed instances that block with their own polygons (the exchange of a
//! level, issue 18): a lit square sends its neighbour what the form factor between them
//! says, computed here by a double integral that shares no code with the solver.

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

/// Reflectance of the squares (both bands).
const RHO: f32 = 0.5;
/// The sun's irradiance (W/m^2, both bands), straight down.
const SUN: f32 = 100.0;
/// Side of the squares (m).
const SIDE: f32 = 1.0;

fn instance(transform: Similarity) -> Cluster {
    Cluster {
        instance: Some(InstanceOf {
            original: 0,
            exact: true,
            transform,
        }),
        ..Cluster::default()
    }
}

/// The square's corners in its frame (normal +z).
fn square() -> [Vec3; 4] {
    let h = 0.5 * SIDE;
    [
        Vec3::new(-h, -h, 0.0),
        Vec3::new(h, -h, 0.0),
        Vec3::new(h, h, 0.0),
        Vec3::new(-h, h, 0.0),
    ]
}

/// Where the second square of pair `k` stands: upright (its normal along -x, edge-on to the
/// sun), beside and above the first, which faces the sun.
fn upright(k: usize, at: Vec3) -> Similarity {
    let gap = 0.2 + 0.1 * (k % 4) as f32;
    Similarity {
        rotation: Quat::from_rotation_y(-std::f32::consts::FRAC_PI_2),
        translation: at + Vec3::new(0.5 * SIDE + gap, 0.0, 0.3 + 0.1 * (k % 3) as f32),
        scale: 1.0,
    }
}

/// The form factor from square `a` to square `b` (world corners, fronts facing each other
/// as their normals say), by the midpoint rule on `n x n` cells of each.
fn form_factor(a: [Vec3; 4], b: [Vec3; 4], n: usize) -> f64 {
    let f = |v: Vec3| glam::DVec3::new(v.x as f64, v.y as f64, v.z as f64);
    let (a, b) = (a.map(f), b.map(f));
    let na = (a[1] - a[0]).cross(a[3] - a[0]).normalize();
    let nb = (b[1] - b[0]).cross(b[3] - b[0]).normalize();
    let area = |q: &[glam::DVec3; 4]| (q[1] - q[0]).cross(q[3] - q[0]).length();
    let (da, db) = (area(&a) / (n * n) as f64, area(&b) / (n * n) as f64);
    let point = |q: &[glam::DVec3; 4], i: usize, j: usize| {
        let (u, v) = ((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
        q[0] + (q[1] - q[0]) * u + (q[3] - q[0]) * v
    };
    let mut sum = 0.0;
    for i in 0..n {
        for j in 0..n {
            let x = point(&a, i, j);
            for k in 0..n {
                for l in 0..n {
                    let y = point(&b, k, l);
                    let d = y - x;
                    let r2 = d.length_squared();
                    let (ca, cb) = (na.dot(d), -nb.dot(d));
                    if ca > 0.0 && cb > 0.0 {
                        sum += ca * cb / (std::f64::consts::PI * r2 * r2) * db;
                    }
                }
            }
        }
    }
    sum * da / area(&a)
}

/// Pairs of squares far apart from each other: in each, one faces the sun and the other
/// stands upright beside it, edge-on to the sun, lit only by the first. What the upright one
/// intercepts is the first's radiosity times its area times the form factor between them,
/// pair by pair within the exchange's sampling noise and on average within 6%.
#[test]
fn a_closed_instance_sends_its_neighbour_what_the_form_factor_says() {
    let mut s = Scene::new(2);
    let m = diffuse(&mut s, "paper", &[RHO, RHO]);
    let mut leaf = Cluster::named("square");
    add_quad(&mut leaf, square(), m);
    s.originals.push(Original {
        name: "square".into(),
        root: leaf,
    });
    // The level's own polygon: a black speck far below, out of the way.
    let black = diffuse(&mut s, "black", &[0.0, 0.0]);
    add_quad(
        &mut s.root,
        square().map(|c| c * 0.01 + Vec3::new(0.0, 0.0, -40.0)),
        black,
    );
    let pairs = 32usize;
    let mut expected = Vec::new();
    for k in 0..pairs {
        let at = Vec3::new(30.0 * (k % 8) as f32, 30.0 * (k / 8) as f32, 0.0);
        let flat = Similarity {
            rotation: Quat::IDENTITY,
            translation: at,
            scale: 1.0,
        };
        let up = upright(k, at);
        s.root.children.push(instance(flat));
        s.root.children.push(instance(up));
        let f = form_factor(
            square().map(|c| flat.point(c)),
            square().map(|c| up.point(c)),
            24,
        );
        // The flat square's radiosity times its area times the form factor.
        expected.push(RHO as f64 * SUN as f64 * (SIDE * SIDE) as f64 * f);
    }
    s.suns.push(LightData {
        towards: Vec3::Z,
        irradiance: [SUN, SUN, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    });
    let mut exec = RayonExecutor::new(2).unwrap();
    let settings = common::quick_tables();
    let t = bake_original(&s, 0, &settings, &mut exec, &mut |_, _, _| {}).unwrap();
    s.tables = vec![t.to_scene()];
    let bytes = compile(&s).unwrap();
    let view = SceneView::open(SliceSource(&bytes[..])).unwrap();
    let mut ws = vec![0u8; 64 << 20];
    let mut got = vec![[0.0f64; 2]; 2 * pairs];
    solve_level(
        &view,
        &Settings::default(),
        Instancing::Top,
        &mut ws,
        &mut exec,
        &mut common::Nothing,
        |l| {
            let mut by_node: Vec<u32> = (0..l.instances()).collect();
            by_node.sort_by_key(|&i| l.instance(i).node);
            for (k, &i) in by_node.iter().enumerate() {
                let c = l.instance(i);
                let r = Received::over(&c.placed, c.received).unwrap();
                got[k] = [r.intercepted(0) as f64, r.intercepted(1) as f64];
            }
        },
    )
    .unwrap();
    let mut ratios = Vec::new();
    for k in 0..pairs {
        // The flat one takes the sun whole (and a little of its neighbour's light back).
        let sun = (SUN * SIDE * SIDE) as f64;
        for (b, (&flat, &upright)) in got[2 * k].iter().zip(&got[2 * k + 1]).enumerate() {
            assert!(
                flat >= sun * 0.99 && flat <= sun * 1.03,
                "pair {k} band {b}: flat {flat} vs {sun}"
            );
            let r = upright / expected[k];
            assert!(
                (r - 1.0).abs() <= 0.25,
                "pair {k} band {b}: upright {upright} vs {}",
                expected[k]
            );
            ratios.push(r);
        }
    }
    let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
    println!("upright over form factor: mean {mean:.4}, {ratios:.3?}");
    assert!((mean - 1.0).abs() <= 0.06, "mean {mean}");
}
