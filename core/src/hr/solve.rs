//! Solving with the current links: gather, push, pull, until the radiosities settle.
//!
//! * gather: each receiver sums, over the links it receives, coefficient x emitter radiosity
//!   (in chunks that any number of threads may compute);
//!   a link received by a cluster gives each polygon below it its share by the polygon's own
//!   cosine (see `oriented`);
//! * push: a patch's gathered irradiance passes to its sub-patches;
//! * pull: leaf radiosities come from the materials (`B = E + rho H + tau H_other`, H with
//!   the direct light of suns and sky), parents take means weighted by exposed area,
//!   clusters the power of their surfaces over their area.
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
///
/// The change of the largest leaf radiosity shrinks by about the same ratio q every
/// iteration once the slowest mode dominates; the change still to come is then
/// `change * q / (1 - q)`. q is taken as the largest ratio of the last [`WINDOW`] iterations
/// (a single ratio is often optimistic while faster modes die out), and the solution stops
/// when that estimate, and the last change itself, are below the tolerance of the largest
/// radiosity. At the iteration cap the solution is reported as not converged with its
/// estimate.
///
/// Where reflection goes on for long (q near 1: rooms of white walls, a furnace with
/// rho = 0.9999) and q has settled, one iteration is extrapolated: every leaf moves by its
/// change times `q / (1 - q)`, the sum of the geometric tail (Aitken's extrapolation of the
/// slowest mode). The faster modes that this misjudges die out in the iterations after it.
pub(crate) fn iterate<E: Executor, P: Progress>(
    st: &mut State,
    ws: &mut [u8],
    ex: &mut Fallback<'_, E>,
    progress: &mut P,
    tolerance: f32,
) -> u32 {
    let mut ratios = [0.0f32; WINDOW];
    let mut changes = [0.0f32; WINDOW];
    let mut last = f32::INFINITY;
    let mut iterations = 0;
    let mut remaining = f32::INFINITY;
    let mut extrapolate = 0.0f32;
    let mut settled = 0usize;
    let mut last_scale = 0.0f32;
    // The contraction of the previous solution (the same operator, refined): a warm start
    // may begin right at the answer, where rounding hides it.
    let mut q_known = st.contraction;
    let q_before = st.contraction;
    st.stats.iteration_capped = false;
    st.stats.converged = false;
    for it in 0..st.settings.max_iterations.max(1) {
        if progress.cancelled() {
            break;
        }
        // Every solution's iterations counted on from the last one's: the count only grows.
        progress.report("solving (iterations)", st.stats.iterations, 0);
        gather(st, ws, ex, false, it == 0);
        push(st, ws);
        let jumped = extrapolate > 0.0;
        let (change, b_max) = pull_parallel(st, ws, ex, extrapolate);
        // Closed instances change with what they receive (see `instance_light`).
        let (change, b_max) = if st.instances > 0 {
            (
                change.max(st.instance_change.0),
                b_max.max(st.instance_change.1),
            )
        } else {
            (change, b_max)
        };
        extrapolate = 0.0;
        iterations = it + 1;
        st.stats.iterations += 1;
        if !(change.is_finite() && b_max.is_finite()) {
            // Radiosity without bound (an operator that gives back more than it takes): no
            // tolerance can be met, and every comparison with it would pass.
            st.stats.diverged = true;
            st.stats.converged = false;
            st.stats.remaining_change = f32::INFINITY;
            return iterations;
        }
        let scale = b_max.max(f32::MIN_POSITIVE);
        last_scale = scale;
        let tol = tolerance * scale;
        if change <= tol * 1e-3 {
            remaining = change / scale;
            st.stats.converged = true;
            break;
        }
        if jumped {
            // The jump spoils this change as a measure of contraction: start over.
            ratios = [0.0; WINDOW];
            changes = [0.0; WINDOW];
            settled = 0;
            last = f32::INFINITY;
            continue;
        }
        if last.is_finite() && last > 0.0 {
            ratios[settled % WINDOW] = change / last;
            changes[settled % WINDOW] = change;
            settled += 1;
        }
        last = change;
        // Warm started with the contraction of the solution before (the same operator, or
        // one refined a little): the tail is judged with the larger of that and the ratios
        // seen so far, without waiting for a window of its own.
        if (1..WINDOW).contains(&settled) && q_before < 1.0 {
            let q = ratios[..settled].iter().copied().fold(q_before, f32::max);
            if q < 1.0 {
                let tail = change * q / (1.0 - q);
                if tail <= tol && change <= tol {
                    remaining = tail / scale;
                    st.stats.converged = true;
                    break;
                }
            }
        }
        if settled >= WINDOW {
            let q = ratios.iter().copied().fold(0.0f32, f32::max);
            let q_min = ratios.iter().copied().fold(f32::INFINITY, f32::min);
            if q < 1.0 {
                q_known = q;
                st.contraction = q;
            }
            if (0.9..1.0).contains(&q) && q - q_min <= 0.01 * (1.0 - q_min) {
                extrapolate = (q / (1.0 - q)).min(1e6);
            }
            // Changes lost in rounding do not tell the contraction: keep the last one known.
            remaining = if q_known < 1.0 {
                change * q_known / (1.0 - q_known)
            } else {
                f32::INFINITY
            };
            if remaining <= tol && change <= tol {
                remaining /= scale;
                st.stats.converged = true;
                break;
            }
            remaining /= scale;
            // Down to single-precision rounding while the estimate is still above the
            // tolerance: more iterations cannot help, say so now.
            let floor = changes.iter().copied().fold(0.0f32, f32::max);
            if floor <= scale * 4.0 * f32::EPSILON && extrapolate == 0.0 {
                if !remaining.is_finite() {
                    // Never seen contracting, and already still: nothing left to change.
                    remaining = floor / scale;
                    st.stats.converged = remaining <= tolerance;
                }
                break;
            }
        }
    }
    if !st.stats.converged {
        st.stats.iteration_capped = true;
        // Whatever ratios there are make the estimate (none: unknown).
        let k = settled.min(WINDOW);
        if k > 0 && !remaining.is_finite() {
            let q = ratios[..k]
                .iter()
                .copied()
                .fold(0.0f32, f32::max)
                .min(q_known);
            if q < 1.0 && last.is_finite() && last_scale > 0.0 {
                remaining = last * q / (1.0 - q) / last_scale;
            }
        }
    }
    st.stats.remaining_change = remaining;
    iterations
}

