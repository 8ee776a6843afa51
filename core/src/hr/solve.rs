//! Solving with the current links: gather, push, pull, until the radiosities settle.
//!
//! * gather: each receiver sums, over the links it receives, coefficient x emitter radiosity
//!   (in chunks that any number of threads may compute);
//! * push: irradiance flows down: a cluster's flux density passes to child clusters and,
//!   spread isotropically, a quarter of it to each side of child patches; a patch's
//!   irradiance passes to its sub-patches;
//! * pull: leaf radiosities come from the materials (`B = E + rho H + tau H_other`), parents
//!   take area-weighted means, clusters the power of their surfaces over their area.
//!
//! Convergence is judged by the estimated remaining change (last change x q / (1 - q), with q
//! the ratio of successive changes), so a closed scene with rho = 0.99 is not stopped early.

use super::exec::{Executor, Fallback, Progress, run_chunks};
use super::ids::{Elem, Kind};
use super::layout::CHUNK;
use super::state::State;
use crate::limits::NONE;

struct Ctx<'a> {
    st: &'a mut State,
    ws: &'a mut [u8],
}

/// Iterates to convergence; returns the iterations run.
pub(crate) fn iterate<E: Executor, P: Progress>(
    st: &mut State,
    ws: &mut [u8],
    ex: &mut Fallback<'_, E>,
    progress: &mut P,
) -> u32 {
    let mut last = f32::INFINITY;
    let mut iterations = 0;
    st.stats.iteration_capped = false;
    for it in 0..st.settings.max_iterations.max(1) {
        gather(st, ws, ex);
        push(st, ws);
        let (change, b_max) = pull(st, ws);
        iterations = it + 1;
        st.stats.iterations += 1;
        progress.report("solving (iterations)", it as u64 + 1, 0);
        let scale = b_max.max(f32::MIN_POSITIVE);
        if change <= st.settings.tolerance * scale * 1e-3 {
            return iterations;
        }
        if it > 0 && last.is_finite() && last > 0.0 {
            let q = (change / last).min(0.999_999);
            let remaining = change * q / (1.0 - q);
            if q < 1.0
                && remaining <= st.settings.tolerance * scale
                && change <= st.settings.tolerance * scale
            {
                return iterations;
            }
        }
        last = change;
    }
    st.stats.iteration_capped = true;
    iterations
}

/// Every receiver's gathered irradiance.
fn gather<E: Executor>(st: &mut State, ws: &mut [u8], ex: &mut Fallback<'_, E>) {
    let n = st.receiver_count() as usize;
    let nb = st.bands;
    let out = st.lay.strides.gather_out();
    let kk = st.lay.strides.link_k;
    let mut ctx = Ctx { st, ws };
    run_chunks(
        ex,
        &mut ctx,
        n.div_ceil(CHUNK),
        CHUNK * out,
        |c: &Ctx<'_>, chunk, buf| {
            buf.fill(0.0);
            for (slot, i) in (chunk * CHUNK..((chunk + 1) * CHUNK).min(n)).enumerate() {
                let recv = c.st.receiver(i as u64);
                let h = &mut buf[slot * out..(slot + 1) * out];
                let mut cur = c.st.links_head(c.ws, recv);
                while cur != NONE {
                    let l = c.st.link(c.ws, cur);
                    let k = c.st.link_k(c.ws, cur);
                    let emit = Elem(l.emit);
                    if l.recv != l.emit {
                        for s in 0..kk.min(2) {
                            let Some(b) = c.st.b(c.ws, emit, s) else {
                                continue;
                            };
                            for r in 0..if kk == 1 { 1 } else { 2 } {
                                let coef = if kk == 1 { k[0] } else { k[r * 2 + s] };
                                if coef != 0.0 {
                                    for (hb, bb) in h[r * nb..(r + 1) * nb].iter_mut().zip(b) {
                                        *hb += coef * bb;
                                    }
                                }
                            }
                        }
                    }
                    cur = l.next;
                }
            }
        },
        |c: &mut Ctx<'_>, chunk, buf| {
            for (slot, i) in (chunk * CHUNK..((chunk + 1) * CHUNK).min(n)).enumerate() {
                let recv = c.st.receiver(i as u64);
                for side in 0..State::sides(recv) {
                    let src = &buf[slot * out + side * nb..slot * out + (side + 1) * nb];
                    c.st.h_mut(c.ws, recv, side).copy_from_slice(src);
                }
            }
        },
        &mut |_, _| {},
    );
}

