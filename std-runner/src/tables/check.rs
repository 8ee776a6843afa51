//! `hirad tables --check N`: a baked table's predictions at directions off its grids against
//! direct simulations of the expanded original under that sun: `tau` against 1,000 x 1,000
//! parallel rays, the scattered power against an hr solve, the outgoing intensity in a few
//! directions against the solve's surfaces, and the energy of each solve.

use super::OriginalTables;
use super::bake::{TableSettings, intensity_error, scattered_error, uniform_direction};
use super::original::Alone;
use super::sample::sample_at;
use crate::scene::Scene;
use crate::solve::RayonExecutor;
use anyhow::Result;
use glam::Vec3;
use hirad_core::sampling::hash3;
use hirad_core::tables::tau::tau;

/// Rays along each side of the reference `tau` (a million rays).
pub const TAU_RAYS: u32 = 1000;

/// Outgoing directions checked per incoming direction.
pub const OUT_DIRECTIONS: u32 = 8;

/// What the checks of one original found: the worst of each error.
#[derive(Clone, Copy, Debug, Default)]
pub struct CheckReport {
    /// Directions checked.
    pub directions: u32,
    /// Largest |interpolated tau - tau by a million rays|.
    pub tau: f32,
    /// Largest relative error of the scattered power (to the solve's, or to 1% of the
    /// power crossing the box when it is smaller), any band.
    pub scattered: f32,
    /// Largest error of the bidirectional intensity, relative to the solve's or, when that
    /// is darker, to its mean over all directions.
    pub intensity: f32,
    /// The same for the uniform form (the paper's).
    pub uniform_intensity: f32,
    /// The bidirectional form's error towards the sun itself (the hot spot, where the
    /// observer sees only lit surfaces: a peak narrower than the outgoing grid's cells),
    /// reported, not held to the target.
    pub hotspot: f32,
    /// Where the largest bidirectional error was: towards the sun and towards the observer
    /// (unit vectors, the original's frame).
    pub worst: (Vec3, Vec3),
    /// Largest |incoming - absorbed - scattered - uncollided| over incoming, any band.
    pub energy: f32,
}

/// Checks `t` (of original `t.index` of `scene`) at `n` directions drawn with `seed`.
pub fn check(
    scene: &Scene,
    t: &OriginalTables,
    n: u32,
    seed: u32,
    settings: &TableSettings,
    exec: &mut RayonExecutor,
    progress: &mut dyn FnMut(&str, u64, u64),
) -> Result<CheckReport> {
    let alone = Alone::new(scene, t.index)?;
    let view = t.view();
    let mut r = CheckReport {
        directions: n,
        ..CheckReport::default()
    };
    for k in 0..n {
        progress(&format!("{}: checks", t.name), k as u64, n as u64);
        let d = uniform_direction(seed, k, 0xC0DE);
        let exact = tau(
            &alone.vis,
            alone.lo,
            alone.hi,
            d,
            TAU_RAYS,
            hash3(seed, k, 0x7A),
        );
        r.tau = r.tau.max((view.tau(d) - exact.tau).abs());
        let s = sample_at(&alone, d, settings, exec)?;
        let outs: Vec<_> = (0..OUT_DIRECTIONS)
            .map(|m| {
                let o = uniform_direction(seed, k * 64 + m, 0x0B5E7);
                (
                    o,
                    s.intensity(&alone, o, settings.check_out_rays, hash3(seed, k, m))
                        .0,
                )
            })
            .collect();
        let (hot, _) = s.intensity(&alone, d, settings.check_out_rays, hash3(seed, k, 0x407));
        for b in 0..t.bands {
            let pred = view.scattered(d, b) / s.area;
            r.scattered = r.scattered.max(scattered_error(pred, s.scattered[b]));
            r.energy = r
                .energy
                .max((1.0 - s.tau - s.absorbed[b] - s.scattered[b]).abs());
            let mean = s.scattered[b] * s.area / (4.0 * std::f32::consts::PI);
            r.hotspot = r
                .hotspot
                .max(intensity_error(view.intensity(d, d, b), hot[b], mean));
            for (o, meas) in &outs {
                let e = intensity_error(view.intensity(d, *o, b), meas[b], mean);
                if e > r.intensity {
                    r.intensity = e;
                    r.worst = (d, *o);
                }
                r.uniform_intensity = r.uniform_intensity.max(intensity_error(
                    view.uniform_intensity(d, *o, b),
                    meas[b],
                    mean,
                ));
            }
        }
    }
    Ok(r)
}

impl CheckReport {
    /// True when every error is within `targets`' (the uniform form's is not held to one).
    pub fn within(&self, targets: &CheckReport) -> bool {
        self.tau <= targets.tau
            && self.scattered <= targets.scattered
            && self.intensity <= targets.intensity
            && self.energy <= targets.energy
    }
}
