use super::*;
use glam::{Quat, Vec3};

/// A small scene with every feature: two-sided material, an original with a nested original,
/// exact and approximate instances, lights and a camera.
pub(crate) fn sample() -> Scene {
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

#[test]
fn compile_open_decompile() {
    let s = sample();
    let bytes = compile(&s).unwrap();
    let view = read_image(&bytes).unwrap();
    let info = *view.info();
    // twig = 2, branch = 1 + 3 * 2 = 7; scene = 1 + 1 + (1 + 2) + 7 = 12
    assert_eq!(info.expanded_polygons, 12);
    assert_eq!(info.instancing_depth, 2);
    assert_eq!(info.originals, 2);
    assert_eq!(info.exact_instances, 3 + 1 + 1);
    assert_eq!(info.approximate_instances, 1);
    let back = decompile(&view).unwrap();
    // Originals were reordered (twig before branch); recompiling gives the same bytes.
    assert_eq!(back.originals[0].name, "twig");
    assert_eq!(compile(&back).unwrap(), bytes);
}

#[test]
fn expansion_counts_and_order() {
    struct Count(u64, Vec<u64>);
    impl ExpandVisitor for Count {
        type Error = ();
        fn node(&mut self, n: &ExpandedNode<'_>) -> Result<(), ()> {
            assert_eq!(n.first_id, self.0);
            self.0 += n.cluster.polygons.len() as u64;
            self.1.push(n.first_id);
            Ok(())
        }
    }
    let s = sample();
    let mut c = Count(0, Vec::new());
    assert_eq!(expand(&s, &mut c), Ok(12));
    assert_eq!(c.0, 12);
}

#[test]
fn refuses_cycles_and_bad_content() {
    let mut s = sample();
    // twig instances branch: branch -> twig -> branch.
    s.originals[1].root.children.push(Cluster {
        instance: Some(InstanceOf {
            original: 0,
            exact: true,
            transform: Similarity::IDENTITY,
        }),
        ..Cluster::default()
    });
    let e = compile(&s).unwrap_err();
    assert!(e.message.contains("cycle"), "{e}");
    let mut s = sample();
    s.root.children[0].polygons[0].corners[1] = 99;
    let e = compile(&s).unwrap_err();
    assert!(
        e.to_string().contains("scene > cluster 'lamp' > polygon 0"),
        "{e}"
    );
    let mut s = sample();
    s.materials[1].data.tau[1] = 0.9;
    assert!(
        compile(&s)
            .unwrap_err()
            .to_string()
            .contains("material 'leaf'")
    );
}

#[test]
fn refuses_placements_beyond_f32() {
    let mut s = sample();
    s.root.children.push(Cluster {
        instance: Some(InstanceOf {
            original: 1,
            exact: true,
            transform: Similarity {
                rotation: Quat::IDENTITY,
                translation: Vec3::new(3.4e38, 0., 0.),
                scale: 3e38,
            },
        }),
        ..Cluster::default()
    });
    let e = compile(&s).unwrap_err();
    assert!(e.message.contains("beyond the range"), "{e}");
    assert!(!e.message.contains("internal"), "{e}");
}

#[test]
fn refuses_unused_values() {
    let mut s = sample();
    s.suns[0].irradiance[5] = 1.0;
    assert!(
        compile(&s)
            .unwrap_err()
            .message
            .contains("past the band count")
    );
    let mut s = sample();
    s.materials[0].data.rho_back[0] = 0.5;
    assert!(
        compile(&s)
            .unwrap_err()
            .to_string()
            .contains("material 'white'")
    );
}
