//! The exact solver's power balance: where the light that enters went, per band (W), by the
//! same accounting as the hierarchical solver's (`hirad_core::hr` balance), so that both
//! report alike and the reference can be checked the same way.
//!
//! * in: emitted (`A f E` over every exposed side) plus direct light of suns and sky on the
//!   receiving sides (`A f D`);
//! * absorbed: `A f H (1 - rho - tau)` from the solution;
//! * what every side sends out (`A f B`) goes to a receiving side, to the back of a
//!   one-sided polygon (absorbed there, "by backs") or out of the scene ("escaped"). The last
//!   two are measured by rays, apart from the form factors: [`RAYS_PER_SIDE`] stratified
//!   cosine-distributed rays from each emitting side's exposed quadrature points.
//!
//! The imbalance is then `in - absorbed - by backs - escaped`: zero up to the rays' noise
//! when the form factors' row sums agree with what the rays see (a wrong form factor, a leak
//! through a contact or an unconverged solution shows).

use super::mesh::Mesh;
use super::quadrature::Quadrature;
use super::solve::Solution;
use crate::scene::Scene;
use glam::Vec3;
use hirad_core::hr::Balance;
use hirad_core::limits::{MAX_BANDS, NONE};
use hirad_core::sampling::{hash3, unit2};
use hirad_core::visibility::Visibility;
use rayon::prelude::*;

/// Rays per emitting element side for the escaped and back-absorbed light (a square).
pub const RAYS_PER_SIDE: u32 = 256;

/// The balance of a converged `solution` (the hierarchical solver's [`Balance`]), and the
/// rays it cast.
pub fn balance<V: Visibility + ?Sized>(
    scene: &Scene,
    mesh: &Mesh,
    quad: &Quadrature,
    solution: &Solution,
    direct: &[f64],
    exposed: &[f64],
    visibility: &V,
) -> (Balance, u64) {
    let bands = scene.bands as usize;
    let reach = 2.0 * mesh.bounds.diagonal().max(f32::MIN_POSITIVE);
    // The front normal of every one-sided polygon (whose back absorbs what meets it).
    let one_sided: Vec<Option<Vec3>> = mesh
        .polygons
        .iter()
        .map(|p| (!scene.materials[p.material].data.two_sided).then_some(p.normal))
        .collect();
    let parts: Vec<(Balance, u64)> = (0..mesh.elements.len())
        .into_par_iter()
        .map(|e| {
            let el = &mesh.elements[e];
            let m = mesh.material(scene, e);
            let (mut out, mut rays) = (Balance::default(), 0u64);
            let seen = el.area as f64 * exposed[e];
            if seen <= 0.0 {
                return (out, rays);
            }
            let slots = [e, el.back_slot as usize];
            let sides = if el.back_slot == NONE { 1 } else { 2 };
            for (side, &slot) in slots.iter().enumerate().take(sides) {
                let (emit, rho) = if side == 0 {
                    (&m.emit_front, &m.rho_front)
                } else {
                    (&m.emit_back, &m.rho_back)
                };
                let tau = if sides == 2 {
                    &m.tau
                } else {
                    &[0.0; MAX_BANDS]
                };
                let b = &solution.radiosity[slot * bands..(slot + 1) * bands];
                let h = &solution.irradiance[slot * bands..(slot + 1) * bands];
                let d = &direct[slot * bands..(slot + 1) * bands];
                for k in 0..bands {
                    out.emitted[k] += seen * emit[k] as f64;
                    out.direct[k] += seen * d[k];
                    out.absorbed[k] += seen * h[k] * (1.0 - rho[k] as f64 - tau[k] as f64);
                }
                if b.iter().all(|&v| v <= 0.0) {
                    continue;
                }
                let normal = if side == 0 { el.normal } else { -el.normal };
                let (escaped, backs) = fate(
                    quad,
                    e,
                    slot as u32,
                    normal,
                    el.polygon,
                    reach,
                    &one_sided,
                    visibility,
                );
                rays += u64::from(RAYS_PER_SIDE);
                for (k, &bk) in b.iter().enumerate() {
                    out.escaped[k] += seen * bk * escaped;
                    out.absorbed_backs[k] += seen * bk * backs;
                }
            }
            (out, rays)
        })
        .collect();
    // Summed in element order: the same total for any thread count.
    let (mut total, mut rays) = (Balance::default(), 0u64);
    for (p, r) in &parts {
        for k in 0..bands {
            total.emitted[k] += p.emitted[k];
            total.direct[k] += p.direct[k];
            total.absorbed[k] += p.absorbed[k];
            total.absorbed_backs[k] += p.absorbed_backs[k];
            total.escaped[k] += p.escaped[k];
        }
        rays += r;
    }
    (total, rays)
}

/// The fractions of the light leaving side `slot` of element `e` (unit `normal` on that
/// side) that leave the scene and that meet the back of a one-sided polygon: stratified
/// cosine-distributed rays from its quadrature points in turn, by weight.
#[allow(clippy::too_many_arguments)]
fn fate<V: Visibility + ?Sized>(
    quad: &Quadrature,
    e: usize,
    slot: u32,
    normal: Vec3,
    polygon: u32,
    reach: f32,
    one_sided: &[Option<Vec3>],
    visibility: &V,
) -> (f64, f64) {
    let (points, weights) = quad.of(e);
    let grid = (RAYS_PER_SIDE as f32).sqrt() as u32;
    let total_w: f64 = weights.iter().map(|&w| w as f64).sum();
    if total_w <= 0.0 {
        return (0.0, 0.0);
    }
    let (t, bt) = normal.any_orthonormal_pair();
    let (mut escaped, mut backs) = (0.0f64, 0.0f64);
    let mut n = 0u32;
    for i in 0..grid {
        for j in 0..grid {
            // Quadrature points in turn, each carrying its weight.
            let q = (n as usize) % points.len();
            n += 1;
            let w = weights[q] as f64 * points.len() as f64 / total_w;
            if w <= 0.0 {
                continue;
            }
            let (ju, jv) = unit2(hash3(e as u32, slot.wrapping_mul(RAYS_PER_SIDE) + n, 0xBA1));
            let u = (i as f32 + ju) / grid as f32;
            let v = (j as f32 + jv) / grid as f32;
            let (r, phi) = (u.sqrt(), std::f32::consts::TAU * v);
            let z = (1.0 - u).max(0.0).sqrt();
            let dir = (t * (r * phi.cos()) + bt * (r * phi.sin()) + normal * z).normalize_or_zero();
            let from = points[q];
            match visibility.first_hit(from, from + dir * reach, [polygon, NONE]) {
                None => escaped += w,
                Some((hit, _)) => {
                    // The back of a one-sided polygon: the ray runs along its normal.
                    if let Some(Some(n)) = one_sided.get(hit as usize)
                        && n.dot(dir) > 0.0
                    {
                        backs += w;
                    }
                }
            }
        }
    }
    let rays = f64::from(grid * grid);
    (escaped / rays, backs / rays)
}