/// Iterations over which the contraction ratio is judged.
const WINDOW: usize = 8;

/// Every patch's gathered irradiance, and what the links received by clusters bring their
/// polygons (see `oriented`).
///
/// With `unit`, every emitting side counts as radiosity 1: what each leaf then receives is
/// the sum of its coefficients (see `closure`).
///
/// With `select`, clusters choose anew which links they share out apart (see
/// `oriented::summarize`): the first gather of every solution.
pub(crate) fn gather<E: Executor>(
    st: &mut State,
    ws: &mut [u8],
    ex: &mut Fallback<'_, E>,
    unit: bool,
    select: bool,
) {
    super::oriented::link_fluxes(st, ws, ex, unit);
    super::oriented::distribute(st, ws, ex, select);
    if st.instances > 0 && !unit {
        st.instance_change = super::instance_gather::gather_instances(st, ws, ex);
    }
    let first = st.clusters as usize;
    let n = st.receiver_count() as usize - first;
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
            let mut b = [0.0f32; 8];
            for (slot, i) in (chunk * CHUNK..((chunk + 1) * CHUNK).min(n)).enumerate() {
                let recv = c.st.receiver((first + i) as u64);
                let at = super::oriented::centre(c.st, c.ws, recv);
                // Sums in f64: in a closed scene with rho near 1 the light is a sum of many
                // reflections that f32 rounding would bias.
                let mut h = [0.0f64; 16];
                let mut cur = c.st.links_head(c.ws, recv);
                while cur != NONE {
                    let l = c.st.link(c.ws, cur);
                    let k = c.st.link_k(c.ws, cur);
                    let emit = Elem(l.emit);
                    if super::oriented::witnessed(&l) {
                        let per_side = State::sides(recv) == 2;
                        for r in 0..if kk == 1 { 1 } else { 2 } {
                            let coef = if kk == 1 { k[0] } else { k[r * 2] };
                            if coef == 0.0 {
                                continue;
                            }
                            super::oriented::witness_radiosity(
                                c.st,
                                c.ws,
                                &l,
                                r,
                                per_side,
                                unit,
                                &mut b[..nb],
                            );
                            for (hb, bb) in h[r * nb..(r + 1) * nb].iter_mut().zip(&b[..nb]) {
                                *hb += coef as f64 * *bb as f64;
                            }
                        }
                        cur = l.next;
                        continue;
                    }
                    for s in 0..kk.min(2) {
                        let any = if kk == 1 {
                            k[0] != 0.0
                        } else {
                            k[s] != 0.0 || k[2 + s] != 0.0
                        };
                        if !any
                            || !super::oriented::radiosity_towards(
                                c.st,
                                c.ws,
                                emit,
                                s,
                                at,
                                unit,
                                l.flags & super::records::EXACT != 0,
                                &mut b[..nb],
                            )
                        {
                            continue;
                        }
                        for r in 0..if kk == 1 { 1 } else { 2 } {
                            let coef = if kk == 1 { k[0] } else { k[r * 2 + s] };
                            if coef != 0.0 {
                                for (hb, bb) in h[r * nb..(r + 1) * nb].iter_mut().zip(&b[..nb]) {
                                    *hb += coef as f64 * *bb as f64;
                                }
                            }
                        }
                    }
                    cur = l.next;
                }
                for (o, v) in buf[slot * out..(slot + 1) * out].iter_mut().zip(&h) {
                    *o = *v as f32;
                }
            }
        },
        |c: &mut Ctx<'_>, chunk, buf| {
            for (slot, i) in (chunk * CHUNK..((chunk + 1) * CHUNK).min(n)).enumerate() {
                let recv = c.st.receiver((first + i) as u64);
                for side in 0..State::sides(recv) {
                    let src = &buf[slot * out + side * nb..slot * out + (side + 1) * nb];
                    c.st.h_mut(c.ws, recv, side).copy_from_slice(src);
                }
            }
        },
        &mut |_, _| {},
    );
}

