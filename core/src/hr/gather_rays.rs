//! How many rays the final gather casts from each receiving side: the setting or an
//! automatic budget, times what the side's light needs (the share of it that the
//! hierarchy's links bring, noted before the first pass so that no pass draws its counts
//! from the gather's own samples).

use super::ids::{Elem, Kind};
use super::state::State;
use crate::limits::NONE;

/// Rays for the whole scene when the count per side is chosen automatically, at epsilon
/// 1e-3 (it grows as 1 / epsilon: a finer solution asks for less noise).
const AUTO_BUDGET: f64 = 1_048_576.0;
/// Most rays per receiving side when chosen automatically, at epsilon 1e-5 (again as
/// 1 / epsilon, at most [`AUTO_MAX`]), and the fewest.
const AUTO_CAP: f64 = 65_536.0;
const AUTO_MAX: u32 = 262_144;
const AUTO_MIN: u32 = 64;

/// Rays per receiving side: the setting, or (for [`super::settings::Settings::AUTO`]) a budget of
/// [`AUTO_BUDGET`] x (1e-3 / epsilon) rays spread over all receiving sides, at least
/// [`AUTO_MIN`] and at most [`AUTO_CAP`] x (1e-5 / epsilon) per side. Rounded to a square
/// (points and directions are both stratified on a grid).
pub(crate) fn rays_per_side(st: &State, ws: &[u8]) -> u32 {
    let asked = st.settings.final_rays;
    if asked == 0 {
        return 0;
    }
    let n = if asked == super::settings::Settings::AUTO {
        let mut sides = st.scene_sides;
        if sides == 0 {
            for i in 0..st.polygons {
                sides += State::sides(Elem(st.polygon(ws, i).root)) as u64;
            }
        }
        let eps = st.settings.epsilon as f64;
        let budget = AUTO_BUDGET * (1e-3 / eps);
        let cap = (AUTO_CAP * (1e-5 / eps)).clamp(AUTO_MIN as f64, AUTO_MAX as f64);
        (budget / sides.max(1) as f64).clamp(AUTO_MIN as f64, cap) as u32
    } else {
        asked
    };
    let g = libm::roundf(libm::sqrtf(n as f32)).max(1.0) as u32;
    g * g
}

/// Rays per receiving side of a polygon of `area` (m^2), out of `full` for one of the scene's
/// typical size: `full x sqrt(area / typical)`, between 1 and [`LARGE_BOOST`] times `full`.
/// The noise a side leaves on the scene's power is its relative noise times its area, so
/// the few large polygons of a room (walls and floor, far larger than its chairs' polygons)
/// set the noise of its balance and of its picture: at 64 rays each, the passes of a small
/// room's gather moved its light by 1% to 3% apiece, none settling.
pub(crate) fn polygon_rays(st: &State, full: u32, area: f32) -> u32 {
    let typical = st.typical_area;
    if !(typical > 0.0 && area > typical) {
        return full;
    }
    let boost = libm::sqrtf(area / typical).min(LARGE_BOOST);
    (full as f32 * boost).min(super::settings::Settings::MAX_FINAL_RAYS as f32) as u32
}

/// Most times the rays of a polygon of typical size that a large polygon casts per side.
const LARGE_BOOST: f32 = 16.0;

/// The share of a receiving side's light that the gather recomputes: what the hierarchy's
/// links bring it over all it gets, links and the direct light of suns and sky, the largest
/// over bands, for leaf patches `leaves` of one polygon (their exposed-area mean). 0 when
/// the links bring nothing: then no surface the side can see reflects or emits. Read as
/// noted before the gather began ([`note_shares`]) where it was: a pass of the gather
/// replaces the links' light by its own estimate, and a count drawn from that estimate
/// would follow its noise (a side whose few rays all escaped in one pass got none in the
/// next, and kept its zero: a 2 x 3 maize canopy lost 1.0% to 1.5% of its NIR that way).
pub(crate) fn gathered_share(
    st: &State,
    ws: &[u8],
    leaves: impl Iterator<Item = Elem>,
    side: usize,
) -> f32 {
    let (mut sum, mut area) = (0.0f64, 0.0f64);
    for e in leaves {
        let p = st.patch(ws, e);
        let a = (p.area * p.exposed) as f64;
        let s = match p.gather[side.min(1)] {
            0 => live_share(st, ws, e, side),
            q => (q - 1) as f32 / SHARE_STEPS,
        };
        sum += a * s as f64;
        area += a;
    }
    if area > 0.0 {
        (sum / area).clamp(0.0, 1.0) as f32
    } else {
        0.0
    }
}

