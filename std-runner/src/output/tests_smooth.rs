//! Smooth shading: radiosity interpolated across shared corners, not across creases,
//! material boundaries or a surface's two faces; T-junctions; perspective-correct
//! interpolation; `--shading flat` as before.

use super::camera::{Projection, Size};
use super::frame::{Frame, channel_names};
use super::image::{ImageSink, Shading};
use super::interp::{corner_weights, inverse_bilinear};
use super::raster::Rasterizer;
use super::smooth::PatchStore;
use crate::scene::Camera;
use glam::Vec3;
use hirad_core::sink::{PatchResult, Sink};
use std::f32::consts::PI;

/// 2 m in front of the plane y = 0 looking along +y, z up, 90 degrees: the plane shows
/// 4 m x 4 m on a square image.
fn camera() -> Camera {
    Camera {
        name: None,
        position: Vec3::new(0.0, -2.0, 0.0),
        target: Vec3::ZERO,
        up: Vec3::Z,
        fovy_deg: 90.0,
    }
}

fn size(n: u32) -> Size {
    Size {
        width: n,
        height: n,
    }
}

/// A patch of one band: corners, normal, material, front and back radiance (radiosity / pi).
struct P {
    corners: Vec<Vec3>,
    normal: Vec3,
    material: u32,
    front: Vec<f32>,
    back: Vec<f32>,
}

/// A rectangle in the plane y = `y` from (x0, z0) to (x1, z1), facing the camera, of
/// radiance `l` (one band, one-sided).
fn rect(x0: f32, z0: f32, x1: f32, z1: f32, y: f32, l: f32) -> P {
    P {
        corners: vec![
            Vec3::new(x0, y, z0),
            Vec3::new(x1, y, z0),
            Vec3::new(x1, y, z1),
            Vec3::new(x0, y, z1),
        ],
        normal: -Vec3::Y,
        material: 0,
        front: vec![l * PI],
        back: vec![],
    }
}

fn feed(sink: &mut impl Sink<Error = anyhow::Error>, patches: &[P]) {
    for (id, p) in patches.iter().enumerate() {
        sink.patch(&PatchResult {
            id: id as u64,
            corners: &p.corners,
            normal: p.normal,
            material: p.material,
            radiosity: [&p.front, &p.back],
        })
        .unwrap();
    }
}

fn render(n: u32, shading: Shading, patches: &[P]) -> Frame {
    let dir = tempfile::tempdir().unwrap();
    let mut sink = ImageSink::new(&dir.path().join("x.exr"), &camera(), size(n), 1, 1, &[])
        .unwrap()
        .with_shading(shading);
    feed(&mut sink, patches);
    sink.frame()
}

/// A 2 m square centred on the origin split into 4 patches of radiance 1, 2, 3, 4.
fn four() -> Vec<P> {
    vec![
        rect(-1.0, -1.0, 0.0, 0.0, 0.0, 1.0),
        rect(0.0, -1.0, 1.0, 0.0, 0.0, 2.0),
        rect(-1.0, 0.0, 0.0, 1.0, 0.0, 3.0),
        rect(0.0, 0.0, 1.0, 1.0, 0.0, 4.0),
    ]
}

fn px(f: &Frame, x: u32, y: u32) -> f32 {
    f.pixel(x, y)[0]
}

#[test]
fn shared_corners_blend_and_the_old_edges_vanish() {
    // 80 pixels over 4 m: 20 pixels per metre; the square spans pixels 20..60, the patch
    // edge x = 0 lies between pixels 39 and 40. Row 50 crosses the lower patches (1 and 2).
    let flat = render(80, Shading::Flat, &four());
    let smooth = render(80, Shading::Smooth, &four());
    assert_eq!(px(&flat, 39, 50), 1.0);
    assert_eq!(px(&flat, 40, 50), 2.0);
    let jump = (px(&smooth, 40, 50) - px(&smooth, 39, 50)).abs();
    assert!(
        jump < 0.1,
        "jump across the old edge {jump}, patches differ by 1"
    );
    // Every step along the row is small, and the row rises from left to right.
    for x in 21..59 {
        let (a, b) = (px(&smooth, x, 50), px(&smooth, x + 1, 50));
        assert!(
            b >= a - 1e-5 && b - a < 0.1,
            "pixels {x}, {}: {a} {b}",
            x + 1
        );
    }
    // Background stays empty.
    assert_eq!(px(&smooth, 5, 5), 0.0);
}

