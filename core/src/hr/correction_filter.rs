//! The relighting's corrections kept where enough rays sampled them, shrunk towards their
//! parent's where few did.
//!
//! A leaf patch's correction (what it gathered less what its links bring, see
//! `relight::relight`) comes from its share of its polygon's rays: a leaf of a finely
//! refined floor casts one ray or a few, so its correction is mostly noise, and the picture
//! and every ray that reads the leaf showed it as a checkerboard of light and dark tiles
//! (the floor between the Cornell box's tall block and the red wall, at 1e-3 and 1e-4
//! alike, however many rays the polygon cast in all). Going down a polygon's quadtree, each
//! child keeps `n / (n + MIN_RAYS)` of its departure from its siblings' mean, `n` the rays
//! its share of the polygon's stood on: a correction from many rays stays, one from a ray
//! or two follows its parent's. Siblings are shrunk alike around their exposed-area mean,
//! so a polygon's corrected power is unchanged (unless a leaf's light would go negative: it
//! stops at zero).
//!
//! Measured on 2026-12-04 (`hirad solve SCENE --image H.exr --size 400x400
//! --reference-image E.exr` against `--method exact`): Cornell box 0.884% -> 0.822% at the
//! defaults, 0.386% at `--epsilon 1e-4` (speckled before); the OBJ Cornell room 0.831% ->
//! 0.895%. `MIN_RAYS` 16 left mottling at 1e-4 (0.799%, 0.390%, 0.865%), 64 blurred
//! more (0.852%, 0.392%, 0.936%).

use super::gather_rays::polygon_rays;
use super::ids::{Elem, Kind};
use super::state::State;
use crate::limits::NONE;

/// The ray count at which a child keeps half its departure from its siblings' mean.
pub(crate) const MIN_RAYS: f32 = 32.0;

/// Shrinks every leaf side's correction towards its ancestors' as described above, from
/// the `rays` per side (before a polygon's boost) that the pass cast. Uses the interior
/// patches' correction slots (unused otherwise) for the means and leaves them zero. Does
/// nothing without corrections.
pub(crate) fn filter_corrections(st: &State, ws: &mut [u8], rays: u32) {
    if st.correction == NONE as usize {
        return;
    }
    let nb = st.bands;
    for kind in [Kind::Patch1, Kind::Patch2] {
        let len = st.pool(kind).len;
        let sides = if kind == Kind::Patch2 { 2 } else { 1 };
        // Children come after their parents in a pool: the means bottom-up ...
        for i in (0..len).rev() {
            let e = Elem::new(kind, i);
            let p = st.patch(ws, e);
            if p.first_child == NONE {
                continue;
            }
            for side in 0..sides {
                let m = children_mean(st, ws, kind, p.first_child, side);
                if let Some(c) = st.correction_mut(ws, e, side) {
                    for (v, m) in c.iter_mut().zip(m) {
                        *v = m as f32;
                    }
                }
            }
        }
        // ... and handed down: each child's departure from its siblings' mean shrunk by
        // how few rays it stands on (parents come before their children).
        for i in 0..len {
            let e = Elem::new(kind, i);
            let p = st.patch(ws, e);
            if p.first_child == NONE {
                continue;
            }
            let total = st.patch(ws, Elem(st.polygon(ws, p.poly).root)).area;
            let per_area = if total > 0.0 {
                polygon_rays(st, rays, total) as f32 / total
            } else {
                0.0
            };
            let smallest = (0..4)
                .map(|j| st.patch(ws, Elem::new(kind, p.first_child + j)).area)
                .fold(f32::INFINITY, f32::min);
            let n = smallest * per_area;
            let keep = n / (n + MIN_RAYS);
            for side in 0..sides {
                let mut value = [0.0f32; 8];
                if let Some(c) = st.correction(ws, e, side) {
                    value[..nb].copy_from_slice(c);
                }
                let mean = children_mean(st, ws, kind, p.first_child, side);
                for j in 0..4 {
                    let child = Elem::new(kind, p.first_child + j);
                    // A leaf's irradiance without its correction: what the shrunk
                    // correction may take away at most (light is never negative).
                    let mut base = [f32::INFINITY; 8];
                    if st.patch(ws, child).first_child == NONE {
                        super::closure::leaf_irradiance(st, ws, child, side, &mut base[..nb]);
                        if let Some(c) = st.correction(ws, child, side) {
                            for (v, c) in base.iter_mut().zip(c) {
                                *v -= c;
                            }
                        }
                    }
                    if let Some(c) = st.correction_mut(ws, child, side) {
                        for b in 0..nb {
                            let own = c[b] as f64 - mean[b];
                            c[b] = (value[b] + (keep as f64 * own) as f32).max(-base[b]);
                        }
                    }
                }
            }
        }
        // The interior slots back to zero: only leaves' corrections are read.
        for i in 0..len {
            let e = Elem::new(kind, i);
            if st.patch(ws, e).first_child == NONE {
                continue;
            }
            for side in 0..sides {
                if let Some(c) = st.correction_mut(ws, e, side) {
                    c.fill(0.0);
                }
            }
        }
    }
}

/// The mean correction (per band) of side `side` over the 4 children from `first` of a
/// patch in pool `kind`, weighted by exposed area (by plain area where all are buried).
fn children_mean(st: &State, ws: &[u8], kind: Kind, first: u32, side: usize) -> [f64; 8] {
    let (mut seen, mut area) = (0.0f64, 0.0f64);
    let (mut sum, mut plain) = ([0.0f64; 8], [0.0f64; 8]);
    for j in 0..4 {
        let child = Elem::new(kind, first + j);
        let cp = st.patch(ws, child);
        let (a, w) = (cp.area as f64, (cp.area * cp.exposed) as f64);
        area += a;
        seen += w;
        if let Some(c) = st.correction(ws, child, side) {
            for (b, v) in c.iter().enumerate() {
                sum[b] += w * *v as f64;
                plain[b] += a * *v as f64;
            }
        }
    }
    let (sum, total) = if seen > 0.0 {
        (sum, seen)
    } else {
        (plain, area)
    };
    let mut mean = [0.0f64; 8];
    if total > 0.0 {
        for (m, s) in mean.iter_mut().zip(sum) {
            *m = s / total;
        }
    }
    mean
}
