//! The phase table's values by reciprocity: one hr solve of the original per outgoing cell,
//! then any grid of incoming directions by rays alone.
//!
//! Light from a sun towards `d` that falls first on side `s` of polygon `p` (power
//! `Phi_ps(d)`, from the polygon's area, cosine and the fraction of it the sun reaches) is
//! scattered diffusely, `rho_s` of it from that side and `tau` from the other. By reciprocity
//! (diffuse surfaces, symmetric transport), the intensity that a watt of diffuse emission from
//! a side sends towards an observer at `o`, over every path, is that side's irradiance under
//! a sun of 1 W/m^2 towards `o`, interreflections included, over pi. So with the solve under
//! a sun at each outgoing cell, `W_ps(o) = rho_s E_ps(o) + tau E_p(other side)(o)`, the
//! intensity for any sun is `I(d, o) = sum_ps Phi_ps(d) W_ps(o) / pi`, kept apart by the
//! side lit, and the incoming grid costs rays: as fine as a sun near a leaf's plane needs.
//! Where the polygons' first scattering is kept apart (see [`super::single_bake`]), the part
//! of `W` that is light straight from the sun at `o` is taken out: the table holds the rest.

use super::bake::TableSettings;
use super::intercept::EscapeWeights;
use super::original::Alone;
use super::sample::{Visibilities, samples_at};
use crate::solve::RayonExecutor;
use anyhow::Result;
use glam::Vec3;
use hirad_core::limits::MAX_BANDS;
use hirad_core::tables::grid::DirectionGrid;
use hirad_core::tables::phase::side_lit;
use hirad_core::tables::tau::projected_area;
use rayon::prelude::*;

/// Per polygon side and outgoing cell, the intensity towards that cell per watt falling on
/// the side, times pi: `W_ps(o)` (m^2/sr x pi per W, i.e. dimensionless per band).
pub(super) struct Returns {
    polygons: usize,
    bands: usize,
    cells: usize,
    /// `[((p * 2 + side) * cells + o) * bands + band]`.
    w: Vec<f32>,
    /// The same for the light that leaves the polygon straight towards the cell (its
    /// first scattering, from its visible fraction there), when that is kept apart.
    direct: Option<Vec<f32>>,
}

impl Returns {
    /// Solves `alone` under a sun of 1 W/m^2 at every cell of `outgoing`; `progress(done,
    /// total)` after each. With `direct` (the polygons' visible fractions towards the
    /// cells), the part of `W` that is their first scattering is kept too.
    pub fn solve(
        alone: &Alone,
        outgoing: DirectionGrid,
        direct: Option<&Visibilities>,
        settings: &TableSettings,
        exec: &mut RayonExecutor,
        progress: &mut dyn FnMut(u64, u64),
    ) -> Result<Self> {
        let (polygons, bands, cells) = (
            alone.polygons.len(),
            alone.bands(),
            outgoing.cells() as usize,
        );
        let mut w = vec![0.0f32; polygons * 2 * cells * bands];
        let mut first = direct.map(|_| vec![0.0f32; w.len()]);
        // Several cells' suns a solve, each in its own copy of the bands.
        let per = (MAX_BANDS / bands).max(1);
        for start in (0..cells).step_by(per) {
            progress(start as u64, cells as u64);
            let end = (start + per).min(cells);
            let suns: Vec<Vec3> = (start..end).map(|o| outgoing.direction(o as u32)).collect();
            let solved = samples_at(alone, &suns, settings, exec)?;
            for (o, s) in (start..end).zip(solved) {
                for p in 0..polygons {
                    let m = &alone.scene.materials[alone.materials[p] as usize].data;
                    let e = |side: usize, b: usize| {
                        s.lit
                            .table
                            .irradiance(p, side)
                            .get(b)
                            .copied()
                            .unwrap_or(0.0)
                    };
                    // Per side, what leaves it per unit irradiance on the fronts (ef) and backs (eb).
                    let put = |out: &mut [f32], b: usize, ef: f32, eb: f32| {
                        out[((p * 2) * cells + o) * bands + b] =
                            m.rho_front[b] * ef + m.tau[b] * eb;
                        out[((p * 2 + 1) * cells + o) * bands + b] =
                            m.rho_back[b] * eb + m.tau[b] * ef;
                    };
                    for b in 0..bands {
                        put(&mut w, b, e(0, b), e(1, b));
                    }
                    if let (Some(first), Some(v)) = (&mut first, direct) {
                        // The sun at `o` straight on the polygon: |cos| x visible fraction, on
                        // the side facing it.
                        let c = alone.normals[p].dot(outgoing.direction(o as u32));
                        let lit = c.abs() * v.fraction(o as u32, p);
                        let (ef, eb) = if c >= 0.0 { (lit, 0.0) } else { (0.0, lit) };
                        for b in 0..bands {
                            put(first, b, ef, eb);
                        }
                    }
                }
            }
        }
        progress(cells as u64, cells as u64);
        Ok(Self {
            polygons,
            bands,
            cells,
            w,
            direct: first,
        })
    }