#[test]
fn the_shared_vertex_holds_the_area_weighted_mean() {
    // On an odd image the centre pixel's centre is the origin: the vertex of all four.
    for n in [41, 81] {
        let f = render(n, Shading::Smooth, &four());
        let c = px(&f, n / 2, n / 2);
        assert!((c - 2.5).abs() < 1e-4, "{n} pixels: {c}");
    }
    // Unequal areas: a 2 m x 1 m patch of 1 beside a 1 m x 1 m patch of 4 share the edge
    // x = 0; its ends get (2 * 1 + 1 * 4) / 3 = 2.
    let mut store = PatchStore::new(1);
    let patches = [
        rect(-2.0, 0.0, 0.0, 1.0, 0.0, 1.0),
        rect(0.0, 0.0, 1.0, 1.0, 0.0, 4.0),
    ];
    for p in &patches {
        store.push(&PatchResult {
            id: 0,
            corners: &p.corners,
            normal: p.normal,
            material: 0,
            radiosity: [&p.front, &p.back],
        });
    }
    let v = store.corner_values();
    let left = v.get(0, 0);
    assert!((left[1] / PI - 2.0).abs() < 1e-5, "{left:?}");
    assert!(
        (left[0] / PI - 1.0).abs() < 1e-5,
        "an outer corner keeps its own"
    );
}

#[test]
fn creases_do_not_blend() {
    // A floor (z = -1, facing up, radiance 1) meeting a back wall (y = 2, facing the
    // camera, radiance 3) at 90 degrees.
    let floor = P {
        corners: vec![
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(1.0, 2.0, -1.0),
            Vec3::new(-1.0, 2.0, -1.0),
        ],
        normal: Vec3::Z,
        material: 0,
        front: vec![PI],
        back: vec![],
    };
    let wall = rect(-1.0, -1.0, 1.0, 1.0, 2.0, 3.0);
    let f = render(80, Shading::Smooth, &[floor, wall]);
    let mut seen = [false; 2];
    for v in f.data.iter().filter(|v| **v > 0.0) {
        let one = (v - 1.0).abs() < 1e-5;
        let three = (v - 3.0).abs() < 1e-5;
        assert!(one || three, "a blended value {v}");
        seen[usize::from(three)] = true;
    }
    assert_eq!(seen, [true, true]);
}

/// Two coplanar 1 m patches side by side (radiance 1 and 3); `second` edits the right one.
fn pair(second: impl FnOnce(&mut P)) -> Frame {
    let mut right = rect(0.0, -0.5, 1.0, 0.5, 0.0, 3.0);
    second(&mut right);
    render(
        80,
        Shading::Smooth,
        &[rect(-1.0, -0.5, 0.0, 0.5, 0.0, 1.0), right],
    )
}

fn blended(f: &Frame) -> bool {
    f.data
        .iter()
        .any(|v| *v > 1.0 + 1e-4 && (v - 3.0).abs() > 1e-4)
}

#[test]
fn material_boundaries_do_not_blend() {
    assert!(blended(&pair(|_| {})), "one material blends");
    assert!(!blended(&pair(|p| p.material = 1)));
}

#[test]
fn a_surfaces_two_faces_do_not_blend() {
    // The right patch faces away (its back, radiance 3, is seen); both two-sided.
    let f = pair(|p| {
        p.corners.reverse();
        p.normal = Vec3::Y;
        p.back = vec![3.0 * PI];
        p.front = vec![7.0 * PI];
    });
    assert!(!blended(&f));
    assert!(f.data.iter().any(|v| (v - 3.0).abs() < 1e-5));
}

#[test]
fn t_junctions_take_the_patch_whose_edge_they_lie_on() {
    // A 2 m x 2 m patch (radiance 1) beside two 1 m patches (3 below, 5 above): the
    // small ones' shared corner (1, 0) lies inside the big one's right edge.
    let patches = [
        rect(-1.0, -1.0, 1.0, 1.0, 0.0, 1.0),
        rect(1.0, -1.0, 2.0, 0.0, 0.0, 3.0),
        rect(1.0, 0.0, 2.0, 1.0, 0.0, 5.0),
    ];
    let mut store = PatchStore::new(1);
    for p in &patches {
        store.push(&PatchResult {
            id: 0,
            corners: &p.corners,
            normal: p.normal,
            material: 0,
            radiosity: [&p.front, &p.back],
        });
    }
    let v = store.corner_values();
    // Lower small patch: corner 3 is (1, 0): (4 * 1 + 1 * 3 + 1 * 5) / 6 = 2.
    let at = v.get(1, 0)[3] / PI;
    assert!((at - 2.0).abs() < 1e-5, "T-junction value {at}");
    // Its corner (1, -1) is a corner of the big patch: (4 * 1 + 1 * 3) / 5.
    let at = v.get(1, 0)[0] / PI;
    assert!((at - 7.0 / 5.0).abs() < 1e-5, "shared corner {at}");
}

