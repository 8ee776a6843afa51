//! Direct irradiance from directional sources (suns) and sky directions.
//!
//! A source gives `E_perp` (W/m^2 per band) on a plane facing it; a side with unit normal
//! `n` receives `E_perp * max(n . towards, 0)` where the ray from the point towards the source
//! is not blocked. Per element and side: the quadrature average of that over the exposed
//! points (buried ones have weight 0), one ray per point and source, cast to a point beyond
//! the scene's bounding box.

use super::mesh::Mesh;
use super::quadrature::Quadrature;
use crate::scene::{LightData, Scene};
use hirad_core::limits::{MAX_BANDS, NONE};
use hirad_core::visibility::Visibility;
use rayon::prelude::*;

/// Direct irradiance per slot and band (`slot * bands + band`, W/m^2), and rays cast.
pub fn direct<V: Visibility + ?Sized>(
    scene: &Scene,
    mesh: &Mesh,
    quad: &Quadrature,
    visibility: &V,
) -> (Vec<f64>, u64) {
    let bands = scene.bands as usize;
    let mut h = vec![0.0f64; mesh.slots * bands];
    let lights: Vec<&LightData> = scene.suns.iter().chain(&scene.sky).collect();
    if lights.is_empty() {
        return (h, 0);
    }
    // Any point farther than the box's diagonal from a point of the scene is outside it.
    let reach = 2.0 * mesh.bounds.diagonal();
    let per_element: Vec<([[f64; MAX_BANDS]; 2], u64)> = (0..mesh.elements.len())
        .into_par_iter()
        .map(|e| {
            let el = &mesh.elements[e];
            let (points, weights) = quad.of(e);
            let mut sides = [[0.0f64; MAX_BANDS]; 2];
            let mut rays = 0u64;
            for light in &lights {
                for (&x, &w) in points.iter().zip(weights) {
                    // Buried points (weight 0) receive nothing.
                    if w == 0.0 {
                        continue;
                    }
                    let cos = el.normal.dot(light.towards);
                    // The front sees the source when cos > 0, a back side when cos < 0.
                    let side = if cos > 0.0 {
                        0
                    } else if cos < 0.0 && el.two_sided() {
                        1
                    } else {
                        continue;
                    };
                    rays += 1;
                    let to = x + light.towards * reach;
                    let v = visibility.transmittance(x, to, [el.polygon, NONE]) as f64;
                    for (b, s) in sides[side][..bands].iter_mut().enumerate() {
                        *s += w as f64 * cos.abs() as f64 * v * light.irradiance[b] as f64;
                    }
                }
            }
            (sides, rays)
        })
        .collect();
    let mut rays = 0;
    for (e, (sides, r)) in per_element.into_iter().enumerate() {
        rays += r;
        let el = &mesh.elements[e];
        h[e * bands..(e + 1) * bands].copy_from_slice(&sides[0][..bands]);
        if el.back_slot != NONE {
            let s = el.back_slot as usize;
            h[s * bands..(s + 1) * bands].copy_from_slice(&sides[1][..bands]);
        }
    }
    (h, rays)
}
