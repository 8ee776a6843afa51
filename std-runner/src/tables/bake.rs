//! Baking an original's tables: the escape weights, `tau` and the albedo on their own grid,
//! the polygons' first scattering on the grid of their visible fractions (small originals),
//! then the phase table on grids of outgoing directions (a solve per cell) and incoming
//! directions (rays, by reciprocity: see [`super::response`]) made finer until
//! interpolation meets error targets at check directions off the grids (issue 17:
//! "resolution chosen per original by an error target").

use super::OriginalTables;
use super::intercept::EscapeWeights;
use super::original::Alone;
use super::response::{PhaseValues, Returns, phase_values};
use super::sample::{Sample, Visibilities, samples_at};
use super::single_bake::{bake_single, first_scattering};
use super::tau_bake::bake_tau;
use crate::scene::Scene;
use crate::solve::RayonExecutor;
use anyhow::{Result, anyhow};
use glam::Vec3;
use hirad_core::hr::Settings;
use hirad_core::limits::MAX_BANDS;
use hirad_core::sampling::{hash3, unit2};
use hirad_core::tables::bake::TauSettings;
use hirad_core::tables::grid::{DirectionGrid, MAX_SIDE};
use hirad_core::tables::single::SingleScatter;
use hirad_core::tables::tau::{interpolate_tau, tau};
use std::time::Instant;

/// How tables are made.
#[derive(Clone, Copy, Debug)]
pub struct TableSettings {
    /// The `tau` table's rays, target and checks.
    pub tau: TauSettings,
    /// The hr solves of the original under each sun.
    pub solve: Settings,
    /// Rays along each side of the estimates that check the `tau` table (more than the
    /// cells', so that the check's own noise stays below the target).
    pub tau_check_rays: u32,
    /// Side of the grid of suns whose solve gives the polygons' escape weights (see
    /// [`super::intercept`]).
    pub escape_side: u32,
    /// Largest side of the `tau` grid.
    pub max_tau_side: u32,
    /// Side of the first grid of incoming directions tried.
    pub first_side: u32,
    /// Largest side of the incoming grid (rays only; the response holds its cells times the
    /// outgoing grid's).
    pub max_side: u32,
    /// Side of the first grid of outgoing directions tried.
    pub first_out_side: u32,
    /// Largest side of the outgoing grid (each cell is one solve).
    pub max_out_side: u32,
    /// Points along each side of the stratified set on every polygon from which rays test
    /// whether it is seen from an outgoing direction (k x k rays a polygon, k at most 15).
    pub out_rays: u32,
    /// The same for the check directions.
    pub check_out_rays: u32,
    /// Side of the first grid of the polygons' visible fractions tried (their first
    /// scattering kept apart, see [`hirad_core::tables::single`]); 0 keeps none apart.
    pub first_single_side: u32,
    /// Largest side of that grid; 0 keeps no first scattering apart.
    pub max_single_side: u32,
    /// Largest size of the visible fractions (bytes: cells x polygons): larger originals
    /// leave all their light to the phase table.
    pub max_single_bytes: u64,
    /// Rays along each side of the stratified set on every polygon for its visible
    /// fractions (k x k, at most 15).
    pub single_rays: u32,
    /// Largest error of the interpolated first scattering at the check directions
    /// (relative as the intensity's).
    pub single_target: f32,
    /// Largest relative error of the interpolated scattered fraction.
    pub scattered_target: f32,
    /// The grids are made finer until the interpolated intensity's error (see
    /// [`OriginalTables::intensity_error`]) is at most this, or they reach their largest.
    pub intensity_target: f32,
    /// The tables meet their targets only if that error is at most this.
    pub intensity_limit: f32,
    /// Incoming check directions (each one solve).
    pub checks: u32,
    /// Outgoing check directions per incoming check direction.
    pub out_checks: u32,
    /// Seed of the check directions and of the rays' jitter.
    pub seed: u32,
}

