//! The default view of a scene that has no camera: the one that shows most of what can be
//! seen, not the backs of walls.
//!
//! A one-sided polygon shows nothing from behind (it absorbs there), so the old default, from
//! above and to the side of the scene's box, looked at a closed room from outside onto the
//! backs of its walls: the Cornell box as an OBJ rendered black. Candidates now come from
//! around the box (its corners and its faces) and, when no view from outside sees much,
//! from inside it (near each face, looking across); each is scored by a grid of rays: the
//! share that meets the side of a polygon that can show light (the front of a one-sided
//! polygon, either side of a two-sided one). The classic view from above and to the side
//! stays the choice unless another sees clearly more; a view from inside is taken only for
//! an enclosure, where no view from outside sees a third of what it looks at.

use super::camera::{DEFAULT_FOVY_DEG, DEFAULT_VIEW_FROM, OptionError, Size, check_camera};
use crate::scene::{Camera, ExpandVisitor, ExpandedNode, Scene, Up, expand};
use crate::visibility::ObvhsVisibility;
use glam::{DVec3, Vec3};
use hirad_core::geometry::Aabb;
use hirad_core::visibility::Visibility;

/// Rays per candidate: a grid this many across (and 3/4 as many down).
const GRID: u32 = 24;

/// Scenes with more polygons than this keep the classic view (scoring would expand them).
pub const MAX_SCORED_POLYGONS: u64 = 2_000_000;

/// Field of view of the views from inside (degrees): wider, as a room is seen from in it.
const INSIDE_FOVY_DEG: f32 = 70.0;

/// A view from outside that sees less than this share of showing sides among what it meets
/// marks an enclosure.
const ENCLOSED: f64 = 1.0 / 3.0;

/// The polygons of the expanded scene in world space, and which can show light from behind.
struct Polygons<'a> {
    /// Per material: two-sided.
    materials: &'a [bool],
    corners: Vec<Vec<Vec3>>,
    two_sided: Vec<bool>,
}

impl ExpandVisitor for Polygons<'_> {
    type Error = std::convert::Infallible;
    fn node(&mut self, n: &ExpandedNode<'_>) -> Result<(), Self::Error> {
        for p in &n.cluster.polygons {
            let c = &p.corners[..p.corner_count()];
            self.corners.push(
                c.iter()
                    .map(|&i| n.to_world.point(n.cluster.vertices[i as usize]))
                    .collect(),
            );
            self.two_sided.push(
                self.materials
                    .get(p.material as usize)
                    .copied()
                    .unwrap_or(false),
            );
        }
        Ok(())
    }
}

/// A candidate view and what its rays saw.
struct Candidate {
    camera: Camera,
    /// Rays that met a side that can show light, over all rays.
    showing: f64,
    /// The same over the rays that met anything.
    of_hits: f64,
}

/// The default camera for a scene without one (see the module) whose up axis is `up`.
pub fn choose(scene: &Scene, bounds: &Aabb, size: Size, up: Up) -> Result<Camera, OptionError> {
    let classic = super::camera::default_camera_up(bounds, size, up)?;
    let mut count = 0u64;
    struct Count<'a>(&'a mut u64);
    impl ExpandVisitor for Count<'_> {
        type Error = ();
        fn node(&mut self, n: &ExpandedNode<'_>) -> Result<(), ()> {
            *self.0 += n.cluster.polygons.len() as u64;
            if *self.0 > MAX_SCORED_POLYGONS {
                Err(())
            } else {
                Ok(())
            }
        }
    }
    if expand(scene, &mut Count(&mut count)).is_err() {
        return Ok(classic);
    }
    let materials: Vec<bool> = scene.materials.iter().map(|m| m.data.two_sided).collect();
    let mut polys = Polygons {
        materials: &materials,
        corners: Vec::new(),
        two_sided: Vec::new(),
    };
    let _ = expand(scene, &mut polys);
    let Ok(vis) = ObvhsVisibility::new(&polys.corners) else {
        return Ok(classic);
    };
    let score = |camera: Camera| {
        score(&camera, size, &polys, &vis).map(|(showing, of_hits)| Candidate {
            camera,
            showing,
            of_hits,
        })
    };
    // From outside: the classic view first, then the box's other corners and its faces.
    let (min, max) = (bounds.min.as_dvec3(), bounds.max.as_dvec3());
    let centre = (min + max) * 0.5;
    let distance = (classic.position.as_dvec3() - centre).length();
    let from_dirs = directions(up);
    let up = up.vector();
    let mut outside = Vec::new();
    let first = score(classic.clone());
    let classic_score = first.as_ref().map_or(0.0, |c| c.showing);
    outside.extend(first);
    for d in from_dirs {
        let camera = look(centre + d * distance, centre, up, DEFAULT_FOVY_DEG);
        if let Some(c) = camera.and_then(&score) {
            outside.push(c);
        }
    }
    let best_outside = outside
        .iter()
        .max_by(|a, b| a.showing.total_cmp(&b.showing))
        .map(|c| (c.showing, c.of_hits));
    if let Some((best, of_hits)) = best_outside
        && of_hits >= ENCLOSED
    {
        // The classic view unless another shows clearly more.
        if classic_score >= 0.8 * best {
            return Ok(classic);
        }
        if let Some(c) = outside
            .into_iter()
            .max_by(|a, b| a.showing.total_cmp(&b.showing))
        {
            return Ok(c.camera);
        }
        return Ok(classic);
    }
    // An enclosure: from inside, near each face, looking across.
    let half = (max - min) * 0.5;
    let mut inside: Vec<Candidate> = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0, 1.0] {
            let mut at = centre;
            at[axis] += sign * half[axis] * 0.9;
            // A little towards the top, as a person stands.
            at += up * (half.dot(up.abs()) * 0.2);
            if let Some(c) = look(at, centre, up, INSIDE_FOVY_DEG).and_then(&score) {
                inside.push(c);
            }
        }
    }
    let all = inside.into_iter().chain(outside);
    Ok(all
        .max_by(|a, b| a.showing.total_cmp(&b.showing))
        .map_or(classic, |c| c.camera))
}

