//! The light an original sends towards one direction, as an observer outside its box sees
//! it: parallel rays from the observer's side across the box's projection, each reading the
//! radiance of the first surface it meets (paper section 3.1: the phase function is measured
//! on the light that leaves the box). Light that crosses the box uncollided is not in it
//! (that is `tau`): this is the scattered light alone.

use super::tau::parallel_rays;
use crate::limits::{MAX_BANDS, NONE};
use crate::visibility::Visibility;
use glam::Vec3;

/// One measurement of the light leaving a box towards a direction.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Outgoing {
    /// Radiant intensity towards the direction per band (W/sr), for the radiances the caller
    /// gave: the radiance of each surface seen, integrated over the box's projection.
    pub intensity: [f32; MAX_BANDS],
    /// Rays that crossed the box.
    pub rays: u32,
    /// Of them, the rays that met a surface.
    pub hits: u32,
}

/// The light leaving the box `[lo, hi]` towards the unit direction `towards`, from a
/// stratified `g x g` grid of parallel rays (jittered by `seed`) that come from that side.
/// `radiance(polygon, towards, out)` writes the radiance (W/m^2/sr per band, first `bands`
/// entries) that the polygon `vis` names sends towards `towards` from the side facing it.
pub fn outgoing<V, R>(
    vis: &V,
    lo: Vec3,
    hi: Vec3,
    towards: Vec3,
    g: u32,
    seed: u32,
    bands: usize,
    mut radiance: R,
) -> Outgoing
where
    V: Visibility + ?Sized,
    R: FnMut(u32, Vec3, &mut [f32; MAX_BANDS]),
{
    let towards = towards.normalize_or_zero();
    let bands = bands.min(MAX_BANDS);
    let mut sum = [0.0f64; MAX_BANDS];
    let mut hits = 0u32;
    let mut l = [0.0f32; MAX_BANDS];
    // The rays travel from the observer into the box: along -towards.
    let (rays, cell) = parallel_rays(lo, hi, -towards, g, seed, |from, to| {
        if let Some((poly, _)) = vis.first_hit(from, to, [NONE, NONE]) {
            hits += 1;
            l = [0.0; MAX_BANDS];
            radiance(poly, towards, &mut l);
            for (s, v) in sum.iter_mut().zip(&l).take(bands) {
                *s += *v as f64;
            }
        }
    });
    let mut intensity = [0.0f32; MAX_BANDS];
    for (i, s) in intensity.iter_mut().zip(&sum).take(bands) {
        *i = (*s * cell as f64) as f32;
    }
    Outgoing {
        intensity,
        rays,
        hits,
    }
}
