//! The surroundings of trees: a flat ground of tiles, the sun and sky, and a camera that
//! frames a box.
//!
//! Coordinates: z up, metres. Directions by elevation (degrees above the horizon) and
//! azimuth (degrees from +x towards +y).

use super::materials::Bands;
use crate::generate::shapes::add_quad;
use crate::generate::sky::{SkyModel, sky, sun};
use crate::scene::{Camera, Cluster, Original, Scene};
use glam::Vec3;
use hirad_core::geometry::Aabb;

/// A square of side `side` (m) centred on the origin at z = 0, facing up, in `tiles` x
/// `tiles` quads (so that results show where the ground is shaded); a cluster named
/// `ground`.
pub fn ground(side: f32, tiles: u32, material: u32) -> Cluster {
    let mut c = Cluster::named("ground");
    let n = tiles.max(1);
    let step = side / n as f32;
    let p = |i: u32, j: u32| {
        Vec3::new(
            -0.5 * side + i as f32 * step,
            -0.5 * side + j as f32 * step,
            0.0,
        )
    };
    for j in 0..n {
        for i in 0..n {
            // Counter-clockwise seen from above.
            add_quad(
                &mut c,
                [p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1)],
                material,
            );
        }
    }
    c
}

/// A unit direction `elevation_deg` above the horizon, `azimuth_deg` from +x towards +y.
pub fn direction(elevation_deg: f32, azimuth_deg: f32) -> Vec3 {
    let (e, a) = (elevation_deg.to_radians(), azimuth_deg.to_radians());
    Vec3::new(e.cos() * a.cos(), e.cos() * a.sin(), e.sin()).normalize()
}

/// Adds a clear-day sun at the given position and a uniform sky of 24 directions, with the
/// band set's irradiance.
pub fn sun_and_sky(scene: &mut Scene, bands: Bands, elevation_deg: f32, azimuth_deg: f32) {
    scene
        .suns
        .push(sun(elevation_deg, azimuth_deg, &bands.sun()));
    scene.sky = sky(3, SkyModel::Uniform, &bands.sky());
}

/// A camera looking at the centre of the box `min..max` from the direction
/// (`elevation_deg`, `azimuth_deg`), just far enough for every corner of the box to lie
/// within a vertical field of view of `fovy_deg` and as wide a horizontal one (so that it
/// frames the box in any image at least as wide as tall), with a 5% margin.
pub fn framing_camera(
    name: &str,
    min: Vec3,
    max: Vec3,
    elevation_deg: f32,
    azimuth_deg: f32,
    fovy_deg: f32,
) -> Camera {
    let centre = 0.5 * (min + max);
    let back = direction(elevation_deg, azimuth_deg);
    let right = Vec3::Z.cross(back).try_normalize().unwrap_or(Vec3::X);
    let up = back.cross(right);
    let tan = (0.5 * fovy_deg.to_radians()).tan();
    let mut distance = 1e-3 * (max - min).length().max(1e-3);
    for k in 0..8 {
        let corner = Vec3::new(
            if k & 1 == 0 { min.x } else { max.x },
            if k & 2 == 0 { min.y } else { max.y },
            if k & 4 == 0 { min.z } else { max.z },
        ) - centre;
        let off = corner.dot(up).abs().max(corner.dot(right).abs()) * 1.05;
        distance = distance.max(corner.dot(back) + off / tan);
    }
    Camera {
        name: Some(name.to_string()),
        position: centre + back * distance,
        target: centre,
        up: Vec3::Z,
        fovy_deg,
    }
}

/// The box of everything `c` stands for once expanded, in `c`'s frame (m); `originals`
/// are the scene's (each original's box is computed once).
pub fn bounds(c: &Cluster, originals: &[Original]) -> Aabb {
    let mut memo: Vec<Option<Aabb>> = vec![None; originals.len()];
    content_bounds(c, originals, &mut memo)
}

fn content_bounds(c: &Cluster, originals: &[Original], memo: &mut [Option<Aabb>]) -> Aabb {
    let mut b = Aabb::EMPTY;
    for v in &c.vertices {
        b.include(*v);
    }
    for child in &c.children {
        let inner = match &child.instance {
            Some(i) if i.exact => match originals.get(i.original) {
                Some(o) => {
                    let ob = match memo[i.original] {
                        Some(ob) => ob,
                        None => {
                            let ob = content_bounds(&o.root, originals, memo);
                            memo[i.original] = Some(ob);
                            ob
                        }
                    };
                    i.transform.aabb(&ob)
                }
                None => Aabb::EMPTY,
            },
            Some(i) => i.transform.aabb(&content_bounds(child, originals, memo)),
            None => content_bounds(child, originals, memo),
        };
        b = b.union(inner);
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ground_faces_up_and_camera_sees_the_box() {
        let g = ground(10.0, 3, 0);
        assert_eq!(g.polygons.len(), 9);
        let c = framing_camera("v", Vec3::ZERO, Vec3::new(1.0, 1.0, 4.0), 10.0, -90.0, 40.0);
        assert!(c.position.y < -2.0 && c.position.z > 2.0);
        assert!(hirad_core::geometry::camera_ok(
            c.position, c.target, c.up, c.fovy_deg
        ));
    }
}