/// Gathered irradiance down each polygon's quadtree (parents are numbered before their
/// children). What clusters receive reaches polygons through `oriented::distribute`.
pub(crate) fn push(st: &State, ws: &mut [u8]) {
    let nb = st.bands;
    let mut tmp = [0.0f32; 8];
    for kind in [Kind::Patch1, Kind::Patch2] {
        let len = st.pool(kind).len;
        for i in 0..len {
            let e = Elem::new(kind, i);
            let parent = Elem(st.patch(ws, e).parent);
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
/// largest radiosity (W/m^2). Parents take the mean of their children weighted by exposed
/// area (buried parts are seen by nothing); polygons record their power for `oriented`;
/// clusters take the power of their surfaces over their area.
pub(crate) fn pull(st: &State, ws: &mut [u8]) -> (f32, f32) {
    pull_extrapolated(st, ws, 0.0)
}

/// [`pull`], with every leaf's change from its previous radiosity scaled by
/// `1 + extrapolate` (see [`iterate`]); the returned change is before scaling.
fn pull_extrapolated(st: &State, ws: &mut [u8], extrapolate: f32) -> (f32, f32) {
    pull_from(st, ws, extrapolate, false)
}

/// A leaf's new radiosity per side and band, `B = E + rho H + tau H_other` (H with the
/// direct light of suns and sky).
fn leaf_radiosity(st: &State, ws: &[u8], e: Elem, new: &mut [[f32; 8]; 2]) {
    let nb = st.bands;
    let sides = State::sides(e);
    let p = st.patch(ws, e);
    let m = st.material(ws, st.polygon(ws, p.poly).material);
    let mut h = [[0.0f32; 8]; 2];
    for (side, hs) in h.iter_mut().enumerate().take(sides) {
        super::closure::leaf_irradiance(st, ws, e, side, &mut hs[..nb]);
    }
    for side in 0..sides {
        for b in 0..nb {
            let other = if sides == 2 { h[1 - side][b] } else { 0.0 };
            new[side][b] = m.emit[side][b] + m.rho[side][b] * h[side][b] + m.tau[b] * other;
        }
    }
}

/// [`pull_extrapolated`] with the leaves' radiosities, the bulk of the work, computed in
/// chunks on the executor (the same arithmetic, applied in order: the same bits for any
/// thread count); then parents and clusters as before.
fn pull_parallel<E: Executor>(
    st: &mut State,
    ws: &mut [u8],
    ex: &mut Fallback<'_, E>,
    extrapolate: f32,
) -> (f32, f32) {
    let nb = st.bands;
    let per = 2 * nb;
    let mut change = 0.0f32;
    for kind in [Kind::Patch2, Kind::Patch1] {
        let n = st.pool(kind).len as usize;
        let mut ctx = Ctx {
            st: &mut *st,
            ws: &mut *ws,
        };
        run_chunks(
            ex,
            &mut ctx,
            n.div_ceil(CHUNK),
            CHUNK * per,
            |c: &Ctx<'_>, chunk, buf| {
                for (slot, i) in (chunk * CHUNK..((chunk + 1) * CHUNK).min(n)).enumerate() {
                    let e = Elem::new(kind, i as u32);
                    let o = &mut buf[slot * per..(slot + 1) * per];
                    if c.st.patch(c.ws, e).first_child != NONE {
                        o[0] = f32::NAN;
                        continue;
                    }
                    let mut new = [[0.0f32; 8]; 2];
                    leaf_radiosity(c.st, c.ws, e, &mut new);
                    for side in 0..State::sides(e) {
                        o[side * nb..(side + 1) * nb].copy_from_slice(&new[side][..nb]);
                    }
                }
            },
            |c: &mut Ctx<'_>, chunk, buf| {
                for (slot, i) in (chunk * CHUNK..((chunk + 1) * CHUNK).min(n)).enumerate() {
                    let o = &buf[slot * per..(slot + 1) * per];
                    if o[0].is_nan() {
                        continue;
                    }
                    let e = Elem::new(kind, i as u32);
                    for side in 0..State::sides(e) {
                        let b = c.st.b_mut(c.ws, e, side);
                        for (old, &n) in b.iter_mut().zip(&o[side * nb..(side + 1) * nb]) {
                            change = change.max((n - *old).abs());
                            let n = if extrapolate > 0.0 {
                                (n + (n - *old) * extrapolate).max(0.0)
                            } else {
                                n
                            };
                            *old = n;
                        }
                    }
                }
            },
            &mut |_, _| {},
        );
    }
    let (_, b_max) = pull_from(st, ws, 0.0, true);
    (change, b_max)
}

/// The pull itself; with `leaves_done` the leaves' radiosities are already new (see
/// [`pull_parallel`]) and are only passed up.
fn pull_from(st: &State, ws: &mut [u8], extrapolate: f32, leaves_done: bool) -> (f32, f32) {
    let nb = st.bands;
    let (mut change, mut b_max) = (0.0f32, 0.0f32);
    for kind in [Kind::Patch2, Kind::Patch1] {
        let len = st.pool(kind).len;
        for i in (0..len).rev() {
            let e = Elem::new(kind, i);
            let mut p = st.patch(ws, e);
            let sides = State::sides(e);
            let mut new = [[0.0f32; 8]; 2];
            if p.first_child == NONE && leaves_done {
                for (side, ns) in new.iter_mut().enumerate().take(sides) {
                    if let Some(b) = st.b(ws, e, side) {
                        ns[..nb].copy_from_slice(b);
                    }
                }
            } else if p.first_child == NONE {
                leaf_radiosity(st, ws, e, &mut new);
            } else {
                let (mut area, mut seen) = (0.0f32, 0.0f32);
                let mut plain = [[0.0f32; 8]; 2];
                for j in 0..4 {
                    let child = Elem::new(kind, p.first_child + j);
                    let cp = st.patch(ws, child);
                    let (a, w) = (cp.area, cp.area * cp.exposed);
                    area += a;
                    seen += w;
                    for side in 0..sides {
                        if let Some(b) = st.b(ws, child, side) {
                            for k in 0..nb {
                                new[side][k] += w * b[k];
                                plain[side][k] += a * b[k];
                            }
                        }
                    }
                }
                // Wholly buried: nobody sees it, keep the plain mean.
                let (weights, total) = if seen > 0.0 {
                    (&mut new, seen)
                } else {
                    (&mut plain, area)
                };
                let inv = if total > 0.0 { 1.0 / total } else { 0.0 };
                for ns in weights.iter_mut().take(sides) {
                    for n in ns[..nb].iter_mut() {
                        *n *= inv;
                    }
                }
                if seen <= 0.0 {
                    new = plain;
                }
                let exposed = if area > 0.0 { seen / area } else { 0.0 };
                if exposed != p.exposed {
                    p.exposed = exposed;
                    st.set_patch(ws, e, &p);
                }
            }
            for (side, ns) in new.iter_mut().enumerate().take(sides) {
                let b = st.b_mut(ws, e, side);
                for (old, n) in b.iter_mut().zip(ns[..nb].iter_mut()) {
                    if p.first_child == NONE {
                        change = change.max((*n - *old).abs());
                        if extrapolate > 0.0 {
                            *n = (*n + (*n - *old) * extrapolate).max(0.0);
                        }
                    }
                    b_max = b_max.max(*n);
                    *old = *n;
                }
            }
            if Elem(p.parent).kind() == Kind::Cluster {
                let w = p.area * p.exposed;
                for side in 0..2 {
                    let dst = st.polygon_power_mut(ws, p.poly, side);
                    for (d, n) in dst.iter_mut().zip(&new[side.min(sides - 1)][..nb]) {
                        *d = if side < sides { w * n } else { 0.0 };
                    }
                }
            }
        }
    }
    for i in (0..st.clusters).rev() {
        let mut c = st.cluster(ws, i);
        let mut power = [0.0f32; 8];
        let mut peak = 0.0f32;
        for k in 0..c.child_count {
            let child = st.child(ws, c.children + k);
            if child.kind() == Kind::Cluster {
                let cc = st.cluster(ws, child.index());
                peak = peak.max(cc.peak);
                if let Some(b) = st.b(ws, child, 0) {
                    for (p, v) in power.iter_mut().zip(b) {
                        *p += cc.area * v;
                    }
                }
            } else if child.kind() == Kind::Instance {
                // Links never leave a cluster that holds closed instances (see
                // `refine::must_open`): its radiosity is its polygons' alone.
                continue;
            } else {
                let poly = st.patch(ws, child).poly;
                for side in 0..2 {
                    for (p, v) in power.iter_mut().zip(st.polygon_power(ws, poly, side)) {
                        *p += v;
                    }
                    if let Some(b) = st.b(ws, child, side) {
                        peak = b.iter().copied().fold(peak, f32::max);
                    }
                }
            }
        }
        c.peak = peak;
        st.set_cluster(ws, i, &c);
        let inv = if c.area > 0.0 { 1.0 / c.area } else { 0.0 };
        let b = st.b_mut(ws, Elem::new(Kind::Cluster, i), 0);
        for (d, p) in b.iter_mut().zip(&power[..nb]) {
            *d = p * inv;
        }
    }
    super::bins::update(st, ws, false);
    (change, b_max)
}

/// The power leaving all surfaces (W, the largest band): epsilon's unit.
pub(crate) fn flow(st: &State, ws: &[u8]) -> f32 {
    let nb = st.bands;
    let mut total = [0.0f64; 8];
    for i in 0..st.polygons {
        for side in 0..2 {
            for (t, v) in total.iter_mut().zip(st.polygon_power(ws, i, side)) {
                *t += *v as f64;
            }
        }
    }
    for i in 0..st.instances {
        let placed = st.placed(ws, i);
        if let Ok(r) = crate::tables::closed::Received::over(&placed, st.received(ws, i)) {
            for (b, t) in total.iter_mut().enumerate().take(nb) {
                *t += r.scattered(b) as f64;
            }
        }
    }
    total[..nb].iter().copied().fold(0.0, f64::max) as f32
}
