//! Quadrature points buried inside closed objects: a floor under a box, a ceiling behind a
//! lamp. A point of a one-sided element is buried when every one of up to [`BURIED_RAYS`]
//! rays from it (its normal first, then stratified cosine-distributed directions over its
//! front hemisphere, stopping at the first that proves it exposed) meets the back of a
//! one-sided polygon. A ray that leaves the scene, or meets the front of a polygon or any
//! side of a two-sided one (leaves), proves the point exposed; points of two-sided elements
//! are never buried.
//!
//! Buried points are left out of their element's quadrature (the others' weights scaled to
//! sum to 1), and the element's exposed fraction, the sum of the plain weights of its exposed
//! points, scales what it stands for in the results table (see the module docs of
//! [`super`]). The same rule as the hierarchical solver's, so both converge to the same
//! answer.
//!
//! Rays come from `hash3(element, point, ..)`: the result never depends on the thread count.

use super::mesh::Mesh;
use super::quadrature::Quadrature;
use crate::scene::Scene;
use glam::Vec3;
use hirad_core::geometry::Aabb;
use hirad_core::limits::NONE;
use hirad_core::sampling::{hash3, unit2};
use hirad_core::visibility::Visibility;
use rayon::prelude::*;

/// Most rays per quadrature point for the buried test.
pub const BURIED_RAYS: u32 = 8;

/// What the buried test found, per element.
#[derive(Clone, Debug, Default)]
pub struct Exposure {
    /// Exposed fraction of every element (0..=1): the plain quadrature weight of its exposed
    /// points. 1 for two-sided elements.
    pub exposed: Vec<f64>,
    /// Buried quadrature points, over all elements.
    pub buried_points: u64,
    /// Rays cast by the test.
    pub rays: u64,
}

/// Finds the buried points of every one-sided element of `mesh`, removes them from `quad`
/// (the remaining weights of an element scaled to sum to 1, all 0 when every point is
/// buried) and returns the exposed fractions.
pub fn bury<V: Visibility + ?Sized>(
    scene: &Scene,
    mesh: &Mesh,
    quad: &mut Quadrature,
    visibility: &V,
) -> Exposure {
    let one_sided: Vec<bool> = mesh
        .polygons
        .iter()
        .map(|p| !scene.materials[p.material].data.two_sided)
        .collect();
    let per_element: Vec<(Vec<bool>, u64)> = (0..mesh.elements.len())
        .into_par_iter()
        .map(|e| {
            let el = &mesh.elements[e];
            let (points, _) = quad.of(e);
            let mut rays = 0u64;
            if el.two_sided() {
                return (vec![false; points.len()], rays);
            }
            let buried = points
                .iter()
                .enumerate()
                .map(|(q, &x)| {
                    let seed = hash3(e as u32, q as u32, 0xB0);
                    let (b, r) =
                        is_buried(mesh, &one_sided, x, el.normal, el.polygon, seed, visibility);
                    rays += r as u64;
                    b
                })
                .collect();
            (buried, rays)
        })
        .collect();
    let mut out = Exposure {
        exposed: Vec::with_capacity(mesh.elements.len()),
        ..Exposure::default()
    };
    for (e, (buried, rays)) in per_element.into_iter().enumerate() {
        out.rays += rays;
        out.buried_points += buried.iter().filter(|&&b| b).count() as u64;
        out.exposed.push(quad.restrict(e, &buried));
    }
    out
}

/// Whether every ray from `x` (on polygon `poly`, front normal `n`) meets the back of a
/// one-sided polygon, and the rays cast.
fn is_buried<V: Visibility + ?Sized>(
    mesh: &Mesh,
    one_sided: &[bool],
    x: Vec3,
    n: Vec3,
    poly: u32,
    seed: u32,
    visibility: &V,
) -> (bool, u32) {
    for j in 0..BURIED_RAYS {
        // The normal first, then cosine-distributed directions, stratified in u.
        let d = if j == 0 {
            n
        } else {
            let (u, v) = unit2(hash3(seed, j, 0xD1));
            let u = ((j - 1) as f32 + u) / (BURIED_RAYS - 1) as f32;
            cosine_direction(n, u, v)
        };
        let Some((hit, _)) = visibility.first_hit(x, beyond(&mesh.bounds, x, d), [poly, NONE])
        else {
            return (false, j + 1);
        };
        let Some(p) = mesh.polygons.get(hit as usize) else {
            return (false, j + 1);
        };
        if !one_sided[hit as usize] || p.normal.dot(d) <= 0.0 {
            return (false, j + 1);
        }
    }
    (true, BURIED_RAYS)
}

/// A point on the ray from `x` along unit `d` safely outside the scene's box `bounds`: twice
/// the distance to where the ray leaves the box, plus a thousandth of its diagonal. Not a
/// fixed far point: the ray caster ignores crossings within a relative margin of the
/// segment's ends, and on a very long segment that margin would let a ray starting next to
/// an edge slip past the polygon beside it.
fn beyond(bounds: &Aabb, x: Vec3, d: Vec3) -> Vec3 {
    let mut t = f32::INFINITY;
    for k in 0..3 {
        if d[k] > 0.0 {
            t = t.min((bounds.max[k] - x[k]) / d[k]);
        } else if d[k] < 0.0 {
            t = t.min((bounds.min[k] - x[k]) / d[k]);
        }
    }
    let diag = bounds.diagonal();
    let t = if t.is_finite() { t.max(0.0) } else { diag };
    x + d * (2.0 * t + 1e-3 * diag)
}

/// The cosine-distributed direction about unit `n` for `(u, v)` in [0, 1)^2 (`u` the squared
/// sine of the polar angle, `v` the azimuth's turn).
fn cosine_direction(n: Vec3, u: f32, v: f32) -> Vec3 {
    let (t, b) = n.any_orthonormal_pair();
    let r = u.sqrt();
    let phi = 2.0 * std::f32::consts::PI * v;
    let z = (1.0 - u).max(0.0).sqrt();
    (t * (r * phi.cos()) + b * (r * phi.sin()) + n * z).normalize_or_zero()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cosine_directions_stay_in_the_front_hemisphere() {
        let n = Vec3::new(0.3, -0.4, 0.866).normalize();
        for k in 0..64u32 {
            let (u, v) = unit2(hash3(k, 1, 2));
            let d = cosine_direction(n, u, v);
            assert!((d.length() - 1.0).abs() < 1e-5);
            assert!(d.dot(n) >= 0.0, "{d} against {n}");
        }
        let b = Aabb {
            min: Vec3::ZERO,
            max: Vec3::ONE,
        };
        let far = beyond(&b, Vec3::splat(0.5), Vec3::X);
        assert!((far.x - (1.5 + 1e-3 * 3f32.sqrt())).abs() < 1e-5, "{far}");
    }
}
