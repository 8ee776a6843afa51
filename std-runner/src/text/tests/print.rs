//! The printer's output form and round trips of hand-built scenes.

use super::{ok, round_trips};
use crate::scene::*;
use crate::text::print;
use glam::{Quat, Vec3};

#[test]
fn output_form() {
    let text = "hirad 1
bands par nir

material leaf rho 0.1 0.45 back_rho 0.1 0.45 tau 0.05 0.45
material soil rho 0.1 0.2
material \"scene\" rho 0 0 emit 1 2

sun from 0 0 1 irradiance 800 700

sky from 0.6 0 0.8 irradiance 10 20

camera main pos 0 -5 1 target 0 0 0 up 0 0 1 fovy 40

original \"my twig\" name twig axis 3 age 1.5 {
  v 0 0 0
  v 0.1 0 0
  v 0.1 0.1 0
  tri leaf 0 1 2
}

scene ground {
  v -1 -1 0
  v 1 -1 0
  v 1 1 0
  v -1 1 0
  quad soil 0 1 2 3
  instance \"my twig\" exact name a translate 0 0 0.5 quat 0 0 0 1 scale 2
  instance \"my twig\" approx axis 2 {
    v 0 0 0
    v 0.2 0 0
    v 0.2 0.2 0
    tri \"scene\" 0 1 2
  }
  instance \"my twig\" approx {}
  cluster empty axis 1 {}
}
";
    let s = ok(text);
    assert_eq!(print(&s), text);
    round_trips(&s);
}

#[test]
fn awkward_names_and_floats_round_trip() {
    let mut s = Scene::new(1);
    s.band_names = vec!["".into()];
    for (i, name) in [
        "v",
        "1abc",
        "a b",
        "\"",
        "\\",
        "\n\t\r\u{0}\u{7f}",
        "é",
        "inf",
        "",
    ]
    .iter()
    .enumerate()
    {
        let mut m = MaterialData::black(1);
        m.rho_front[0] = [0.1, 1e-45, -0.0, 1.0, 0.3333333][i % 5];
        m.emit_front[0] = [0.0, -0.0, 3e38, 1e-7, 5.0][i % 5];
        s.materials.push(Material {
            name: name.to_string(),
            data: m,
        });
    }
    let mut c = Cluster::named("in\"side");
    c.age = Some(-0.0);
    c.axis = Some(u32::MAX - 1);
    let a = c.vertex(Vec3::new(1e-30, -0.0, 123456.79));
    let b = c.vertex(Vec3::new(1.0, 1e-30, 123456.79));
    let d = c.vertex(Vec3::new(1e-30, 1.0, 123456.79));
    c.polygons.push(triangle(a, b, d, 5));
    s.root.children.push(c);
    s.cameras.push(Camera {
        name: Some("".into()),
        position: Vec3::new(0., 0., -1.),
        target: Vec3::ZERO,
        up: Vec3::Y,
        fovy_deg: 179.9,
    });
    s.suns.push(light(Vec3::new(0.0, -0.0, -1.0), &[0.0]));
    s.originals.push(Original {
        name: "o".into(),
        root: Cluster::default(),
    });
    s.root.children.push(Cluster {
        instance: Some(InstanceOf {
            original: 0,
            exact: true,
            transform: Similarity {
                rotation: Quat::from_xyzw(-0.0, 0.0, 0.0, 1.0),
                translation: Vec3::new(-0.0, 0.0, 0.0),
                scale: f32::MIN_POSITIVE,
            },
        }),
        ..Cluster::default()
    });
    s.check().unwrap();
    round_trips(&s);
    let text = print(&s);
    assert!(text.contains("quat 1 -0 0 0"), "{text}");
    assert!(text.contains("translate -0 0 0"), "{text}");
}

#[test]
fn printing_never_recurses_deeply_nor_panics_on_invalid_models() {
    let mut root = Cluster::default();
    for _ in 0..100_000 {
        root = Cluster {
            children: vec![root],
            ..Cluster::default()
        };
    }
    let mut s = Scene::new(1);
    s.root.children.push(root);
    s.root.polygons.push(triangle(0, 1, 7, 99));
    s.root.children.push(Cluster {
        instance: Some(InstanceOf {
            original: 42,
            exact: true,
            transform: Similarity::IDENTITY,
        }),
        ..Cluster::default()
    });
    let text = print(&s);
    assert!(text.lines().count() > 100_000);
    assert!(crate::text::parse(text.as_bytes()).is_err());
    // Dropping the model recursively is the model's business; leak it to keep the test
    // about printing.
    std::mem::forget(s);
}