/// Steps of a noted share (see `Patch::gather`).
const SHARE_STEPS: f32 = 65_534.0;

/// A leaf patch side's share (see [`gathered_share`]) from its irradiance as it stands.
fn live_share(st: &State, ws: &[u8], e: Elem, side: usize) -> f32 {
    let nb = st.bands;
    let mut h = [0.0f32; 8];
    super::closure::leaf_irradiance(st, ws, e, side, &mut h[..nb]);
    let d = st.direct(ws, e, side);
    // The part of the direct light that came through the links of the levels around (an
    // opened instance's level) is gathered again: it counts as the links' (counted as direct,
    // the lamps around an opened chair left its polygons a thirteenth of hr's rays).
    let linked = st.linked(ws, e, side);
    let mut share = 0.0f32;
    for k in 0..nb {
        let dk = d.map_or(0.0, |d| d[k]) - linked.map_or(0.0, |l| l[k]);
        let all = h[k].max(dk);
        if all > 0.0 {
            share = share.max((h[k] - dk).max(0.0) / all);
        }
    }
    share.clamp(0.0, 1.0)
}

/// Notes every leaf patch's share (see [`gathered_share`]) from the hierarchy's solution,
/// before any pass of the gather replaces its links' light. A share that is not 0 is noted
/// as at least one step, so that a side that gathers anything keeps gathering.
pub(crate) fn note_shares(st: &State, ws: &mut [u8]) {
    for kind in [Kind::Patch1, Kind::Patch2] {
        for i in 0..st.pool(kind).len {
            let e = Elem::new(kind, i);
            let mut p = st.patch(ws, e);
            if p.first_child != NONE {
                continue;
            }
            for side in 0..State::sides(e) {
                let s = live_share(st, ws, e, side);
                let q = if s > 0.0 {
                    libm::ceilf(s * SHARE_STEPS).clamp(1.0, SHARE_STEPS)
                } else {
                    0.0
                };
                p.gather[side] = 1 + q as u16;
            }
            st.set_patch(ws, e, &p);
        }
    }
}

/// Rays for a receiving side of which the gather recomputes the share `share` of the light
/// (see [`gathered_share`]), out of `full` for a side it recomputes wholly: `full x
/// sqrt(share)`. The gather's noise on the side's total is its noise on that share times
/// the share, so `full x share^2` would keep every side's relative noise equal; the square
/// root spends more, because the share itself comes from the hierarchy's estimate (a law
/// linear in the share left a two-sided leaf inside a cluster 5% off, the square root 1.5%).
/// A sunlit leaf whose light is nine tenths sun still casts a third of the rays of a shaded
/// one. At least [`MIN_RAYS`] while anything is to be gathered, none when the links bring
/// nothing (a scene whose surfaces neither reflect nor emit). The count depends only on the
/// hierarchy's solution, never on the gather's own samples, so it biases nothing.
pub(crate) fn adaptive_rays(full: u32, share: f32) -> u32 {
    if full == 0 || share.is_nan() || share <= 0.0 {
        return 0;
    }
    let n = libm::ceilf(full as f32 * libm::sqrtf(share)) as u32;
    n.clamp(MIN_RAYS.min(full), full)
}

/// The fewest rays a receiving side that gathers anything casts.
const MIN_RAYS: u32 = 4;
