//! Geometry builders shared by the generators. Every builder appends vertices and polygons to
//! a cluster and keeps the format's rules: quads planar and strictly convex, fronts
//! counter-clockwise, no degenerate polygons (tiny or collinear pieces are skipped).

use crate::scene::{Cluster, quad, triangle};
use glam::{Quat, Vec3};
use hirad_core::geometry::polygon_shape;

/// Two unit vectors completing `d` (unit) to a right-handed frame.
pub fn frame(d: Vec3) -> (Vec3, Vec3) {
    let helper = if d.z.abs() < 0.9 { Vec3::Z } else { Vec3::X };
    let u = helper.cross(d).normalize();
    (u, d.cross(u))
}

/// Adds a triangle if it is a valid polygon; returns whether it was added.
pub fn add_triangle(c: &mut Cluster, p: [Vec3; 3], material: u32) -> bool {
    if polygon_shape(&p).is_err() {
        return false;
    }
    let a = c.vertex(p[0]);
    let b = c.vertex(p[1]);
    let d = c.vertex(p[2]);
    c.polygons.push(triangle(a, b, d, material));
    true
}

/// Adds a quad if valid, else its two triangles where those are valid.
pub fn add_quad(c: &mut Cluster, p: [Vec3; 4], material: u32) -> usize {
    if polygon_shape(&p).is_ok() {
        let i: Vec<u32> = p.iter().map(|v| c.vertex(*v)).collect();
        c.polygons.push(quad(i[0], i[1], i[2], i[3], material));
        return 1;
    }
    add_triangle(c, [p[0], p[1], p[2]], material) as usize
        + add_triangle(c, [p[0], p[2], p[3]], material) as usize
}

/// A frustum (open cylinder) from `a` (radius `ra`) to `b` (radius `rb`) with `sides` planar
/// quads facing outwards; returns the polygons added.
pub fn cylinder(
    c: &mut Cluster,
    a: Vec3,
    b: Vec3,
    ra: f32,
    rb: f32,
    sides: u32,
    material: u32,
) -> usize {
    let axis = b - a;
    let len = axis.length();
    if len <= 0.0 || sides < 3 {
        return 0;
    }
    let d = axis / len;
    let (u, v) = frame(d);
    let ring = |center: Vec3, r: f32, k: u32| {
        let t = k as f32 / sides as f32 * std::f32::consts::TAU;
        center + (u * t.cos() + v * t.sin()) * r
    };
    let mut n = 0;
    for k in 0..sides {
        // Counter-clockwise seen from outside.
        let p = [
            ring(a, ra, k),
            ring(a, ra, k + 1),
            ring(b, rb, k + 1),
            ring(b, rb, k),
        ];
        n += add_quad(c, p, material);
    }
    n
}

/// A box with outward fronts (or inward with `inward`, for rooms); returns the polygons added.
pub fn cuboid(c: &mut Cluster, min: Vec3, max: Vec3, material: u32, inward: bool) -> usize {
    let (x0, y0, z0, x1, y1, z1) = (min.x, min.y, min.z, max.x, max.y, max.z);
    let v = |x, y, z| Vec3::new(x, y, z);
    let faces = [
        [v(x0, y0, z0), v(x0, y1, z0), v(x1, y1, z0), v(x1, y0, z0)], // -z
        [v(x0, y0, z1), v(x1, y0, z1), v(x1, y1, z1), v(x0, y1, z1)], // +z
        [v(x0, y0, z0), v(x1, y0, z0), v(x1, y0, z1), v(x0, y0, z1)], // -y
        [v(x0, y1, z0), v(x0, y1, z1), v(x1, y1, z1), v(x1, y1, z0)], // +y
        [v(x0, y0, z0), v(x0, y0, z1), v(x0, y1, z1), v(x0, y1, z0)], // -x
        [v(x1, y0, z0), v(x1, y1, z0), v(x1, y1, z1), v(x1, y0, z1)], // +x
    ];
    let mut n = 0;
    for mut f in faces {
        if inward {
            f.reverse();
        }
        n += add_quad(c, f, material);
    }
    n
}

