//! The tables on the `tau` grid: `tau` and the albedo per cell, from the same rays (see
//! [`super::intercept`]), on grids of side 4, 8, ... until interpolation meets the target at
//! check directions off the grid.

use super::bake::{TableSettings, uniform_direction};
use super::intercept::{EscapeWeights, Intercept, intercept};
use super::original::Alone;
use anyhow::{Result, anyhow};
use glam::Vec3;
use hirad_core::sampling::hash3;
use hirad_core::tables::grid::DirectionGrid;
use hirad_core::tables::tau::{interpolate_scattered, interpolate_tau, projected_area};
use rayon::prelude::*;

/// The tables on the `tau` grid and what making them cost.
pub(super) struct Tau {
    pub grid: DirectionGrid,
    /// `tau` per cell.
    pub values: Vec<f32>,
    /// Albedo per cell, side lit and band.
    pub albedo: Vec<f32>,
    /// Largest relative error of the cross-section or of the scattered cross-section at the
    /// check directions.
    pub error: f32,
    pub met: bool,
    pub rays: u64,
}

/// Cells measured between two progress reports.
const CHUNK: u32 = 256;

/// Bakes `tau` and the albedo of `alone` (see the module); `progress` as in
/// [`super::bake_original`].
pub(super) fn bake_tau(
    alone: &Alone,
    weights: &EscapeWeights,
    name: &str,
    settings: &TableSettings,
    progress: &mut dyn FnMut(&str, u64, u64),
) -> Result<Tau> {
    let bands = alone.bands();
    let mut side = 4u32;
    let mut rays = 0u64;
    let mut missed = String::new();
    loop {
        let what = format!("{name}: tau on grid {side}{missed}");
        let grid = DirectionGrid::new(side).map_err(|e| anyhow!("{e:?}"))?;
        let mut cells: Vec<Intercept> = Vec::with_capacity(grid.cells() as usize);
        for start in (0..grid.cells()).step_by(CHUNK as usize) {
            progress(&what, start as u64, grid.cells() as u64);
            let end = (start + CHUNK).min(grid.cells());
            cells.par_extend((start..end).into_par_iter().map(|c| {
                intercept(
                    alone,
                    weights,
                    grid.direction(c),
                    settings.tau.rays,
                    hash3(settings.tau.seed, c, side),
                )
            }));
        }
        rays += cells.iter().map(|c| c.crossed as u64).sum::<u64>();
        let values: Vec<f32> = cells.iter().map(Intercept::tau).collect();
        let albedo: Vec<f32> = cells
            .iter()
            .flat_map(|c| (0..2).flat_map(move |side| (0..bands).map(move |b| c.albedo(side, b))))
            .collect();
        // The check: the cross-section (1 - tau) A and the scattered cross-section, which
        // predictions of the intercepted and scattered power multiply by, each relative to
        // itself (or to 5% of the box's shadow when the contents cast less), against
        // estimates with more rays than the cells'.
        progress(&what, grid.cells() as u64, grid.cells() as u64);
        let checks: Vec<(Vec3, Intercept)> = (0..settings.tau.checks)
            .into_par_iter()
            .map(|k| {
                let d = uniform_direction(settings.tau.seed, k, 0xC4EC);
                let e = intercept(
                    alone,
                    weights,
                    d,
                    settings.tau_check_rays,
                    hash3(settings.tau.seed, k, 0xC4ED),
                );
                (d, e)
            })
            .collect();
        let mut error = 0.0f32;
        for (d, e) in &checks {
            rays += e.crossed as u64;
            let (lo, hi) = (alone.lo, alone.hi);
            let pred = interpolate_tau(&grid, &values, lo, hi, *d);
            let floor = (1.0 - e.tau()).max(0.05);
            error = error.max((pred - e.tau()).abs() / floor);
            let area = projected_area(lo, hi, *d);
            for b in 0..bands {
                let a = e.total_albedo(b);
                if a <= 0.0 || area <= 0.0 {
                    continue;
                }
                let s: f32 = (0..2)
                    .map(|side| {
                        let at = side * bands + b;
                        interpolate_scattered(&grid, &values, &albedo, 2 * bands, at, lo, hi, *d)
                    })
                    .sum();
                let meas = a * (1.0 - e.tau());
                error = error.max((s / area - meas).abs() / (a * floor));
            }
        }
        let met = error <= settings.tau.target;
        missed = format!(", {side}: {:.1}% off", 100.0 * error);
        if met || side * 2 > settings.max_tau_side {
            return Ok(Tau {
                grid,
                values,
                albedo,
                error,
                met,
                rays,
            });
        }
        side *= 2;
    }
}
