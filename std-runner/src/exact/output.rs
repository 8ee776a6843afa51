//! Hands the solution to a sink: for every input polygon in global-id order, its elements as
//! patches, then the polygon's area-weighted means of radiosity and irradiance per side.
//!
//! An element's solution is that of its exposed part (see `super::buried`); in the means
//! its buried part counts as unlit, showing only its emission: the polygon's irradiance is
//! `sum(a f H) / A` and its radiosity `sum(a (f B + (1 - f) E)) / A` (`a` an element's area,
//! `f` its exposed fraction, `A` the polygon's area), which is `E + rho H` of the means for a
//! one-sided polygon, the area mean a particle tracer reports.

use super::mesh::Mesh;
use super::solve::Solution;
use crate::scene::Scene;
use hirad_core::limits::{MAX_BANDS, NONE};
use hirad_core::sink::{PatchResult, PolygonResult, Sink};

/// Streams every polygon of `mesh` to `sink`; `exposed` is every element's exposed fraction.
pub fn emit<S: Sink>(
    scene: &Scene,
    mesh: &Mesh,
    solution: &Solution,
    exposed: &[f64],
    sink: &mut S,
) -> Result<(), S::Error> {
    let bands = scene.bands as usize;
    let value = |v: &[f64], slot: usize, out: &mut [f32; MAX_BANDS]| {
        for (o, x) in out.iter_mut().zip(&v[slot * bands..(slot + 1) * bands]) {
            *o = *x as f32;
        }
    };
    for (id, p) in mesh.polygons.iter().enumerate() {
        let m = &scene.materials[p.material].data;
        let emit = [&m.emit_front[..bands], &m.emit_back[..bands]];
        let mut area = 0.0f64;
        // sums[quantity][side][band]: quantity 0 radiosity, 1 irradiance.
        let mut sums = [[[0.0f64; MAX_BANDS]; 2]; 2];
        let mut two_sided = false;
        for e in p.elements.clone() {
            let el = &mesh.elements[e];
            two_sided = el.back_slot != NONE;
            let slots = [e, el.back_slot as usize];
            let sides = if two_sided { 2 } else { 1 };
            let a = el.area as f64;
            let seen = a * exposed[e];
            let mut radiosity = [[0.0f32; MAX_BANDS]; 2];
            for side in 0..sides {
                value(&solution.radiosity, slots[side], &mut radiosity[side]);
                let range = slots[side] * bands..(slots[side] + 1) * bands;
                let b = &solution.radiosity[range.clone()];
                let h = &solution.irradiance[range];
                for k in 0..bands {
                    sums[0][side][k] += seen * b[k] + (a - seen) * emit[side][k] as f64;
                    sums[1][side][k] += seen * h[k];
                }
            }
            area += a;
            sink.patch(&PatchResult {
                id: id as u64,
                corners: el.corners(),
                normal: el.normal,
                material: p.material as u32,
                radiosity: [&radiosity[0][..bands], &radiosity[1][..bands * (sides - 1)]],
            })?;
        }
        let mut means = [[[0.0f32; MAX_BANDS]; 2]; 2];
        for (mq, sq) in means.iter_mut().zip(&sums) {
            for (ms, ss) in mq.iter_mut().zip(sq) {
                for (m, s) in ms.iter_mut().zip(ss) {
                    *m = if area > 0.0 { (s / area) as f32 } else { 0.0 };
                }
            }
        }
        let back = if two_sided { bands } else { 0 };
        sink.polygon(&PolygonResult {
            id: id as u64,
            area: area as f32,
            two_sided,
            radiosity: [&means[0][0][..bands], &means[0][1][..back]],
            irradiance: [&means[1][0][..bands], &means[1][1][..back]],
        })?;
    }
    Ok(())
}
