//! Option parsing, camera checks, the default camera, scene bounds and the projection.

use super::camera::{
    Projection, Size, camera_arg, default_camera, parse_camera, parse_size, scene_bounds,
};
use crate::scene::{Camera, Cluster, InstanceOf, Original, Scene, Similarity, quad};
use glam::{Quat, Vec3};
use hirad_core::geometry::{Aabb, camera_ok};

#[test]
fn sizes() {
    assert_eq!(
        parse_size("640x480").unwrap(),
        Size {
            width: 640,
            height: 480
        }
    );
    assert_eq!(parse_size(" 2X1 ").unwrap().width, 2);
    let e = parse_size("640").unwrap_err().to_string();
    assert!(e.contains("WIDTHxHEIGHT") && e.contains("`640`"), "{e}");
    let e = parse_size("0x10").unwrap_err().to_string();
    assert!(e.contains("width `0`"), "{e}");
    let e = parse_size("10x99999").unwrap_err().to_string();
    assert!(e.contains("height `99999`") && e.contains("16384"), "{e}");
    let e = parse_size("ax3").unwrap_err().to_string();
    assert!(e.contains("width `a`"), "{e}");
    assert!(parse_size("3x-2").is_err());
    assert!(parse_size("1x2x3").is_err());
}

#[test]
fn cameras() {
    let c = parse_camera("0,-5,1, 0,0,1, 0,0,1, 60").unwrap();
    assert_eq!(c.position, Vec3::new(0.0, -5.0, 1.0));
    assert_eq!(c.target, Vec3::new(0.0, 0.0, 1.0));
    assert_eq!(c.up, Vec3::Z);
    assert_eq!(c.fovy_deg, 60.0);
    let e = parse_camera("0,-5,1,0,0,1,0,0,1").unwrap_err().to_string();
    assert!(
        e.contains("10 comma-separated") && e.contains("found 9"),
        "{e}"
    );
    let e = parse_camera("0,-5,abc,0,0,1,0,0,1,60")
        .unwrap_err()
        .to_string();
    assert!(e.contains("number 3 (pz) `abc`"), "{e}");
    let e = parse_camera("0,-5,1,0,0,1,0,0,1,NaN")
        .unwrap_err()
        .to_string();
    assert!(e.contains("number 10 (fovy_deg)"), "{e}");
    let e = parse_camera("0,-5,1,0,0,1,0,0,inf,60")
        .unwrap_err()
        .to_string();
    assert!(e.contains("number 9 (uz)"), "{e}");
    let e = parse_camera("1,1,1,1,1,1,0,0,1,60")
        .unwrap_err()
        .to_string();
    assert!(e.contains("eye is at the target"), "{e}");
    let e = parse_camera("0,0,5,0,0,0,0,0,1,60")
        .unwrap_err()
        .to_string();
    assert!(e.contains("up direction"), "{e}");
    let e = parse_camera("0,-5,0,0,0,0,0,0,1,180")
        .unwrap_err()
        .to_string();
    assert!(e.contains("field of view 180"), "{e}");
}

#[test]
fn projection_has_its_origin_top_left() {
    // Looking along +y from 5 m away with a 90-degree vertical field of view onto 200 x 100
    // pixels: 1 m at 5 m distance is 50 / 5 = 10 pixels both ways.
    let camera = Camera {
        name: None,
        position: Vec3::new(0.0, -5.0, 0.0),
        target: Vec3::ZERO,
        up: Vec3::Z,
        fovy_deg: 90.0,
    };
    let p = Projection::new(
        &camera,
        Size {
            width: 200,
            height: 100,
        },
    );
    let close = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9;
    assert!(close(p.pixel(Vec3::ZERO).unwrap(), [100.0, 50.0]));
    assert!(
        close(p.pixel(Vec3::new(0.0, 0.0, 1.0)).unwrap(), [100.0, 40.0]),
        "up is smaller y"
    );
    assert!(
        close(p.pixel(Vec3::new(1.0, 0.0, 0.0)).unwrap(), [110.0, 50.0]),
        "+x is right"
    );
    assert!(close(
        p.pixel(Vec3::new(-5.0, 0.0, 5.0)).unwrap(),
        [50.0, 0.0]
    ));
    assert!(
        p.pixel(Vec3::new(0.0, -6.0, 0.0)).is_none(),
        "behind the eye"
    );
}

#[test]
fn default_camera_sees_the_whole_box() {
    let size = Size {
        width: 64,
        height: 256,
    };
    let b = Aabb::new(Vec3::new(1000.0, 2.0, -3.0), Vec3::new(1004.0, 2.5, 9.0));
    let c = default_camera(&b, size).unwrap();
    assert!(camera_ok(c.position, c.target, c.up, c.fovy_deg));
    assert_eq!(c.target, Vec3::new(1002.0, 2.25, 3.0));
    let dir = (c.position - c.target).normalize();
    assert!((dir - Vec3::new(1.0, -1.0, 1.0).normalize()).length() < 1e-4);
    let p = Projection::new(&c, size);
    for i in 0..8 {
        let corner = Vec3::new(
            if i & 1 == 0 { b.min.x } else { b.max.x },
            if i & 2 == 0 { b.min.y } else { b.max.y },
            if i & 4 == 0 { b.min.z } else { b.max.z },
        );
        let [x, y] = p.pixel(corner).unwrap();
        assert!(
            (0.0..=64.0).contains(&x) && (0.0..=256.0).contains(&y),
            "{corner} at {x},{y}"
        );
    }
    let e = default_camera(&Aabb::EMPTY, size).unwrap_err().to_string();
    assert!(e.contains("no geometry"), "{e}");
}

#[test]
fn bounds_follow_instances() {
    let mut s = Scene::new(1);
    let mut leaf = Cluster::named("leaf");
    let a = leaf.vertex(Vec3::new(0.0, 0.0, 0.0));
    let b = leaf.vertex(Vec3::new(1.0, 0.0, 0.0));
    let c = leaf.vertex(Vec3::new(1.0, 1.0, 0.0));
    let d = leaf.vertex(Vec3::new(0.0, 1.0, 0.0));
    leaf.vertex(Vec3::splat(100.0)); // unused by any polygon: not in the box
    leaf.polygons.push(quad(a, b, c, d, 0));
    s.originals.push(Original {
        name: "leaf".into(),
        root: leaf,
    });
    let place = |t: Vec3, scale: f32| Cluster {
        instance: Some(InstanceOf {
            original: 0,
            exact: true,
            transform: Similarity::checked(Quat::IDENTITY, t, scale).unwrap(),
        }),
        ..Cluster::default()
    };
    s.root.children.push(place(Vec3::new(10.0, 0.0, 0.0), 1.0));
    s.root.children.push(place(Vec3::new(0.0, 0.0, 5.0), 2.0));
    let got = scene_bounds(&s);
    assert_eq!(
        got,
        Aabb::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(11.0, 2.0, 5.0))
    );
    assert!(scene_bounds(&Scene::new(1)).is_empty());
}

#[test]
fn a_camera_prints_as_the_argument_that_gives_it_back() {
    let b = Aabb {
        min: Vec3::new(-1.3, 0.1, -0.7),
        max: Vec3::new(2.9, 1.7, 3.3),
    };
    let c = default_camera(&b, parse_size("320x240").unwrap()).unwrap();
    let arg = camera_arg(&c);
    assert!(!arg.contains("-0,") && !arg.contains(' '), "{arg}");
    let back = parse_camera(&arg).unwrap();
    assert_eq!(
        (back.position, back.target, back.up, back.fovy_deg),
        (c.position, c.target, c.up, c.fovy_deg)
    );
}
