//! What an original does with the light of one sun: an hr solve of it alone, and the light
//! that leaves its box, measured as an observer would (rays from outside reading the
//! surfaces they meet).

use super::bake::TableSettings;
use super::original::{Alone, Lit};
use crate::solve::RayonExecutor;
use anyhow::Result;
use glam::Vec3;
use hirad_core::hr::Settings;
use hirad_core::limits::MAX_BANDS;
use hirad_core::sampling::hash3;
use hirad_core::tables::grid::DirectionGrid;
use hirad_core::tables::tau::{projected_area, tau};
use rayon::prelude::*;

/// An original under a sun of 1 W/m^2 towards `source`; fractions are of the power that
/// crosses the box's projection, `A(source)` W.
pub struct Sample {
    /// Unit direction towards the sun (original's frame).
    pub source: Vec3,
    /// The box's projected area along `source` (m^2).
    pub area: f32,
    /// Scattered out of the box (the solver's escaped power), per band.
    pub scattered: [f32; MAX_BANDS],
    /// Absorbed by the surfaces (both sides), per band.
    pub absorbed: [f32; MAX_BANDS],
    /// Intercepted: the sun's direct light on the surfaces, per band.
    pub direct: [f32; MAX_BANDS],
    /// Uncollided transmittance along `source`, by rays.
    pub tau: f32,
    /// The solve.
    pub lit: Lit,
}

/// Solves `alone` under a sun towards `source` and measures its `tau` there.
pub fn sample_at(
    alone: &Alone,
    source: Vec3,
    settings: &TableSettings,
    exec: &mut RayonExecutor,
) -> Result<Sample> {
    sample_sides(alone, source, settings, Settings::BOTH_SIDES, exec)
}

/// [`sample_at`] with the sun lighting only the sides of the polygons named by `sides` (see
/// [`Settings::sun_sides`]).
pub fn sample_sides(
    alone: &Alone,
    source: Vec3,
    settings: &TableSettings,
    sides: u8,
    exec: &mut RayonExecutor,
) -> Result<Sample> {
    let source = source.normalize();
    let solve = Settings {
        sun_sides: sides,
        ..settings.solve
    };
    let lit = alone.solve(source, &solve, exec)?;
    Ok(measure(alone, source, lit, settings))
}

/// [`sample_at`] at every direction of `sources` (unit), several suns per solve (see
/// [`Alone::solve_many`]); in the order of `sources`.
pub fn samples_at(
    alone: &Alone,
    sources: &[Vec3],
    settings: &TableSettings,
    exec: &mut RayonExecutor,
) -> Result<Vec<Sample>> {
    let sources: Vec<Vec3> = sources.iter().map(|d| d.normalize()).collect();
    let solve = Settings {
        sun_sides: Settings::BOTH_SIDES,
        ..settings.solve
    };
    let lits = alone.solve_many(&sources, &solve, exec)?;
    Ok(sources
        .iter()
        .zip(lits)
        .map(|(d, lit)| measure(alone, *d, lit, settings))
        .collect())
}

/// What `lit`, the solve under a sun towards `source`, tells: the box's area, the light
/// scattered, absorbed and intercepted, and `tau` by rays.
fn measure(alone: &Alone, source: Vec3, lit: Lit, settings: &TableSettings) -> Sample {
    let area = projected_area(alone.lo, alone.hi, source);
    let t = tau(
        &alone.vis,
        alone.lo,
        alone.hi,
        source,
        settings.tau.rays,
        hash3(
            settings.tau.seed,
            source.x.to_bits(),
            source.y.to_bits() ^ source.z.to_bits(),
        ),
    );
    let b = &lit.stats.balance;
    let frac = |v: &[f64; MAX_BANDS]| {
        let mut f = [0.0f32; MAX_BANDS];
        for (o, x) in f.iter_mut().zip(v) {
            *o = if area > 0.0 {
                (*x / area as f64) as f32
            } else {
                0.0
            };
        }
        f
    };
    let mut absorbed = [0.0f64; MAX_BANDS];
    for (a, (x, y)) in absorbed
        .iter_mut()
        .zip(b.absorbed.iter().zip(&b.absorbed_backs))
    {
        *a = x + y;
    }
    Sample {
        source,
        area,
        scattered: frac(&b.escaped),
        absorbed: frac(&absorbed),
        direct: frac(&b.direct),
        tau: t.tau,
        lit,
    }
}

impl Sample {
    /// The intensity (m^2/sr per band) leaving the box towards the unit `towards`, each
    /// polygon's visible fraction from `k x k` rays; and the rays cast.
    pub fn intensity(
        &self,
        alone: &Alone,
        towards: Vec3,
        k: u32,
        seed: u32,
    ) -> ([f32; MAX_BANDS], u64) {
        let visible = alone.visible(towards, k, seed);
        let i = self.lit.intensity(alone, towards, |p| visible[p]);
        (i, (alone.polygons.len() as u64) * (k * k) as u64)
    }

    /// The intensity towards the centre of every cell of `grid` (cell-major, `bands` values
    /// each), from the polygons' visible fractions per cell (`visible`, see
    /// [`Visibilities`]).
    pub fn intensity_grid(
        &self,
        alone: &Alone,
        grid: DirectionGrid,
        visible: &Visibilities,
    ) -> Vec<f32> {
        let bands = alone.bands();
        let cells: Vec<[f32; MAX_BANDS]> = (0..grid.cells())
            .into_par_iter()
            .map(|c| {
                self.lit
                    .intensity(alone, grid.direction(c), |p| visible.fraction(c, p))
            })
            .collect();
        cells
            .iter()
            .flat_map(|i| i[..bands].iter().copied())
            .collect()
    }
}

/// Per cell of an outgoing grid and polygon, the polygon's visible fraction towards the
/// cell's centre (in 1/(k x k) steps, one byte each).
pub struct Visibilities {
    polygons: usize,
    samples: u32,
    counts: Vec<u8>,
}

impl Visibilities {
    /// Casts `k x k` rays (k at most 15) from every polygon towards every cell of `grid`.
    pub fn new(alone: &Alone, grid: DirectionGrid, k: u32, seed: u32) -> Self {
        let k = k.clamp(1, 15);
        let n = alone.polygons.len();
        let counts: Vec<u8> = (0..grid.cells())
            .into_par_iter()
            .flat_map_iter(|c| {
                alone
                    .visible(grid.direction(c), k, hash3(seed, c, grid.side()))
                    .into_iter()
                    .map(move |f| (f * (k * k) as f32).round() as u8)
            })
            .collect();
        Self {
            polygons: n,
            samples: k * k,
            counts,
        }
    }

    /// The visible fraction of polygon `p` towards cell `cell`.
    pub fn fraction(&self, cell: u32, p: usize) -> f32 {
        self.counts[cell as usize * self.polygons + p] as f32 / self.samples as f32
    }

    /// Rays cast.
    pub fn rays(&self) -> u64 {
        self.counts.len() as u64 * self.samples as u64
    }
}