impl Default for TableSettings {
    fn default() -> Self {
        // The hierarchy alone, at a fine epsilon: what is measured is power leaving the box
        // and polygons' means, not each polygon's own light (the gather would add 4.7 times
        // the time on a maize plant and move its albedo by 0.02%).
        let solve = Settings {
            epsilon: 1e-4,
            final_rays: 0,
            ..Settings::default()
        };
        Self {
            // 512 x 512 rays a cell: a cross-section of a tenth of the box is then known to
            // 0.6% (binomial noise); the target is 1% of the cross-section.
            tau: TauSettings {
                rays: 512,
                target: 0.01,
                checks: 64,
                seed: 1,
            },
            tau_check_rays: 1024,
            escape_side: 16,
            solve,
            max_tau_side: 128,
            first_side: 4,
            max_side: 32,
            first_out_side: 8,
            max_out_side: 32,
            out_rays: 4,
            check_out_rays: 8,
            first_single_side: 32,
            max_single_side: 128,
            // 8 MiB: 512 polygons at side 128, 2048 at 64, 8192 at 32.
            max_single_bytes: 8 << 20,
            single_rays: 15,
            // Below the acceptance's 5% for the whole intensity, which the rest shares.
            single_target: 0.01,
            scattered_target: 0.02,
            // The grids are held to 3% at the bake's own check directions so that other
            // directions stay within 5%.
            intensity_target: 0.03,
            intensity_limit: 0.05,
            checks: 16,
            out_checks: 8,
            seed: 1,
        }
    }
}

/// Rays along each side of the `tau` estimate at an incoming cell's centre (its energy
/// check; 65,536 rays, a binomial noise of at most 0.002).
const TAU_CHECK_RAYS: u32 = 256;