/// A flat leaf blade: a kite from `base` to `base + length * dir`, widest (`width`) at 40% of
/// its length, its front facing `up` as much as the blade allows; returns the polygons added
/// (1, or 2 triangles if the kite came out non-planar, 0 if degenerate).
pub fn leaf(
    c: &mut Cluster,
    base: Vec3,
    dir: Vec3,
    up: Vec3,
    length: f32,
    width: f32,
    material: u32,
) -> usize {
    let d = dir.normalize();
    let side = d.cross(up).try_normalize().unwrap_or_else(|| frame(d).0);
    let mid = base + d * (length * 0.4);
    let tip = base + d * length;
    let half = side * (width * 0.5);
    // Counter-clockwise seen from `up` (`side = d x up` points to the right).
    add_quad(c, [base, mid + half, tip, mid - half], material)
}

/// A rotation taking +z to `d` (unit), then turning by `roll` radians about `d`.
pub fn rotation_to(d: Vec3, roll: f32) -> Quat {
    Quat::from_axis_angle(d, roll) * Quat::from_rotation_arc(Vec3::Z, d)
}

/// A UV sphere of `stacks` x `slices` facets (quads, triangle fans at the poles); fronts
/// face outwards; returns the polygons added.
pub fn sphere(
    c: &mut Cluster,
    center: Vec3,
    radius: f32,
    stacks: u32,
    slices: u32,
    material: u32,
) -> usize {
    let p = |i: u32, j: u32| {
        let th = i as f32 / stacks as f32 * std::f32::consts::PI;
        let ph = j as f32 / slices as f32 * std::f32::consts::TAU;
        center + Vec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()) * radius
    };
    let mut n = 0;
    for i in 0..stacks {
        for j in 0..slices {
            let (a, b, cc, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            if i == 0 {
                n += add_triangle(c, [a, b, cc], material) as usize;
            } else if i == stacks - 1 {
                n += add_triangle(c, [a, b, d], material) as usize;
            } else {
                n += add_quad(c, [a, b, cc, d], material);
            }
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    fn outward(c: &Cluster, center: Vec3) -> bool {
        c.polygons.iter().all(|p| {
            let corners: Vec<Vec3> = p.corners[..p.corner_count()]
                .iter()
                .map(|&i| c.vertices[i as usize])
                .collect();
            let s = polygon_shape(&corners).unwrap();
            let mid = corners.iter().copied().sum::<Vec3>() / corners.len() as f32;
            s.normal.dot(mid - center) > 0.0
        })
    }

    #[test]
    fn shapes_are_valid_and_face_out() {
        let mut c = Cluster::default();
        assert_eq!(
            cylinder(
                &mut c,
                Vec3::ZERO,
                Vec3::new(0.1, 0.2, 1.0),
                0.1,
                0.05,
                5,
                0
            ),
            5
        );
        let mut b = Cluster::default();
        assert_eq!(cuboid(&mut b, Vec3::ZERO, Vec3::ONE, 0, false), 6);
        assert!(outward(&b, Vec3::splat(0.5)));
        let mut s = Cluster::default();
        assert_eq!(sphere(&mut s, Vec3::ONE, 0.01, 6, 8, 0), 48);
        assert!(outward(&s, Vec3::ONE));
        let mut l = Cluster::default();
        assert_eq!(leaf(&mut l, Vec3::ZERO, Vec3::X, Vec3::Z, 0.1, 0.04, 0), 1);
        for p in &l.polygons {
            let corners: Vec<Vec3> = p.corners[..4]
                .iter()
                .map(|&i| l.vertices[i as usize])
                .collect();
            assert!(polygon_shape(&corners).unwrap().normal.dot(Vec3::Z) > 0.9);
        }
    }
}