/// Irradiance down the hierarchy (parents are numbered before their children).
fn push(st: &State, ws: &mut [u8]) {
    let nb = st.bands;
    let mut tmp = [0.0f32; 8];
    for i in 1..st.clusters {
        let e = Elem::new(Kind::Cluster, i);
        let parent = st.cluster(ws, i).parent;
        tmp[..nb].copy_from_slice(st.h(ws, Elem::new(Kind::Cluster, parent), 0));
        for (h, p) in st.h_mut(ws, e, 0).iter_mut().zip(&tmp[..nb]) {
            *h += p;
        }
    }
    for kind in [Kind::Patch1, Kind::Patch2] {
        let len = st.pool(kind).len;
        for i in 0..len {
            let e = Elem::new(kind, i);
            let parent = Elem(st.patch(ws, e).parent);
            // A polygon's cluster part is added at the leaves (see `leaf_irradiance`).
            if parent.kind() == Kind::Cluster {
                continue;
            }
            for side in 0..State::sides(e) {
                tmp[..nb].copy_from_slice(st.h(ws, parent, side));
                for (h, p) in st.h_mut(ws, e, side).iter_mut().zip(&tmp[..nb]) {
                    *h += p;
                }
            }
        }
    }
}

/// Radiosity up the hierarchy; returns the largest change of a leaf radiosity and the
/// largest radiosity (W/m^2).
fn pull(st: &State, ws: &mut [u8]) -> (f32, f32) {
    let nb = st.bands;
    let (mut change, mut b_max) = (0.0f32, 0.0f32);
    for kind in [Kind::Patch2, Kind::Patch1] {
        let len = st.pool(kind).len;
        for i in (0..len).rev() {
            let e = Elem::new(kind, i);
            let p = st.patch(ws, e);
            let sides = State::sides(e);
            let mut new = [[0.0f32; 8]; 2];
            if p.first_child == NONE {
                let m = st.material(ws, st.polygon(ws, p.poly).material);
                let mut h = [[0.0f32; 8]; 2];
                for (side, hs) in h.iter_mut().enumerate().take(sides) {
                    super::closure::leaf_irradiance(st, ws, e, side, &mut hs[..nb]);
                }
                for side in 0..sides {
                    for b in 0..nb {
                        let other = if sides == 2 { h[1 - side][b] } else { 0.0 };
                        new[side][b] =
                            m.emit[side][b] + m.rho[side][b] * h[side][b] + m.tau[b] * other;
                    }
                }
            } else {
                let mut area = 0.0f32;
                for j in 0..4 {
                    let child = Elem::new(kind, p.first_child + j);
                    let a = st.patch(ws, child).area;
                    area += a;
                    for (side, ns) in new.iter_mut().enumerate().take(sides) {
                        if let Some(b) = st.b(ws, child, side) {
                            for (n, v) in ns.iter_mut().zip(b) {
                                *n += a * v;
                            }
                        }
                    }
                }
                let inv = if area > 0.0 { 1.0 / area } else { 0.0 };
                for ns in new.iter_mut().take(sides) {
                    for n in ns[..nb].iter_mut() {
                        *n *= inv;
                    }
                }
            }
            for (side, ns) in new.iter().enumerate().take(sides) {
                let b = st.b_mut(ws, e, side);
                for (old, n) in b.iter_mut().zip(&ns[..nb]) {
                    if p.first_child == NONE {
                        change = change.max((n - *old).abs());
                    }
                    b_max = b_max.max(*n);
                    *old = *n;
                }
            }
        }
    }
    for i in (0..st.clusters).rev() {
        let c = st.cluster(ws, i);
        let mut power = [0.0f32; 8];
        for k in 0..c.child_count {
            let child = st.child(ws, c.children + k);
            let area = super::sample::area(st, ws, child);
            for side in 0..State::sides(child) {
                if let Some(b) = st.b(ws, child, side) {
                    for (p, v) in power.iter_mut().zip(b) {
                        *p += area * v;
                    }
                }
            }
        }
        let inv = if c.area > 0.0 { 1.0 / c.area } else { 0.0 };
        let b = st.b_mut(ws, Elem::new(Kind::Cluster, i), 0);
        for (d, p) in b.iter_mut().zip(&power[..nb]) {
            *d = p * inv;
        }
    }
    (change, b_max)
}
