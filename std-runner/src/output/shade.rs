//! Colours a rasterised image again from smoothed corner values (see [`super::smooth`]):
//! every stored patch's samples get its corners' radiosity interpolated, or, for a patch
//! with T-junctions on its edges, that of a fan of triangles from its centre through its
//! corners and junctions.

use super::raster::Rasterizer;
use super::smooth::PatchStore;
use glam::Vec3;

/// Shades the samples of every patch of `store` in `raster`, whose patches were drawn in
/// the same order, the first as the `first`-th since [`Rasterizer::track_owners`].
pub fn shade_all(raster: &mut Rasterizer, store: &PatchStore, first: u32) {
    let values = store.corner_values();
    let bands = raster.bands();
    for i in 0..store.len() {
        let p = store.patch(i);
        let n = p.corners().len();
        let sides = if p.two_sided { 2 } else { 1 };
        let junctions = values.junctions(i);
        if junctions.is_empty() {
            let side = |s: usize| {
                if s < sides {
                    &values.get(i, s)[..n * bands]
                } else {
                    &[][..]
                }
            };
            raster.shade(first + i as u32, p.corners(), p.normal, [side(0), side(1)]);
            continue;
        }
        // A fan from the centre through corners and junctions (see `super::smooth`).
        let mut ring: Vec<(Vec3, Vec<f32>)> = Vec::with_capacity(n + junctions.len());
        for k in 0..n {
            let mut v = Vec::with_capacity(2 * bands);
            for s in 0..2 {
                v.extend_from_slice(&values.get(i, s)[k * bands..(k + 1) * bands]);
            }
            ring.push((p.corners()[k], v));
            ring.extend(
                junctions
                    .iter()
                    .filter(|j| usize::from(j.edge) == k)
                    .map(|j| (j.at, j.values.clone())),
            );
        }
        let centre = p.corners().iter().sum::<Vec3>() / n as f32;
        let mut mid = vec![0.0f32; 2 * bands];
        for (m, x) in mid.iter_mut().enumerate() {
            let (s, b) = (m / bands, m % bands);
            *x = (0..n).map(|k| values.get(i, s)[k * bands + b]).sum::<f32>() / n as f32;
        }
        let mut tri_values = vec![0.0f32; 2 * 3 * bands];
        for k in 0..ring.len() {
            let (a, b) = (&ring[k], &ring[(k + 1) % ring.len()]);
            for s in 0..2 {
                for (c, v) in [&mid, &a.1, &b.1].into_iter().enumerate() {
                    let at = (s * 3 + c) * bands;
                    tri_values[at..at + bands].copy_from_slice(&v[s * bands..(s + 1) * bands]);
                }
            }
            let (front, back) = tri_values.split_at(3 * bands);
            let back = if sides == 2 { back } else { &[][..] };
            raster.shade(
                first + i as u32,
                &[centre, a.0, b.0],
                p.normal,
                [front, back],
            );
        }
    }
}
