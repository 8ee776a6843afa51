//! Closure: in a closed part of a scene, what a leaf's links bring must add up to exactly all
//! the light around it.
//!
//! From any point inside a closed room every direction ends on a surface, so its form
//! factors to the scene sum to 1. The links a leaf receives (its own, its ancestor patches',
//! its clusters') cover the scene once, but their coefficients are estimates: evaluated at a
//! parent's quadrature points, through an emitting cluster's kernel, with visibility from a
//! few rays. Their sum is 1 only on average, and in a closed scene with rho = 0.99 a sum of
//! 1.01 somewhere is enough to diverge, 0.99 to lose a third of the light. So after every
//! refinement round, when no ray from any patch leaves the scene (see `direct`), each leaf
//! side measures its sum (one gather with every emitting side at radiosity 1) and divides
//! what its links bring by it. In a scene that light can leave, the sums are not known (a
//! few rays per patch cannot tell which see a little of the outside and how much), errors
//! are not amplified by endless reflection, and coefficients stay as they are.

use super::exec::{Executor, Fallback, run_chunks};
use super::ids::{Elem, Kind};
use super::layout::CHUNK;
use super::state::State;
use crate::limits::NONE;

struct Ctx<'a> {
    st: &'a mut State,
    ws: &'a mut [u8],
}

/// Recomputes every leaf's closure factors (per side).
pub(crate) fn update<E: Executor>(
    st: &mut State,
    ws: &mut [u8],
    ex: &mut Fallback<'_, E>,
    progress: &mut dyn super::exec::Progress,
) {
    // Light leaves the scene somewhere: every factor stays 1.
    if !st.closed {
        return;
    }
    progress.report("closing (patches)", 0, 0);
    super::bins::update(st, ws, true);
    super::solve::gather(st, ws, ex, true, true);
    super::bins::update(st, ws, false);
    super::solve::push(st, ws);
    // Both pools under one phase: the count runs on over them.
    let all = st.pool(Kind::Patch1).len as u64 + st.pool(Kind::Patch2).len as u64;
    let mut offset = 0u64;
    for kind in [Kind::Patch1, Kind::Patch2] {
        let n = st.pool(kind).len as usize;
        let mut ctx = Ctx {
            st: &mut *st,
            ws: &mut *ws,
        };
        run_chunks(
            ex,
            &mut ctx,
            n.div_ceil(CHUNK),
            CHUNK * 2,
            |c: &Ctx<'_>, chunk, buf| {
                for (slot, i) in (chunk * CHUNK..((chunk + 1) * CHUNK).min(n)).enumerate() {
                    let e = Elem::new(kind, i as u32);
                    let p = c.st.patch(c.ws, e);
                    // Stored as the factor's departure from 1, which f32 holds far more
                    // finely than the factor itself (with rho = 0.9999 a rounding of 6e-8
                    // would be amplified 10,000 times).
                    let mut f = [0.0f32; 2];
                    if p.first_child == NONE {
                        for (side, fs) in f.iter_mut().enumerate().take(State::sides(e)) {
                            let sum = c.st.h(c.ws, e, side)[0] as f64
                                + c.st.polygon_h(c.ws, p.poly, side)[0] as f64;
                            if sum > 0.0 && sum.is_finite() {
                                *fs = ((1.0 - sum) / sum) as f32;
                            }
                        }
                    }
                    buf[2 * slot..2 * slot + 2].copy_from_slice(&f);
                }
            },
            |c: &mut Ctx<'_>, chunk, buf| {
                for (slot, i) in (chunk * CHUNK..((chunk + 1) * CHUNK).min(n)).enumerate() {
                    let e = Elem::new(kind, i as u32);
                    let mut p = c.st.patch(c.ws, e);
                    let f = [buf[2 * slot], buf[2 * slot + 1]];
                    if p.closure != f {
                        p.closure = f;
                        c.st.set_patch(c.ws, e, &p);
                    }
                }
            },
            &mut |done, total| {
                progress.report(
                    "closing (patches)",
                    offset + (done * CHUNK).min(n) as u64,
                    all.max(offset + (total * CHUNK).min(n) as u64),
                )
            },
        );
        offset += n as u64;
    }
}

/// The irradiance of a leaf patch's side (W/m^2 per band): what it gathered and inherited
/// from ancestor patches plus its polygon's share of what its clusters receive (by the
/// polygon's own cosine, see `oriented`), scaled by its closure factor, plus the direct
/// light of suns and sky, plus the final gather's correction (see `relight::relight`).
pub(crate) fn leaf_irradiance(st: &State, ws: &[u8], e: Elem, side: usize, out: &mut [f32]) {
    let p = st.patch(ws, e);
    let c = p.closure[side.min(1)];
    for ((o, h), hc) in out
        .iter_mut()
        .zip(st.h(ws, e, side))
        .zip(st.polygon_h(ws, p.poly, side))
    {
        *o = ((1.0 + c as f64) * (*h as f64 + *hc as f64)) as f32;
    }
    if let Some(d) = st.direct(ws, e, side) {
        for (o, v) in out.iter_mut().zip(d) {
            *o += v;
        }
    }
    if let Some(d) = st.correction(ws, e, side) {
        for (o, v) in out.iter_mut().zip(d) {
            *o += v;
        }
    }
}