/// The box's other corners and its faces, as directions from its centre (unit), in the
/// scene's frame (whose up axis is `up`).
fn directions(up: Up) -> Vec<DVec3> {
    let mut out = Vec::new();
    let classic = DEFAULT_VIEW_FROM.as_dvec3().normalize();
    for sx in [-1.0, 1.0] {
        for sy in [-1.0, 1.0] {
            for sz in [-1.0, 1.0] {
                let d = DVec3::new(sx, sy, sz).normalize();
                if (d - classic).length() > 1e-9 {
                    out.push(d);
                }
            }
        }
    }
    for axis in 0..3 {
        for sign in [-1.0, 1.0] {
            let mut d = DVec3::ZERO;
            d[axis] = sign;
            out.push(d);
        }
    }
    // The same set of directions, in the scene's frame.
    out.iter_mut().for_each(|d| *d = up.from_z_up(*d));
    out
}

/// A checked camera at `from` looking at `at`, with `up` (another axis when the view runs
/// along it).
fn look(from: DVec3, at: DVec3, up: DVec3, fovy_deg: f32) -> Option<Camera> {
    let forward = (at - from).normalize_or_zero();
    let up = if forward.cross(up).length() < 1e-3 {
        if up.y.abs() > 0.5 { DVec3::Z } else { DVec3::Y }
    } else {
        up
    };
    let camera = Camera {
        name: None,
        position: from.as_vec3(),
        target: at.as_vec3(),
        up: up.as_vec3(),
        fovy_deg,
    };
    check_camera(&camera).ok().map(|()| camera)
}

/// The share of a grid of rays through the camera's image that meets a side of a polygon
/// that can show light, over all rays and over those that met anything.
fn score(
    camera: &Camera,
    size: Size,
    polys: &Polygons,
    vis: &ObvhsVisibility,
) -> Option<(f64, f64)> {
    let eye = camera.position.as_dvec3();
    let forward = (camera.target.as_dvec3() - eye).normalize();
    let right = forward.cross(camera.up.as_dvec3()).normalize();
    let up = right.cross(forward);
    let tan_y = (f64::from(camera.fovy_deg).to_radians() * 0.5).tan();
    let tan_x = tan_y * size.aspect();
    let rows = (GRID * 3 / 4).max(1);
    // Far enough to leave the scene from anywhere in its box.
    let far = polys
        .corners
        .iter()
        .flatten()
        .map(|p| (p.as_dvec3() - eye).length())
        .fold(0.0f64, f64::max)
        * 2.0;
    if !(far > 0.0 && far.is_finite()) {
        return None;
    }
    let (mut showing, mut hits) = (0u32, 0u32);
    for j in 0..rows {
        for i in 0..GRID {
            let x = ((i as f64 + 0.5) / GRID as f64 * 2.0 - 1.0) * tan_x;
            let y = (1.0 - (j as f64 + 0.5) / rows as f64 * 2.0) * tan_y;
            let d = (forward + right * x + up * y).normalize();
            let to = eye + d * far;
            let Some((id, _)) = vis.first_hit(eye.as_vec3(), to.as_vec3(), [u32::MAX; 2]) else {
                continue;
            };
            hits += 1;
            let c = &polys.corners[id as usize];
            let n = (c[1] - c[0]).cross(c[c.len() - 1] - c[0]).as_dvec3();
            if polys.two_sided[id as usize] || n.dot(d) < 0.0 {
                showing += 1;
            }
        }
    }
    let all = (GRID * rows) as f64;
    Some((
        showing as f64 / all,
        if hits > 0 {
            showing as f64 / hits as f64
        } else {
            0.0
        },
    ))
}
