//! Hands the solution to a sink: for every input polygon in global-id order, its elements as
//! patches, then the polygon's area-weighted means of radiosity and irradiance per side.

use super::mesh::Mesh;
use super::solve::Solution;
use hirad_core::limits::{MAX_BANDS, NONE};
use hirad_core::sink::{PatchResult, PolygonResult, Sink};

/// Streams every polygon of `mesh` to `sink`.
pub fn emit<S: Sink>(
    bands: usize,
    mesh: &Mesh,
    solution: &Solution,
    sink: &mut S,
) -> Result<(), S::Error> {
    let value = |v: &[f64], slot: usize, out: &mut [f32; MAX_BANDS]| {
        for (o, x) in out.iter_mut().zip(&v[slot * bands..(slot + 1) * bands]) {
            *o = *x as f32;
        }
    };
    for (id, p) in mesh.polygons.iter().enumerate() {
        let mut area = 0.0f64;
        // sums[quantity][side][band]: quantity 0 radiosity, 1 irradiance.
        let mut sums = [[[0.0f64; MAX_BANDS]; 2]; 2];
        let mut two_sided = false;
        for e in p.elements.clone() {
            let el = &mesh.elements[e];
            two_sided = el.back_slot != NONE;
            let slots = [e, el.back_slot as usize];
            let sides = if two_sided { 2 } else { 1 };
            let mut radiosity = [[0.0f32; MAX_BANDS]; 2];
            for side in 0..sides {
                value(&solution.radiosity, slots[side], &mut radiosity[side]);
                for (q, v) in [&solution.radiosity, &solution.irradiance]
                    .into_iter()
                    .enumerate()
                {
                    let from = &v[slots[side] * bands..(slots[side] + 1) * bands];
                    for (s, x) in sums[q][side].iter_mut().zip(from) {
                        *s += x * el.area as f64;
                    }
                }
            }
            area += el.area as f64;
            sink.patch(&PatchResult {
                id: id as u64,
                corners: el.corners(),
                normal: el.normal,
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
