//! Precomputing an original's `tau` table: one estimate per cell of a direction grid, and the
//! grid made finer until interpolation meets an error target at check directions off the
//! grid (issue 17: "resolution chosen per original by an error target").

use super::grid::{DirectionGrid, MAX_SIDE};
use super::tau::{interpolate_tau, tau};
use crate::sampling::{hash3, unit2};
use crate::visibility::Visibility;
use glam::Vec3;

/// How a `tau` table is made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TauSettings {
    /// Rays along each side of the stratified grid of one estimate (`rays x rays` rays).
    pub rays: u32,
    /// Largest absolute error of interpolated `tau` allowed at the check directions.
    pub target: f32,
    /// Check directions drawn per grid tried. The check is statistical: a direction where
    /// interpolation misses between the checks can remain (12 checks passed a grid of side 8
    /// that missed by 0.09 elsewhere on a sparse ball of leaves; 64 asked for side 16).
    pub checks: u32,
    /// Seed of the rays' jitter and of the check directions.
    pub seed: u32,
}

impl Default for TauSettings {
    /// 256 x 256 rays per direction (a binomial noise of at most 0.002: a check compares two
    /// estimates, so the target must stand well above it), a target of 0.01 absolute, 64
    /// check directions.
    fn default() -> Self {
        Self {
            rays: 256,
            target: 0.01,
            checks: 64,
            seed: 1,
        }
    }
}

/// A finished table's grid and what was measured of it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TauTable {
    /// The grid whose cells the values follow (the caller's slice, first `cells()` entries).
    pub grid: DirectionGrid,
    /// The largest error of interpolated `tau` at the last grid's check directions, against
    /// estimates made there.
    pub error: f32,
    /// Rays cast in all, the grids tried and the checks included.
    pub rays: u64,
    /// True when the error met the target; false when the grid reached the storage or
    /// [`MAX_SIDE`] first (the table is then the finest tried).
    pub met: bool,
}

/// Why a table cannot be made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BakeError {
    /// The storage holds fewer values than the first grid's cells.
    Storage {
        /// Values the first grid needs.
        needed: u32,
    },
    /// A setting is out of range (no rays, or a target that is not a positive number).
    Settings,
}

/// Fills `out` with `tau` at every cell centre of `grid` (`out` at least `grid.cells()`
/// long); returns the rays cast. A line crosses the same polygons both ways, so
/// `tau(-d) = tau(d)`, and a grid of even side maps the centre of a cell to the centre of
/// its antipodal cell: each such pair is estimated once.
pub fn bake_tau<V: Visibility + ?Sized>(
    vis: &V,
    lo: Vec3,
    hi: Vec3,
    grid: DirectionGrid,
    settings: &TauSettings,
    out: &mut [f32],
) -> u64 {
    let mut rays = 0u64;
    let cells = grid.cells().min(out.len() as u32);
    for c in 0..cells {
        let d = grid.direction(c);
        let opposite = grid.cell_of(-d);
        if opposite < c && (grid.direction(opposite) + d).length() < 1e-4 {
            out[c as usize] = out[opposite as usize];
            continue;
        }
        let e = tau(
            vis,
            lo,
            hi,
            d,
            settings.rays,
            hash3(settings.seed, c, grid.side()),
        );
        out[c as usize] = e.tau;
        rays += e.rays as u64;
    }
    rays
}

/// The largest error of `values` interpolated on `grid` at `settings.checks` directions
/// drawn uniformly (off the grid's centres), against `tau` estimated there; and the rays.
pub fn check_tau<V: Visibility + ?Sized>(
    vis: &V,
    lo: Vec3,
    hi: Vec3,
    grid: DirectionGrid,
    values: &[f32],
    settings: &TauSettings,
) -> (f32, u64) {
    let (mut worst, mut rays) = (0.0f32, 0u64);
    for k in 0..settings.checks {
        let (a, b) = unit2(hash3(settings.seed, k, 0xC4EC));
        let z = 1.0 - 2.0 * a;
        let r = libm::sqrtf((1.0 - z * z).max(0.0));
        let phi = 2.0 * core::f32::consts::PI * b;
        let d = Vec3::new(r * libm::cosf(phi), r * libm::sinf(phi), z);
        let e = tau(
            vis,
            lo,
            hi,
            d,
            settings.rays,
            hash3(settings.seed, k, 0xC4ED),
        );
        rays += e.rays as u64;
        worst = worst.max((interpolate_tau(&grid, values, lo, hi, d) - e.tau).abs());
    }
    (worst, rays)
}

/// Bakes `tau` on grids of side `first`, twice that, and so on, until the check error meets
/// `settings.target` or the next grid would not fit in `out` or exceed [`MAX_SIDE`]; the
/// values of the grid returned are the first `grid.cells()` entries of `out`.
pub fn bake_tau_to_target<V: Visibility + ?Sized>(
    vis: &V,
    lo: Vec3,
    hi: Vec3,
    first: u32,
    settings: &TauSettings,
    out: &mut [f32],
) -> Result<TauTable, BakeError> {
    if settings.rays == 0 || settings.target.is_nan() || settings.target <= 0.0 {
        return Err(BakeError::Settings);
    }
    let mut grid = DirectionGrid::new(first.clamp(1, MAX_SIDE)).map_err(|_| BakeError::Settings)?;
    if (out.len() as u64) < grid.cells() as u64 {
        return Err(BakeError::Storage {
            needed: grid.cells(),
        });
    }
    let mut rays = 0u64;
    loop {
        rays += bake_tau(vis, lo, hi, grid, settings, out);
        let (error, r) = check_tau(vis, lo, hi, grid, out, settings);
        rays += r;
        let met = error <= settings.target;
        let next = grid.side() * 2;
        let fits = next <= MAX_SIDE && (next as u64 * next as u64) <= out.len() as u64;
        if met || !fits {
            return Ok(TauTable {
                grid,
                error,
                rays,
                met,
            });
        }
        grid = DirectionGrid::new(next).map_err(|_| BakeError::Settings)?;
    }
}
