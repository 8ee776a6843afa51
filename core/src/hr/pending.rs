//! Evaluating the links that wait for their coefficients: those made since the last
//! evaluation (they lie in one range of the link pool), computed in fixed chunks, possibly
//! on many threads, and applied in order, so the results never depend on the thread count.

use super::eval::evaluate;
use super::exec::{Executor, Fallback, Progress, run_chunks_scaled};
use super::ids::Elem;
use super::layout::{CHUNK, FINE_CHUNK};
use super::records::*;
use super::state::State;
use super::vis::{Ray, Vis, WsPolygons};
use crate::visibility::Visibility;

/// Context of a chunked phase: the state, the workspace, the visibility.
struct Ctx<'a, 'v, V: ?Sized> {
    st: &'a mut State,
    ws: &'a mut [u8],
    vis: &'a Vis<'v, V>,
}

/// Computes the coefficients of every pending link.
pub(crate) fn evaluate_pending<V: Visibility + ?Sized, E: Executor>(
    st: &mut State,
    ws: &mut [u8],
    vis: &Vis<'_, V>,
    ex: &mut Fallback<'_, E>,
    progress: &mut dyn Progress,
) {
    // Only the range where links were added since the last evaluation.
    let (first, n) = (
        st.pending.0 as usize,
        (st.pending.1 as usize).min(st.links.len as usize),
    );
    st.pending = (u32::MAX, 0);
    let pending = core::mem::take(&mut st.pending_links);
    if first >= n {
        return;
    }
    let count = n - first;
    // Progress counts the links evaluated, not the slots of the range looked at.
    let evaluated = core::cell::Cell::new(0u64);
    let out = st.lay.strides.eval_out();
    let kk = st.lay.strides.link_k;
    let items =
        move |chunk: usize| first + chunk * FINE_CHUNK..(first + (chunk + 1) * FINE_CHUNK).min(n);
    let mut ctx = Ctx { st, ws, vis };
    run_chunks_scaled(
        ex,
        &mut ctx,
        count.div_ceil(FINE_CHUNK),
        CHUNK / FINE_CHUNK,
        FINE_CHUNK * out,
        |c: &Ctx<'_, '_, V>, chunk, buf| {
            let ray = Ray {
                vis: c.vis,
                polys: WsPolygons { st: c.st, ws: c.ws },
            };
            for (slot, i) in items(chunk).enumerate() {
                let l = c.st.link(c.ws, i as u32);
                let o = &mut buf[slot * out..(slot + 1) * out];
                if l.flags & (PENDING | FREE) != PENDING {
                    // Nothing to apply: the (sequential) apply skips it unread.
                    o[kk + 2] = -1.0;
                    continue;
                }
                let co = evaluate(c.st, c.ws, Elem(l.recv), Elem(l.emit), &ray);
                if kk == 1 {
                    o[0] = co.k[0][0];
                } else {
                    o[..4].copy_from_slice(&[co.k[0][0], co.k[0][1], co.k[1][0], co.k[1][1]]);
                }
                o[kk] = co.open;
                o[kk + 1] = if co.partial { 1.0 } else { 0.0 };
                o[kk + 2] = co.rays as f32;
                o[kk + 3..kk + 6].copy_from_slice(&co.dir.to_array());
                o[kk + 6] = co.spread;
                o[kk + 7] = if co.exact { 1.0 } else { 0.0 };
                o[kk + 8] = co.seen;
                o[kk + 9] = f32::from_bits(co.witness[0]);
                o[kk + 10] = f32::from_bits(co.witness[1]);
            }
        },
        |c: &mut Ctx<'_, '_, V>, chunk, buf| {
            for (slot, i) in items(chunk).enumerate() {
                let o = &buf[slot * out..(slot + 1) * out];
                if o[kk + 2] < 0.0 {
                    continue;
                }
                let mut l = c.st.link(c.ws, i as u32);
                c.st.link_k_mut(c.ws, i as u32).copy_from_slice(&o[..kk]);
                l.k_open = o[kk];
                l.dir = [o[kk + 3], o[kk + 4], o[kk + 5]];
                l.spread = o[kk + 6];
                l.k_seen = o[kk + 8];
                l.witness = [o[kk + 9].to_bits(), o[kk + 10].to_bits()];
                l.flags = (l.flags & !(PENDING | EXACT))
                    | if o[kk + 1] != 0.0 { PARTIAL } else { 0 }
                    | if o[kk + 7] != 0.0 { EXACT } else { 0 };
                c.st.set_link(c.ws, i as u32, &l);
                c.st.stats.evaluations += 1;
                c.st.stats.rays += o[kk + 2] as u64;
                c.st.stats.rays_by_phase.links += o[kk + 2] as u64;
                evaluated.set(evaluated.get() + 1);
            }
        },
        &mut |_, _| progress.report("evaluating links", evaluated.get(), pending.max(1)),
    );
}
