//! Gauss-Seidel iteration of `B = E + rho H + tau H_other`, `H = H_direct + F B`, per band,
//! sweeping the elements in index order (deterministic).
//!
//! Stopping: per band, the largest change of a sweep must be below `tolerance` times the
//! largest radiosity, and so must the remaining error estimated from the contraction ratio
//! `r` of successive changes (`change * r / (1 - r)`, `r` the largest of the last three
//! ratios). A closed scene with rho = 0.99 contracts by about 0.99 a sweep, so a small change
//! alone would stop far too early.

use super::matrix::{Entry, Row};
use super::mesh::Mesh;
use crate::scene::Scene;
use hirad_core::limits::{MAX_BANDS, NONE};
use hirad_core::material::MaterialData;

/// Changes at this multiple of f64 rounding (relative to the largest radiosity) mean the
/// iteration has reached its floating-point fixed point, whatever the ratio says.
const ROUNDING_FLOOR: f64 = 64.0 * f64::EPSILON;

/// The converged radiosity and irradiance.
#[derive(Clone, Debug)]
pub struct Solution {
    /// Radiosity per slot and band (`slot * bands + band`, W/m^2).
    pub radiosity: Vec<f64>,
    /// Irradiance per slot and band (W/m^2), gathered from the final radiosity.
    pub irradiance: Vec<f64>,
    /// Sweeps done.
    pub iterations: u32,
    /// Estimated remaining error relative to the largest radiosity (worst band).
    pub error: f64,
}

/// Convergence bookkeeping of one band.
#[derive(Clone, Copy, Debug, Default)]
struct Band {
    previous: f64,
    ratios: [f64; 3],
    count: usize,
}

impl Band {
    /// Records a sweep's largest change; returns the estimated remaining error (W/m^2).
    fn record(&mut self, change: f64) -> f64 {
        if self.previous > 0.0 {
            self.ratios[self.count % 3] = change / self.previous;
            self.count += 1;
        }
        self.previous = change;
        if change == 0.0 {
            return 0.0;
        }
        let used = self.count.min(3);
        let r = self.ratios[..used].iter().fold(0.0f64, |a, &b| a.max(b));
        if used == 0 || r >= 1.0 {
            f64::INFINITY
        } else {
            change * r / (1.0 - r)
        }
    }
}

/// Solves for every band at once; `Err((iterations, error))` when `max_iterations` sweeps
/// do not reach `tolerance`.
pub fn solve(
    scene: &Scene,
    mesh: &Mesh,
    rows: &[Row],
    direct: &[f64],
    tolerance: f64,
    max_iterations: u32,
    progress: &crate::output::Progress,
) -> Result<Solution, (u32, f64)> {
    let bands = scene.bands as usize;
    let n = mesh.elements.len();
    let materials: Vec<&MaterialData> = (0..n).map(|e| mesh.material(scene, e)).collect();
    let mut b = vec![0.0f64; mesh.slots * bands];
    for (e, m) in materials.iter().enumerate() {
        for k in 0..bands {
            b[e * bands + k] = m.emit_front[k] as f64;
        }
        let back = mesh.elements[e].back_slot;
        if back != NONE {
            for k in 0..bands {
                b[back as usize * bands + k] = m.emit_back[k] as f64;
            }
        }
    }
    let mut track = [Band::default(); MAX_BANDS];
    let mut error = f64::INFINITY;
    for iteration in 1..=max_iterations {
        progress.set(u64::from(iteration - 1));
        let mut change = [0.0f64; MAX_BANDS];
        for e in 0..n {
            let (hf, hb) = irradiance(mesh, rows, direct, &b, bands, e);
            let m = materials[e];
            let back = mesh.elements[e].back_slot;
            for k in 0..bands {
                let tau = if back != NONE { m.tau[k] as f64 } else { 0.0 };
                let front = m.emit_front[k] as f64 + m.rho_front[k] as f64 * hf[k] + tau * hb[k];
                let old = &mut b[e * bands + k];
                change[k] = change[k].max((front - *old).abs());
                *old = front;
                if back != NONE {
                    let v = m.emit_back[k] as f64 + m.rho_back[k] as f64 * hb[k] + tau * hf[k];
                    let old = &mut b[back as usize * bands + k];
                    change[k] = change[k].max((v - *old).abs());
                    *old = v;
                }
            }
        }
        let mut largest = [0.0f64; MAX_BANDS];
        for (s, v) in b.iter().enumerate() {
            largest[s % bands] = largest[s % bands].max(v.abs());
        }
        error = 0.0;
        for k in 0..bands {
            let estimate = track[k].record(change[k]);
            error = error.max(band_error(change[k], estimate, largest[k]));
        }
        if error <= tolerance {
            let mut h = vec![0.0f64; mesh.slots * bands];
            for e in 0..n {
                let (hf, hb) = irradiance(mesh, rows, direct, &b, bands, e);
                h[e * bands..(e + 1) * bands].copy_from_slice(&hf[..bands]);
                let back = mesh.elements[e].back_slot;
                if back != NONE {
                    let s = back as usize * bands;
                    h[s..s + bands].copy_from_slice(&hb[..bands]);
                }
            }
            return Ok(Solution {
                radiosity: b,
                irradiance: h,
                iterations: iteration,
                error,
            });
        }
    }
    Err((max_iterations, error))
}

/// Remaining error of a band relative to its largest radiosity `scale`: the sweep's change
/// alone once it is at rounding level, else the larger of the change and the estimate.
fn band_error(change: f64, estimate: f64, scale: f64) -> f64 {
    let worst = if change <= ROUNDING_FLOOR * scale {
        change
    } else {
        change.max(estimate)
    };
    if worst == 0.0 {
        0.0
    } else if scale > 0.0 {
        worst / scale
    } else {
        f64::INFINITY
    }
}

/// Irradiance of element `e`'s front and back (zero when one-sided) from the current
/// radiosity `b` (W/m^2 per band).
fn irradiance(
    mesh: &Mesh,
    rows: &[Row],
    direct: &[f64],
    b: &[f64],
    bands: usize,
    e: usize,
) -> ([f64; MAX_BANDS], [f64; MAX_BANDS]) {
    let mut hf = [0.0f64; MAX_BANDS];
    let mut hb = [0.0f64; MAX_BANDS];
    hf[..bands].copy_from_slice(&direct[e * bands..(e + 1) * bands]);
    gather(&rows[e].front, b, bands, &mut hf);
    let back = mesh.elements[e].back_slot;
    if back != NONE {
        let s = back as usize * bands;
        hb[..bands].copy_from_slice(&direct[s..s + bands]);
        gather(&rows[e].back, b, bands, &mut hb);
    }
    (hf, hb)
}

/// `out += sum over entries of F * B[slot]`, per band, in entry order.
fn gather(entries: &[Entry], b: &[f64], bands: usize, out: &mut [f64; MAX_BANDS]) {
    if bands == 1 {
        let mut s = out[0];
        for en in entries {
            s += en.value as f64 * b[en.slot as usize];
        }
        out[0] = s;
        return;
    }
    for en in entries {
        let from = &b[en.slot as usize * bands..][..bands];
        for (o, v) in out.iter_mut().zip(from) {
            *o += en.value as f64 * v;
        }
    }
}
