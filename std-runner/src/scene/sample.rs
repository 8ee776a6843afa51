//! A small scene that uses every feature of the model: for tests, examples and fuzz seeds.

use super::*;
use glam::{Quat, Vec3};

/// A small scene with every feature: two-sided material, an original with a nested original,
/// exact and approximate instances, lights and a camera.
pub fn sample() -> Scene {
    let mut s = Scene::new(2);
    s.band_names = vec!["par".into(), "nir".into()];
    let mut white = MaterialData::black(2);
    white.rho_front[..2].copy_from_slice(&[0.5, 0.6]);
    let mut leaf = MaterialData::black(2);
    leaf.two_sided = true;
    leaf.rho_front[..2].copy_from_slice(&[0.1, 0.4]);
    leaf.rho_back[..2].copy_from_slice(&[0.1, 0.4]);
    leaf.tau[..2].copy_from_slice(&[0.05, 0.4]);
    let mut lamp = MaterialData::black(2);
    lamp.emit_front[..2].copy_from_slice(&[10.0, 5.0]);
    s.materials = vec![
        Material {
            name: "white".into(),
            data: white,
        },
        Material {
            name: "leaf".into(),
            data: leaf,
        },
        Material {
            name: "lamp".into(),
            data: lamp,
        },
    ];
    let mut twig = Cluster::named("twig");
    twig.axis = Some(3);
    twig.age = Some(1.0);
    let a = twig.vertex(Vec3::new(0., 0., 0.));
    let b = twig.vertex(Vec3::new(0.1, 0., 0.));
    let c = twig.vertex(Vec3::new(0.1, 0.1, 0.));
    let d = twig.vertex(Vec3::new(0., 0.1, 0.));
    twig.polygons = vec![quad(a, b, c, d, 1), triangle(a, c, d, 1)];
    // "branch" instances "twig" (defined later in the list: compile must reorder).
    let mut branch = Cluster::named("branch");
    let e = branch.vertex(Vec3::new(0., 0., 0.));
    let f = branch.vertex(Vec3::new(0., 0., 1.));
    let g = branch.vertex(Vec3::new(0.05, 0., 1.));
    branch.polygons = vec![triangle(e, f, g, 0)];
    for k in 0..3 {
        branch.children.push(Cluster {
            instance: Some(InstanceOf {
                original: 1,
                exact: true,
                transform: Similarity {
                    rotation: Quat::from_rotation_z(k as f32),
                    translation: Vec3::new(0., 0., 0.3 * k as f32),
                    scale: 0.5,
                },
            }),
            ..Cluster::default()
        });
    }
    s.originals = vec![
        Original {
            name: "branch".into(),
            root: branch,
        },
        Original {
            name: "twig".into(),
            root: twig,
        },
    ];
    let mut root = Cluster::named("root");
    let p = root.vertex(Vec3::new(-5., -5., 0.));
    let q = root.vertex(Vec3::new(5., -5., 0.));
    let r = root.vertex(Vec3::new(5., 5., 0.));
    let t = root.vertex(Vec3::new(-5., 5., 0.));
    root.polygons = vec![quad(p, q, r, t, 0)];
    let mut lampc = Cluster::named("lamp");
    let l0 = lampc.vertex(Vec3::new(0., 0., 3.));
    let l1 = lampc.vertex(Vec3::new(0., 1., 3.));
    let l2 = lampc.vertex(Vec3::new(1., 0., 3.));
    lampc.polygons = vec![triangle(l0, l1, l2, 2)];
    root.children.push(lampc);
    // An approximate instance of "branch" with its own geometry: one leaf and a nested exact
    // twig.
    let mut own = Cluster::default();
    let u0 = own.vertex(Vec3::new(0., 0., 0.));
    let u1 = own.vertex(Vec3::new(0.2, 0., 0.5));
    let u2 = own.vertex(Vec3::new(0., 0.2, 0.5));
    own.polygons = vec![triangle(u0, u1, u2, 1)];
    own.children.push(Cluster {
        instance: Some(InstanceOf {
            original: 1,
            exact: true,
            transform: Similarity::IDENTITY,
        }),
        ..Cluster::default()
    });
    root.children.push(Cluster {
        name: Some("branch A".into()),
        axis: Some(2),
        age: Some(4.5),
        instance: Some(InstanceOf {
            original: 0,
            exact: false,
            transform: Similarity {
                rotation: Quat::IDENTITY,
                translation: Vec3::new(1., 1., 0.),
                scale: 1.0,
            },
        }),
        vertices: own.vertices.clone(),
        polygons: own.polygons.clone(),
        children: own.children.clone(),
    });
    root.children.push(Cluster {
        instance: Some(InstanceOf {
            original: 0,
            exact: true,
            transform: Similarity {
                rotation: Quat::from_rotation_x(0.3),
                translation: Vec3::new(-1., 2., 0.),
                scale: 2.0,
            },
        }),
        ..Cluster::default()
    });
    s.root = root;
    s.suns
        .push(light(Vec3::new(0.3, 0.2, 1.0).normalize(), &[800.0, 700.0]));
    s.sky.push(light(Vec3::Z, &[100.0, 80.0]));
    s.cameras.push(Camera {
        name: Some("main".into()),
        position: Vec3::new(0., -10., 3.),
        target: Vec3::ZERO,
        up: Vec3::Z,
        fovy_deg: 45.0,
    });
    s
}