#[test]
fn triangles_interpolate_barycentrically() {
    // The square as two triangles of radiance 1 and 3 sharing the diagonal: at the
    // diagonal's corners both get 2, at the outer corners their own.
    let tri = |c: [Vec3; 3], l: f32| P {
        corners: c.to_vec(),
        normal: -Vec3::Y,
        material: 0,
        front: vec![l * PI],
        back: vec![],
    };
    let (a, b, c, d) = (
        Vec3::new(-1.0, 0.0, -1.0),
        Vec3::new(1.0, 0.0, -1.0),
        Vec3::new(1.0, 0.0, 1.0),
        Vec3::new(-1.0, 0.0, 1.0),
    );
    let patches = [tri([a, b, c], 1.0), tri([a, c, d], 3.0)];
    let f = render(81, Shading::Smooth, &patches);
    // The centre lies on the diagonal a-c: 2. Pixel (60, 60) is world (1, -1) (corner b,
    // own value 1) region: near it the value approaches 1.
    assert!((px(&f, 40, 40) - 2.0).abs() < 1e-4);
    assert!((px(&f, 59, 59) - 1.0).abs() < 0.1, "{}", px(&f, 59, 59));
    assert!((px(&f, 21, 21) - 3.0).abs() < 0.1, "{}", px(&f, 21, 21));
    let mut w = [0.0; 4];
    let c2 = [[0.0, 0.0], [2.0, 0.0], [0.0, 1.0]];
    corner_weights(&c2, [0.0, 1.0], &mut w);
    assert_eq!(&w[..3], &[0.0, 0.0, 1.0]);
    corner_weights(&c2, [2.0 / 3.0, 1.0 / 3.0], &mut w);
    assert!(w[..3].iter().all(|x| (x - 1.0 / 3.0).abs() < 1e-12));
}

#[test]
fn inverse_bilinear_finds_the_parameters() {
    let quad = [[0.0, 0.0], [3.0, 0.5], [2.5, 2.0], [-0.5, 1.5]];
    for (u, v) in [(0.0, 0.0), (0.3, 0.7), (1.0, 0.2), (0.5, 1.0), (0.9, 0.9)] {
        let p = [0, 1].map(|k| {
            (1.0 - u) * (1.0 - v) * quad[0][k]
                + u * (1.0 - v) * quad[1][k]
                + u * v * quad[2][k]
                + (1.0 - u) * v * quad[3][k]
        });
        let [gu, gv] = inverse_bilinear(&quad, p);
        assert!(
            (gu - u).abs() < 1e-9 && (gv - v).abs() < 1e-9,
            "{u} {v}: {gu} {gv}"
        );
    }
}

#[test]
fn interpolation_is_perspective_correct() {
    // A floor from y = 0 to y = 8 at z = -1; corner radiosity 0 at the near edge, 8 pi at
    // the far edge: the radiance at a world point is its y.
    let c = Camera {
        position: Vec3::new(0.0, -1.0, 0.0),
        target: Vec3::new(0.0, 0.0, -0.5),
        ..camera()
    };
    let corners = [
        Vec3::new(-4.0, 0.0, -1.0),
        Vec3::new(4.0, 0.0, -1.0),
        Vec3::new(4.0, 8.0, -1.0),
        Vec3::new(-4.0, 8.0, -1.0),
    ];
    let mut r = Rasterizer::new(&c, size(100), 1, 1).unwrap();
    r.track_owners();
    r.draw(&corners, Vec3::Z, [&[PI], &[]]).unwrap();
    let values = [0.0, 0.0, 8.0 * PI, 8.0 * PI];
    r.shade(0, &corners, Vec3::Z, [&values, &[]]);
    let f = r.frame(channel_names(1, &[]));
    let proj = Projection::new(&c, size(100));
    for y in [1.0f32, 2.0, 4.0] {
        let [ix, iy] = proj.pixel(Vec3::new(0.0, y, -1.0)).unwrap();
        let (x, row) = (ix as u32, iy as u32);
        // The pixel's centre is within half a pixel of the point: compare with the
        // values of the rows around it.
        let got = px(&f, x, row);
        let world_row = |r: u32| {
            // y of the floor seen at the centre of row r, by bisection on the projection.
            let (mut lo, mut hi) = (0.0f32, 8.0f32);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                let [_, my] = proj.pixel(Vec3::new(0.0, mid, -1.0)).unwrap();
                if my > f64::from(r) + 0.5 {
                    lo = mid
                } else {
                    hi = mid
                }
            }
            0.5 * (lo + hi)
        };
        let want = world_row(row);
        assert!(
            (got - want).abs() < 0.02 * want.max(1.0),
            "y {y}: got {got}, want {want}"
        );
    }
}

