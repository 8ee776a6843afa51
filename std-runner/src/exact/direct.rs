//! Direct irradiance from directional sources (suns) and sky directions.
//!
//! A source gives `E_perp` (W/m^2 per band) on a plane facing it; a side with unit normal
//! `n` receives `E_perp * max(n . towards, 0)` where the ray from the point towards the source
//! is not blocked. Per element and side: the mean of that over a jittered 8 x 8 grid of the
//! element (one ray per sample and source, cast to a point beyond the scene's bounding box),
//! over the element's exposed fraction (a buried sample's ray meets the object it is buried
//! in, so the mean is that of the exposed part). The element's few quadrature points would
//! give a shadow's edge a third of the element or none: a reference must resolve it.

use super::mesh::Mesh;
use crate::scene::{LightData, Scene};
use hirad_core::limits::{MAX_BANDS, NONE};
use hirad_core::sampling::{hash3, point_on, unit2};
use hirad_core::visibility::Visibility;
use rayon::prelude::*;

/// Samples along each side of an element's grid for direct light.
const SUN_GRID: u32 = 8;

/// Direct irradiance per slot and band (`slot * bands + band`, W/m^2), and rays cast.
pub fn direct<V: Visibility + ?Sized>(
    scene: &Scene,
    mesh: &Mesh,
    exposed: &[f64],
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
            let mut sides = [[0.0f64; MAX_BANDS]; 2];
            let mut rays = 0u64;
            let f = exposed.get(e).copied().unwrap_or(1.0);
            if f <= 0.0 {
                return (sides, rays);
            }
            for (l, light) in lights.iter().enumerate() {
                let cos = el.normal.dot(light.towards);
                // The front sees the source when cos > 0, a back side when cos < 0.
                let side = if cos > 0.0 {
                    0
                } else if cos < 0.0 && el.two_sided() {
                    1
                } else {
                    continue;
                };
                let mut lit = 0.0f64;
                for k in 0..SUN_GRID * SUN_GRID {
                    let (ju, jv) = unit2(hash3(e as u32, k, 0xD1EC + l as u32));
                    let u = ((k % SUN_GRID) as f32 + ju) / SUN_GRID as f32;
                    let v = ((k / SUN_GRID) as f32 + jv) / SUN_GRID as f32;
                    let x = point_on(el.corners(), u, v);
                    rays += 1;
                    let to = x + light.towards * reach;
                    lit += visibility.transmittance(x, to, [el.polygon, NONE]) as f64;
                }
                let lit = (lit / (SUN_GRID * SUN_GRID) as f64 / f).min(1.0);
                for (b, s) in sides[side][..bands].iter_mut().enumerate() {
                    *s += cos.abs() as f64 * lit * light.irradiance[b] as f64;
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
