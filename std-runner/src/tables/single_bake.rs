//! The polygons' first scattering kept apart (see [`hirad_core::tables::single`]): each
//! polygon's shape and material, and the fraction of it visible from each cell of a grid
//! made finer (32, 64, ...) until the first scattering interpolated at the check directions
//! is within its target of the same sum with visible fractions cast at those directions.
//! Only for originals whose fractions fit the byte budget; larger ones leave all their
//! light to the phase table.

use super::Scatterers;
use super::bake::{Check, TableSettings, intensity_error, mean_intensity};
use super::original::Alone;
use anyhow::{Result, anyhow};
use glam::Vec3;
use hirad_core::sampling::hash3;
use hirad_core::tables::grid::DirectionGrid;
use hirad_core::tables::single::{SingleScatter, VISIBLE_ONE, first_scatter, shape_stride};
use rayon::prelude::*;

/// Cells measured between two progress reports.
const CHUNK: u32 = 256;

/// Polygon `p`'s front and back reflectance and transmittance in band `b`.
pub(super) fn material(alone: &Alone, p: usize, b: usize) -> [f32; 3] {
    let m = &alone.scene.materials[alone.materials[p] as usize].data;
    [m.rho_front[b], m.rho_back[b], m.tau[b]]
}

/// The first scattering towards `o` of a sun towards `d` (m^2/sr, band `b`), from every
/// polygon's visible fractions towards the sun (`vd`) and the observer (`vo`).
pub(super) fn first_scattering(
    alone: &Alone,
    d: Vec3,
    o: Vec3,
    b: usize,
    vd: impl Fn(usize) -> f32,
    vo: impl Fn(usize) -> f32,
) -> f32 {
    (0..alone.polygons.len())
        .map(|p| {
            let f = first_scatter(
                alone.normals[p],
                alone.areas[p],
                material(alone, p, b),
                d,
                o,
            );
            if f > 0.0 { f * vd(p) * vo(p) } else { 0.0 }
        })
        .sum()
}

/// The scatterers of an original, and each check sun's visible fractions (cast at its
/// direction, per polygon), which the outgoing grid's refinement uses too.
pub(super) struct Single {
    pub scatterers: Scatterers,
    pub sun_seen: Vec<Vec<f32>>,
}

/// Bakes the scatterers of `alone`, or `None` when its visible fractions would not fit
/// `settings.max_single_bytes` on the first grid (or `max_single_side` is 0). `rays` counts
/// the rays cast.
pub(super) fn bake_single(
    alone: &Alone,
    checks: &[Check],
    name: &str,
    settings: &TableSettings,
    rays: &mut u64,
    progress: &mut dyn FnMut(&str, u64, u64),
) -> Result<Option<Single>> {
    let n = alone.polygons.len();
    let fits = |side: u32| (side as u64).pow(2) * n as u64 <= settings.max_single_bytes;
    let mut side = settings.first_single_side.min(settings.max_single_side);
    if side == 0 || !fits(side) {
        return Ok(None);
    }
    let bands = alone.bands();
    let k = settings.single_rays.clamp(1, 15);
    let mut shape = Vec::with_capacity(n * shape_stride(bands));
    for p in 0..n {
        shape.extend_from_slice(&alone.normals[p].to_array());
        shape.push(alone.areas[p]);
        for b in 0..bands {
            shape.extend_from_slice(&material(alone, p, b));
        }
    }
    // Visible fractions cast at the check directions themselves: what the grid is held to.
    let seen = |d: Vec3, salt: u32| alone.visible(d, k, hash3(settings.seed, salt, 0x51));
    let exact: Vec<(Vec<f32>, Vec<Vec<f32>>)> = checks
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let vd = seen(c.sample.source, i as u32);
            let vo = (c.out.iter().enumerate())
                .map(|(j, (o, _))| seen(*o, 1000 + (i * 64 + j) as u32))
                .collect();
            (vd, vo)
        })
        .collect();
    *rays += (checks.len() * (1 + settings.out_checks as usize) * n) as u64 * (k * k) as u64;
    let mut tried = Vec::new();
    loop {
        let grid = DirectionGrid::new(side).map_err(|e| anyhow!("{e:?}"))?;
        let what = format!("{name}: first scattering, grid {side}");
        let mut visible = Vec::with_capacity(grid.cells() as usize * n);
        for start in (0..grid.cells()).step_by(CHUNK as usize) {
            progress(&what, start as u64, grid.cells() as u64);
            let end = (start + CHUNK).min(grid.cells());
            let part: Vec<u8> = (start..end)
                .into_par_iter()
                .flat_map_iter(|c| {
                    alone
                        .visible(grid.direction(c), k, hash3(settings.seed, c, side))
                        .into_iter()
                        .map(|f| (f * VISIBLE_ONE as f32).round() as u8)
                })
                .collect();
            visible.extend(part);
        }
        *rays += visible.len() as u64 * (k * k) as u64;
        let table = SingleScatter::new(grid, bands, n, &shape, &visible)
            .map_err(|e| anyhow!("{name}: first scattering: {e:?}"))?;
        let mut worst = 0.0f32;
        for (c, (vd, vos)) in checks.iter().zip(&exact) {
            let d = c.sample.source;
            for ((o, meas), vo) in c.out.iter().zip(vos) {
                for (b, &light) in meas.iter().enumerate().take(bands) {
                    let want = first_scattering(alone, d, *o, b, |p| vd[p], |p| vo[p]);
                    let got = table.intensity(d, *o, b);
                    // Relative to the whole light measured there, as the intensity's error.
                    let mean = mean_intensity(&c.sample, b);
                    worst = worst.max(intensity_error(got + light - want, light, mean));
                }
            }
        }
        tried.push((side, worst));
        progress(
            &format!("{what}: {:.1}% off", 100.0 * worst),
            grid.cells() as u64,
            grid.cells() as u64,
        );
        if worst <= settings.single_target || side * 2 > settings.max_single_side || !fits(side * 2)
        {
            return Ok(Some(Single {
                scatterers: Scatterers {
                    grid,
                    polygons: n,
                    shape,
                    visible,
                    tried,
                },
                sun_seen: exact.into_iter().map(|(vd, _)| vd).collect(),
            }));
        }
        side *= 2;
    }
}