#[test]
fn flat_shading_is_the_old_picture() {
    let flat = render(80, Shading::Flat, &four());
    let mut r = Rasterizer::new(&camera(), size(80), 1, 1).unwrap();
    feed(&mut r, &four());
    assert_eq!(flat, r.frame(channel_names(1, &[])));
    assert_ne!(flat, render(80, Shading::Smooth, &four()));
}

#[test]
fn smooth_shading_keeps_the_depth_order() {
    // A small patch in front of the square hides it in both shadings alike.
    let mut patches = four();
    patches.push(rect(-0.25, -0.25, 0.25, 0.25, -0.5, 9.0));
    let smooth = render(80, Shading::Smooth, &patches);
    let flat = render(80, Shading::Flat, &patches);
    for (s, f) in smooth.data.iter().zip(&flat.data) {
        assert_eq!(*s == 9.0, *f == 9.0);
        assert_eq!(*s == 0.0, *f == 0.0);
    }
}

#[test]
fn no_crack_in_value_at_a_t_junction() {
    // As above, drawn: along the big patch's right edge x = 1 (between pixels 59 and 60),
    // the row at z = 0 (row 40) crosses the junction. Without the fan the big patch would
    // show (1.4 + 1.8) / 2 = 1.6 there and the small ones 2: a jump of 0.4.
    let patches = [
        rect(-1.0, -1.0, 1.0, 1.0, 0.0, 1.0),
        rect(1.0, -1.0, 2.0, 0.0, 0.0, 3.0),
        rect(1.0, 0.0, 2.0, 1.0, 0.0, 5.0),
    ];
    let f = render(80, Shading::Smooth, &patches);
    for row in [40, 39, 30, 50] {
        let jump = (px(&f, 60, row) - px(&f, 59, row)).abs();
        assert!(
            jump < 0.15,
            "row {row}: {} | {}",
            px(&f, 59, row),
            px(&f, 60, row)
        );
    }
}

fn render_batched(n: u32, batch: usize, patches: &[P]) -> Frame {
    let dir = tempfile::tempdir().unwrap();
    let mut sink = ImageSink::new(&dir.path().join("x.exr"), &camera(), size(n), 1, 1, &[])
        .unwrap()
        .with_batch(batch);
    feed(&mut sink, patches);
    sink.frame()
}

#[test]
fn batches_bound_what_smooth_shading_keeps() {
    // Two squares of four patches side by side, a patch in front of them drawn last and
    // one behind them drawn first.
    let mut patches = vec![rect(-2.0, -2.0, 2.0, 2.0, 1.0, 7.0)];
    patches.extend(four());
    for p in four() {
        let mut q = p;
        for c in &mut q.corners {
            c.x += 2.5;
        }
        q.front[0] *= 0.5;
        patches.push(q);
    }
    patches.push(rect(-0.25, -0.25, 0.25, 0.25, -0.5, 9.0));
    let all = render(80, Shading::Smooth, &patches);
    // A batch as large as the scene: the same picture, bit for bit.
    for batch in [patches.len(), 1000] {
        assert_eq!(render_batched(80, batch, &patches).data, all.data);
    }
    // Batches of one patch share no corner: flat shading (to rounding).
    let flat = render(80, Shading::Flat, &patches);
    let ones = render_batched(80, 1, &patches);
    for (a, b) in ones.data.iter().zip(&flat.data) {
        assert!((a - b).abs() <= 1e-5 * b.abs().max(1.0), "{a} {b}");
    }
    // Batches of one square each: the same as one batch, for the squares share no corner.
    let squares = &patches[1..9];
    assert_eq!(
        render_batched(80, 4, squares).data,
        render(80, Shading::Smooth, squares).data
    );
    // Depth order holds across batches: the patch in front, in a later batch, hides the
    // squares; the one behind, in an earlier batch, shows only around them.
    let small = render_batched(80, 3, &patches);
    let near = |v: f32, l: f32| (v - l).abs() < 1e-4;
    for (s, f) in small.data.iter().zip(&flat.data) {
        assert_eq!(near(*s, 9.0), *f == 9.0);
        assert_eq!(near(*s, 7.0), *f == 7.0);
    }
}