/// A direction drawn uniformly on the sphere from `(seed, k, salt)`.
pub fn uniform_direction(seed: u32, k: u32, salt: u32) -> Vec3 {
    let (a, b) = unit2(hash3(seed, k, salt));
    let z = 1.0 - 2.0 * a;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * b;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// A check direction with what was measured there: the intensity towards a few outgoing
/// directions.
pub(super) struct Check {
    pub sample: Sample,
    /// (outgoing direction, intensity per band).
    pub out: Vec<(Vec3, [f32; MAX_BANDS])>,
}

/// The error of an interpolated intensity `pred` against the measured `meas`, relative to
/// `meas` or, when that is darker, to the mean intensity over all directions `mean`.
pub(super) fn intensity_error(pred: f32, meas: f32, mean: f32) -> f32 {
    let scale = meas.max(mean);
    if scale > 0.0 {
        (pred - meas).abs() / scale
    } else {
        0.0
    }
}

/// The error of an interpolated scattered fraction, relative to the measured one or to 0.01.
pub(super) fn scattered_error(pred: f32, meas: f32) -> f32 {
    (pred - meas).abs() / meas.max(0.01)
}

/// Mean intensity over all directions of a sample (m^2/sr): its scattered power over 4 pi.
pub(super) fn mean_intensity(s: &Sample, band: usize) -> f32 {
    s.scattered[band] * s.area / (4.0 * std::f32::consts::PI)
}

/// Bakes the tables of original `index` of `scene`. `progress(what, done, total)` is called
/// as work is done.
pub fn bake_original(
    scene: &Scene,
    index: usize,
    settings: &TableSettings,
    exec: &mut RayonExecutor,
    progress: &mut dyn FnMut(&str, u64, u64),
) -> Result<OriginalTables> {
    let alone = Alone::new(scene, index)?;
    bake_alone(scene, index, &alone, settings, exec, progress)
}

/// [`bake_original`] of an original already taken out of its scene.
pub fn bake_alone(
    scene: &Scene,
    index: usize,
    alone: &Alone,
    settings: &TableSettings,
    exec: &mut RayonExecutor,
    progress: &mut dyn FnMut(&str, u64, u64),
) -> Result<OriginalTables> {
    let start = Instant::now();
    if settings.first_side == 0
        || settings.max_side > MAX_SIDE
        || settings.first_out_side == 0
        || settings.max_out_side > MAX_SIDE
        || settings.max_single_side > MAX_SIDE
        || settings.first_single_side > MAX_SIDE
        || settings.out_rays == 0
    {
        return Err(anyhow!("table settings out of range"));
    }
    let bands = alone.bands();
    let name = scene.originals[index].name.clone();
    progress(&format!("{name}: escape weights"), 0, 1);
    let weights = EscapeWeights::solve(alone, settings.escape_side, &settings.solve, exec)?;
    let tt = bake_tau(alone, &weights, &name, settings, progress)?;
    let mut rays = tt.rays;
    // The contents' cross-section along a direction, by the tau table (m^2): the light
    // leaving towards an observer is stored per unit of it.
    let shadow = |d: Vec3| {
        (1.0 - interpolate_tau(&tt.grid, &tt.values, alone.lo, alone.hi, d))
            * hirad_core::tables::tau::projected_area(alone.lo, alone.hi, d)
    };
    let per_shadow = |j: f32, d: Vec3| {
        let s = shadow(d);
        if s > 0.0 { j / s } else { 0.0 }
    };
    let mut solves = 1u32;

    // Check directions, off every grid (drawn uniformly), each solved once.
    // Several suns a solve (see `Alone::solve_many`).
    progress(&format!("{name}: check suns"), 0, 1);
    let suns: Vec<Vec3> = (0..settings.checks)
        .map(|k| uniform_direction(settings.seed, k, 0x7AB1E))
        .collect();
    let solved = samples_at(alone, &suns, settings, exec)?;
    solves += solved.len() as u32;
    let mut checks = Vec::new();
    for (k, sample) in (0..settings.checks).zip(solved) {
        let mut out = Vec::new();
        for m in 0..settings.out_checks {
            let o = uniform_direction(settings.seed, k * 1000 + m, 0x0C7);
            let (i, r) = sample.intensity(
                alone,
                o,
                settings.check_out_rays,
                hash3(settings.seed, k, m),
            );
            rays += r;
            out.push((o, i));
        }
        checks.push(Check { sample, out });
    }

    // The polygons' first scattering, kept apart when the original is small enough: the
    // phase table then holds the light scattered more than once, which is smooth.
    // With it, the check suns' reach on each polygon, for the first scattering at the
    // outgoing cells.
    let (single, sun_seen) =
        match bake_single(alone, &checks, &name, settings, &mut rays, progress)? {
            Some(s) => (Some(s.scatterers), s.sun_seen),
            None => (None, Vec::new()),
        };
    let single_view = single
        .as_ref()
        .map(|s| SingleScatter::new(s.grid, bands, s.polygons, &s.shape, &s.visible))
        .transpose()
        .map_err(|e| anyhow!("{name}: first scattering: {e:?}"))?;
    let k = settings.single_rays.clamp(1, 15);

    // The outgoing grid: the check suns' light, measured on the grid and interpolated at
    // the outgoing check directions.
    let mut out_side = settings.first_out_side.min(settings.max_out_side);
    let mut out_tried = Vec::new();
    let mut missed = String::new();
    loop {
        let grid = DirectionGrid::new(out_side).map_err(|e| anyhow!("{e:?}"))?;
        let mut worst = 0.0f32;
        progress(&format!("{name}: outgoing grid {out_side}{missed}"), 0, 1);
        let this = Visibilities::new(alone, grid, settings.out_rays, settings.seed ^ 0x5EED);
        rays += this.rays();
        for (k_check, c) in checks.iter().enumerate() {
            progress(
                &format!("{name}: outgoing grid {out_side}{missed}"),
                k_check as u64,
                checks.len() as u64,
            );
            let mut values = c.sample.intensity_grid(alone, grid, &this);
            let d = c.sample.source;
            if let Some(vd) = sun_seen.get(k_check) {
                // What the grid holds: the light scattered more than once.
                for cell in 0..grid.cells() {
                    let o = grid.direction(cell);
                    for b in 0..bands {
                        values[cell as usize * bands + b] -=
                            first_scattering(alone, d, o, b, |p| vd[p], |p| this.fraction(cell, p));
                    }
                }
            }
            for (o, meas) in &c.out {
                for b in 0..bands {
                    let w = grid.weights(*o);
                    let pred: f32 = w
                        .iter()
                        .map(|&(cell, wt)| {
                            wt * per_shadow(values[cell as usize * bands + b], grid.direction(cell))
                        })
                        .sum::<f32>()
                        * shadow(*o)
                        + single_view.map_or(0.0, |s| s.intensity(d, *o, b));
                    worst = worst.max(intensity_error(pred, meas[b], mean_intensity(&c.sample, b)));
                }
            }
        }
        missed = format!(", {out_side}: {:.1}% off", 100.0 * worst);
        out_tried.push((out_side, worst));
        if worst <= settings.intensity_target || out_side * 2 > settings.max_out_side {
            progress(&format!("{name}: outgoing grid {out_side}{missed}"), 1, 1);
            break;
        }
        out_side *= 2;
    }
    let outgoing = DirectionGrid::new(out_side).map_err(|e| anyhow!("{e:?}"))?;

    // The light every polygon side sends towards each outgoing cell, by a solve there.
    let what = format!("{name}: suns on the outgoing grid {out_side}");
    // With the first scattering kept apart, each side's direct light at the outgoing cells
    // (from its visible fractions there) is set apart from what the solves give.
    let direct = single_view.map(|_| Visibilities::new(alone, outgoing, k, settings.seed ^ 0xD1));
    if let Some(v) = &direct {
        rays += v.rays();
    }
    let returns = Returns::solve(
        alone,
        outgoing,
        direct.as_ref(),
        settings,
        exec,
        &mut |done, total| progress(&what, done, total),
    )?;
    solves += outgoing.cells();
    // `tau` at an incoming cell's centre by its own rays (the energy check's uncollided part).
    let tau_at = |d: Vec3| {
        let seed = hash3(
            settings.tau.seed,
            d.x.to_bits(),
            d.y.to_bits() ^ d.z.to_bits(),
        );
        tau(&alone.vis, alone.lo, alone.hi, d, TAU_CHECK_RAYS, seed).tau
    };

    // The incoming grid, rays only.
    let mut side = settings.first_side.min(settings.max_side);
    let mut tried = Vec::new();
    loop {
        progress(&format!("{name}: incoming grid {side}"), 0, 1);
        let incoming = DirectionGrid::new(side).map_err(|e| anyhow!("{e:?}"))?;
        // The sun's reach on each polygon, finer than the outgoing grid's: it weighs every
        // polygon's light in the response and closes the cell's energy.
        let lit = Visibilities::new(
            alone,
            incoming,
            settings.check_out_rays,
            settings.seed ^ 0x11,
        );
        rays += lit.rays();
        let values = phase_values(
            alone, &weights, &returns, incoming, &lit, outgoing, &shadow, &tau_at,
        );
        let PhaseValues {
            shares,
            response,
            absorbed,
            residual,
        } = values;
        let mut t = OriginalTables {
            name: name.clone(),
            index,
            polygons: alone.polygons.len(),
            bands,
            lo: alone.lo,
            hi: alone.hi,
            tau_grid: tt.grid,
            tau: tt.values.clone(),
            albedo: tt.albedo.clone(),
            tau_error: tt.error,
            incoming,
            outgoing,
            shares,
            response,
            single: single.clone(),
            absorbed,
            residual,
            scattered_error: 0.0,
            tried: tried.clone(),
            out_tried: out_tried.clone(),
            intensity_error: 0.0,
            met: false,
            solves,
            rays,
            seconds: 0.0,
        };
        let view = t.view();
        let (mut s_err, mut i_err) = (0.0f32, 0.0f32);
        for c in &checks {
            let d = c.sample.source;
            for b in 0..bands {
                let pred = view.scattered(d, b) / c.sample.area;
                s_err = s_err.max(scattered_error(pred, c.sample.scattered[b]));
                for (o, meas) in &c.out {
                    i_err = i_err.max(intensity_error(
                        view.intensity(d, *o, b),
                        meas[b],
                        mean_intensity(&c.sample, b),
                    ));
                }
            }
        }
        tried.push((side, s_err, i_err));
        t.tried = tried.clone();
        t.scattered_error = s_err;
        t.intensity_error = i_err;
        let aimed = t.scattered_error <= settings.scattered_target
            && t.intensity_error <= settings.intensity_target;
        if aimed || side * 2 > settings.max_side {
            t.met = tt.met
                && t.scattered_error <= settings.scattered_target
                && t.intensity_error <= settings.intensity_limit;
            t.seconds = start.elapsed().as_secs_f64();
            return Ok(t);
        }
        side *= 2;
    }
}
