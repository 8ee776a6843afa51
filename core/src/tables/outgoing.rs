//! The light an original sends towards one direction, as an observer outside its box sees
//! it (paper section 3.1: the phase function is measured on the light that leaves the box):
//! by parallel rays from the observer's side across the box's projection, each reading the
//! radiance of the first surface it meets, or from the surfaces, each seen to the extent
//! that rays from it towards the observer leave unblocked. Light that crosses the box
//! uncollided is not in it (that is `tau`): this is the scattered light alone.

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

/// The light leaving the box `[lo, hi]` (`bounds`) towards the unit direction `towards`, from a
/// stratified `g x g` grid of parallel rays (jittered by `seed`) that come from that side.
/// `radiance(polygon, towards, out)` writes the radiance (W/m^2/sr per band, first `bands`
/// entries) that the polygon `vis` names sends towards `towards` from the side facing it.
pub fn outgoing<V, R>(
    vis: &V,
    [lo, hi]: [Vec3; 2],
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

/// The fraction of the polygon `poly` (corners `corners`) from which a ray towards the unit
/// direction `towards` leaves the scene unblocked, from a stratified `k x k` set of points on
/// it (jittered by `seed`); `reach` (m) must take the rays past every polygon. With it, the
/// light leaving a box towards a direction is a sum over its polygons, radiance x area x
/// |cosine| x this fraction, with noise only in the fraction (rays from an observer read
/// each surface's radiance at random, and in a sparse crown few of them meet anything).
pub fn visible_fraction<V: Visibility + ?Sized>(
    vis: &V,
    corners: &[Vec3],
    poly: u32,
    towards: Vec3,
    reach: f32,
    k: u32,
    seed: u32,
) -> f32 {
    if k == 0 || (corners.len() != 3 && corners.len() != 4) {
        return 0.0;
    }
    let mut clear = 0u32;
    for j in 0..k {
        for i in 0..k {
            let (ju, jv) = crate::sampling::unit2(crate::sampling::hash3(seed, poly, j * k + i));
            let p = crate::sampling::point_on(
                corners,
                (i as f32 + ju) / k as f32,
                (j as f32 + jv) / k as f32,
            );
            if vis.transmittance(p, p + towards * reach, [poly, NONE]) > 0.5 {
                clear += 1;
            }
        }
    }
    clear as f32 / (k * k) as f32
}
