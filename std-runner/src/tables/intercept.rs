//! What a sun's light meets first inside an original's box: the contents' cross-section and
//! the share of what they intercept that they scatter out of the box, from the same parallel
//! rays, each asking which polygon and which side of it the light meets first.
//!
//! The share comes from the escape weights of the polygons' sides: the power that leaves the
//! box per watt that falls on a side, over every path. By reciprocity (Lambertian surfaces,
//! symmetric transport), the part of a side's diffuse emission that escapes equals the
//! irradiance of that side under a uniform sky of radiance 1/pi (irradiance 1 on an open
//! plane), interreflections included; so one hr solve of the original under suns spread
//! evenly over the sphere gives every side's weight, and the scattered power of any sun is
//! then a sum over what its rays hit. The albedo so known on the fine `tau` grid follows a
//! sun across the plane of a leaf, whose two sides reflect differently.

use super::original::Alone;
use crate::scene;
use crate::solve::RayonExecutor;
use anyhow::Result;
use glam::Vec3;
use hirad_core::hr::Settings;
use hirad_core::limits::MAX_BANDS;
use hirad_core::tables::grid::DirectionGrid;
use hirad_core::tables::tau::parallel_rays;
use hirad_core::visibility::Visibility;

/// Per side of every polygon, the power scattered out of the original's box per watt that
/// falls on that side from outside (dimensionless, per band).
pub struct EscapeWeights {
    /// `[2 * polygon + side]`, side 0 the front.
    weights: Vec<[f32; MAX_BANDS]>,
}

impl EscapeWeights {
    /// Solves `alone` under suns at the centres of a grid of side `side` (each of
    /// irradiance `4 pi / side^2 / pi` W/m^2: a uniform sky of radiance 1/pi) and weighs
    /// each side's total irradiance by the materials: `rho_s G_s + tau G_other`.
    pub fn solve(
        alone: &Alone,
        side: u32,
        settings: &Settings,
        exec: &mut RayonExecutor,
    ) -> Result<Self> {
        let grid = DirectionGrid::new(side.clamp(1, 64)).map_err(|e| anyhow::anyhow!("{e:?}"))?;
        let bands = alone.bands();
        let share = grid.solid_angle() / std::f32::consts::PI;
        let suns = (0..grid.cells())
            .map(|c| scene::light(grid.direction(c), &[share; MAX_BANDS][..bands]))
            .collect();
        let lit = alone.solve_lights(suns, Vec::new(), settings, exec)?;
        let mut weights = Vec::with_capacity(2 * alone.polygons.len());
        for p in 0..alone.polygons.len() {
            let m = &alone.scene.materials[alone.materials[p] as usize].data;
            let g = |s: usize| lit.table.irradiance(p, s);
            let (front, back) = (g(0), g(1));
            let at = |v: &[f32], b: usize| v.get(b).copied().unwrap_or(0.0);
            let mut w = [[0.0f32; MAX_BANDS]; 2];
            let [wf, wb] = &mut w;
            for (b, (f, k)) in wf.iter_mut().zip(wb.iter_mut()).enumerate().take(bands) {
                let (gf, gb) = (at(front, b), at(back, b));
                *f = m.rho_front[b] * gf + m.tau[b] * gb;
                *k = m.rho_back[b] * gb + m.tau[b] * gf;
            }
            weights.extend(w);
        }
        Ok(Self { weights })
    }

    /// The weight of side `side` (0 front) of polygon `poly`.
    pub fn of(&self, poly: u32, side: usize) -> &[f32; MAX_BANDS] {
        &self.weights[2 * poly as usize + side]
    }
}

/// What parallel rays along one direction met.
#[derive(Clone, Copy, Debug, Default)]
pub struct Intercept {
    /// Rays that crossed the box.
    pub crossed: u32,
    /// Of those, rays that met a polygon.
    pub blocked: u32,
    /// Sum over the blocked rays of the escape weight of the side they met, per side met
    /// (0 fronts, 1 backs) and band.
    pub scattered: [[f64; MAX_BANDS]; 2],
}

impl Intercept {
    /// Uncollided transmittance (1 when no ray crossed).
    pub fn tau(&self) -> f32 {
        if self.crossed > 0 {
            1.0 - self.blocked as f32 / self.crossed as f32
        } else {
            1.0
        }
    }

    /// Of the power intercepted, the share scattered out in band `band` after falling on
    /// side `side` (0 fronts, 1 backs) of the polygons (0 when nothing is intercepted).
    pub fn albedo(&self, side: usize, band: usize) -> f32 {
        if self.blocked > 0 {
            ((self.scattered[side][band] / self.blocked as f64) as f32).clamp(0.0, 1.0)
        } else {
            0.0
        }
    }

    /// Of the power intercepted, the share scattered out in band `band`.
    pub fn total_albedo(&self, band: usize) -> f32 {
        (self.albedo(0, band) + self.albedo(1, band)).min(1.0)
    }
}

/// Casts a stratified `g x g` grid of rays (jittered by `seed`) from a sun towards `d`
/// across `alone`'s box and sums what they meet first.
pub fn intercept(alone: &Alone, weights: &EscapeWeights, d: Vec3, g: u32, seed: u32) -> Intercept {
    let d = d.normalize_or_zero();
    let mut r = Intercept::default();
    let none = hirad_core::limits::NONE;
    let (crossed, _) = parallel_rays(alone.lo, alone.hi, d, g, seed, |from, to| {
        // The light comes from the sun's side: from `to` (the end towards `d`) to `from`.
        if let Some((p, _)) = alone.vis.first_hit(to, from, [none, none]) {
            r.blocked += 1;
            let side = if alone.normals[p as usize].dot(d) >= 0.0 {
                0
            } else {
                1
            };
            for (s, w) in r.scattered[side].iter_mut().zip(weights.of(p, side)) {
                *s += *w as f64;
            }
        }
    });
    r.crossed = crossed;
    r
}