    /// `W` of side `side` of polygon `p` at every outgoing cell, `[o * bands + band]`.
    fn of(&self, p: usize, side: usize) -> &[f32] {
        let n = self.cells * self.bands;
        let at = (p * 2 + side) * n;
        &self.w[at..at + n]
    }

    /// The first-scattering part of [`Self::of`] (zeros when it is not kept apart).
    fn direct_of(&self, p: usize, side: usize) -> &[f32] {
        let n = self.cells * self.bands;
        let at = (p * 2 + side) * n;
        self.direct.as_ref().map_or(&[], |d| &d[at..at + n])
    }
}

/// The phase table's values on an incoming grid (see [`super::OriginalTables`]).
pub(super) struct PhaseValues {
    pub shares: Vec<f32>,
    pub response: Vec<f32>,
    pub absorbed: Vec<f32>,
    pub residual: Vec<f32>,
}

/// The phase values for the cells of `incoming`, whose suns reach the polygons as `lit`
/// says; `shadow(o)` is the cross-section seen from `o` and `tau(d)` the uncollided
/// transmittance (both by the tables on the `tau` grid).
#[allow(clippy::too_many_arguments)]
pub(super) fn phase_values(
    alone: &Alone,
    weights: &EscapeWeights,
    returns: &Returns,
    incoming: DirectionGrid,
    lit: &Visibilities,
    outgoing: DirectionGrid,
    shadow: &(dyn Fn(Vec3) -> f32 + Sync),
    tau: &(dyn Fn(Vec3) -> f32 + Sync),
) -> PhaseValues {
    let (bands, n_out) = (returns.bands, returns.cells);
    let seen: Vec<f32> = (0..n_out as u32)
        .map(|o| shadow(outgoing.direction(o)))
        .collect();
    let omega = outgoing.solid_angle() as f64;
    let per_cell: Vec<PhaseValues> = (0..incoming.cells())
        .into_par_iter()
        .map(|c| {
            let d = incoming.direction(c);
            // Per side lit: power intercepted, scattered out, and the intensity towards
            // every outgoing cell (times pi).
            let mut intercepted = 0.0f64;
            let mut scattered = [[0.0f64; 8]; 2];
            // With the first scattering kept apart, `intensity` is the rest and `total` the
            // whole (for the energy check).
            let mut intensity = vec![[0.0f64; 2]; n_out * bands];
            let mut total_out = [0.0f64; 8];
            for p in 0..returns.polygons {
                let cos = alone.normals[p].dot(d);
                let phi = (alone.areas[p] * cos.abs() * lit.fraction(c, p)) as f64;
                if phi <= 0.0 {
                    continue;
                }
                let side = if cos >= 0.0 { 0 } else { 1 };
                intercepted += phi;
                for (b, s) in scattered[side].iter_mut().enumerate().take(bands) {
                    *s += phi * weights.of(p as u32, side)[b] as f64;
                }
                let direct = returns.direct_of(p, side);
                for (k, (i, w)) in intensity.iter_mut().zip(returns.of(p, side)).enumerate() {
                    let first = direct.get(k).copied().unwrap_or(0.0);
                    i[side] += phi * (*w - first) as f64;
                    total_out[k % bands] += phi * *w as f64;
                }
            }
            let area = projected_area(alone.lo, alone.hi, d) as f64;
            let mut v = PhaseValues {
                shares: vec![0.0; 2 * bands],
                response: vec![0.0; n_out * 2 * bands],
                absorbed: vec![0.0; bands],
                residual: vec![0.0; bands],
            };
            for b in 0..bands {
                let total = scattered[0][b] + scattered[1][b];
                let out = total_out[b] / std::f64::consts::PI * omega;
                for side in 0..2 {
                    let s = scattered[side][b];
                    let on = side_lit(s as f32, total as f32);
                    v.shares[side * bands + b] = if on { (s / total) as f32 } else { 0.0 };
                    for o in 0..n_out {
                        let i = intensity[o * bands + b][side] / std::f64::consts::PI;
                        if on && seen[o] > 0.0 {
                            // The rest after the first scattering may come out a rounding
                            // below zero where the solve's direct light and the rays' differ.
                            v.response[(o * 2 + side) * bands + b] =
                                (i / (s * seen[o] as f64)).max(0.0) as f32;
                        }
                    }
                }
                if area > 0.0 {
                    let absorbed = (intercepted - total) / area;
                    v.absorbed[b] = absorbed as f32;
                    v.residual[b] = (1.0 - tau(d) as f64 - absorbed - out / area) as f32;
                }
            }
            v
        })
        .collect();
    let mut all = PhaseValues {
        shares: Vec::with_capacity(incoming.cells() as usize * 2 * bands),
        response: Vec::with_capacity(incoming.cells() as usize * n_out * 2 * bands),
        absorbed: Vec::with_capacity(incoming.cells() as usize * bands),
        residual: Vec::with_capacity(incoming.cells() as usize * bands),
    };
    for v in per_cell {
        all.shares.extend(v.shares);
        all.response.extend(v.response);
        all.absorbed.extend(v.absorbed);
        all.residual.extend(v.residual);
    }
    all
}
