//! Link coefficients: how much irradiance a receiver gets per unit radiosity of an emitter.
//!
//! * to a patch: the average over the patch's fixed quadrature points of the exact
//!   point-to-polygon form factor (a patch emitter, a small cluster's polygons) or of the
//!   directional-source kernel, times the fraction of unblocked visibility rays;
//! * from a larger cluster or to a cluster: gathered polygon by polygon ([`gather_link`]),
//!   or shot from the emitter where the receiver fills its view ([`shot`]).
//!
//! Every sample point comes from a hash of the two elements, so a link's value never
//! depends on when or on which thread it is computed.

use super::cluster_kernel::{Witnesses, cluster_form_factor, small_cluster};
use super::eval_gathered::{gather_link, witnesses};
use super::eval_reciprocal::reciprocal;
use super::ids::Elem;
use super::shoot::shot;
use super::state::{Shape, State};
use crate::formfactor::{facing_side, point_polygon};
use crate::limits::NONE;
use crate::sampling::{MAX_QUADRATURE, hash3, point_on, quadrature, unit2};
use crate::visibility::Visibility;
use glam::Vec3;

/// Coefficients of one link, by receiving side and emitting side.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Coefficients {
    pub k: [[f32; 2]; 2],
    /// The same without occlusion, over the sides that carry energy.
    pub open: f32,
    pub partial: bool,
    pub rays: u32,
    /// To a cluster: the light's mean direction over its flux density (see `Link::dir`).
    pub dir: Vec3,
    /// From a small cluster: the coefficients are exact sums over its polygons, to be
    /// multiplied by the mean radiosity of its polygons facing the receiver (see
    /// `oriented::mean_facing`), not by its oriented emission.
    pub exact: bool,
    /// To a patch: how much the coefficient varies over the patch (largest minus smallest
    /// value at its quadrature points, per receiving side, the larger side): the error of
    /// taking it as constant there.
    pub spread: f32,
    /// The coefficients with occlusion summed over sides, from the refinement's samples
    /// (see [`evaluate`]).
    pub seen: f32,
    /// From a cluster, gathered: the polygon sides whose radiosities the link carries (see
    /// `Link::witness`).
    pub witness: [u32; 2],
}

/// Receiving sides of an element: both for a two-sided patch, the front otherwise (the back
/// of a one-sided patch absorbs; a cluster has one "side", its flux density).
pub(super) fn recv_sides(shape: &Shape) -> usize {
    match shape {
        Shape::Patch {
            two_sided: true, ..
        } => 2,
        _ => 1,
    }
}

/// True if the emitter's side `s` carries radiosity.
pub(super) fn emits(shape: &Shape, s: usize) -> bool {
    match shape {
        Shape::Patch { two_sided, .. } => s == 0 || *two_sided,
        _ => s == 0,
    }
}

/// The patch's quadrature points with the buried ones weighted 0 and the others' weights
/// scaled to sum to 1 (all 0 when every point is buried); returns the point count.
pub(crate) fn exposed_quadrature(
    p: &super::records::Patch,
    corners: &[Vec3],
    points: &mut [Vec3; MAX_QUADRATURE],
    weights: &mut [f32; MAX_QUADRATURE],
) -> usize {
    let m = quadrature(corners, points, weights);
    let mut total = 0.0f32;
    for (q, w) in weights.iter_mut().enumerate().take(m) {
        if p.buried(q) {
            *w = 0.0;
        }
        total += *w;
    }
    let inv = if total > 0.0 { 1.0 / total } else { 0.0 };
    for w in weights.iter_mut().take(m) {
        *w *= inv;
    }
    m
}

/// A link's coefficients, and what refinement decides by (`open`, `seen`, `partial`,
/// `spread`) from samples of their own.
///
/// Refinement keeps a link whose estimated transfer is small and splits one whose estimate
/// is large. Judged on the very samples the light then goes by, a link whose few samples
/// happened to see too little is kept and one that saw too much is split and estimated
/// again: the links that remain are biased low (in canopies, where many links lie near the
/// threshold and a few rays see a leaf or not, a third of the light went missing; in closed
/// rooms, where the hidden part of a link drives its splitting, the bias was the other way
/// and made light). Two independent estimates make the choice blind to the one kept.
pub(crate) fn evaluate<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    recv: Elem,
    emit: Elem,
    vis: &V,
) -> Coefficients {
    let seed = hash3(recv.0, emit.0, 0x11AD);
    let rays = st.settings.rays.max(1);
    if super::refine::must_open(st, ws, recv, emit).is_some() {
        // Split before it carries anything (see `refine::must_open`).
        return Coefficients::default();
    }
    if recv.kind() == super::ids::Kind::Instance || emit.kind() == super::ids::Kind::Instance {
        return super::instance_kernel::evaluate(st, ws, recv, emit, vis, seed, rays);
    }
    let mut out = match shot(st, ws, recv, emit, seed, rays, vis) {
        Some(c) => c,
        None => evaluate_seeded(st, ws, recv, emit, vis, seed, rays, true),
    };
    // The choice needs an idea of the size: a quarter of the rays, or, where the light is
    // gathered polygon by polygon, as many samples as the light goes by, without occlusion
    // (no rays: a few samples of a large receiver under a few lamps land where they do not
    // shine more often than not, and the whole lamps' light was then judged by nothing).
    let (d_rays, d_occlude) = if gathered_link(st, ws, recv, emit) {
        (rays, false)
    } else {
        (rays.div_ceil(4), true)
    };
    let d = evaluate_seeded(
        st,
        ws,
        recv,
        emit,
        vis,
        hash3(seed, 0xDEC1DE, 0x5EE),
        d_rays,
        d_occlude,
    );
    out.open = d.open;
    out.partial = d.partial;
    out.spread = d.spread;
    out.seen = d.k.iter().flatten().sum();
    out.rays += d.rays;
    out
}

/// True when link `recv <- emit` is evaluated polygon by polygon ([`gather_link`]): to a
/// cluster, or from a cluster too large to sum exactly. A large cluster taken as a volume of
/// uniform radiance (a box kernel times its oriented emission) gave patches a third too
/// little of its light in a furnished room, and misjudged close receivers both ways.
fn gathered_link(st: &State, ws: &[u8], recv: Elem, emit: Elem) -> bool {
    use super::ids::Kind;
    emit.kind() != Kind::Source
        && (recv.kind() == Kind::Cluster
            || (emit.kind() == Kind::Cluster && !small_cluster(st, ws, emit)))
}

/// One estimate of a link's coefficients from `seed`, with `rays` rays per point; without
/// `occlude`, a gathered link ([`gather_link`]) casts no rays and gives its open value.
#[allow(clippy::too_many_arguments)]
pub(crate) fn evaluate_seeded<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    recv: Elem,
    emit: Elem,
    vis: &V,
    seed: u32,
    rays: u32,
    occlude: bool,
) -> Coefficients {
    let r = st.shape(ws, recv);
    let e = st.shape(ws, emit);
    let mut out = Coefficients {
        exact: small_cluster(st, ws, emit),
        witness: [NONE; 2],
        ..Coefficients::default()
    };
    if gathered_link(st, ws, recv, emit) {
        gather_link(st, ws, recv, &r, emit, seed, rays, occlude, vis, &mut out);
        return out;
    }
    match r {
        Shape::Patch {
            corners,
            n,
            normal,
            poly,
            area: r_area,
            ..
        } => {
            if let Shape::Patch { area: e_area, .. } = e
                && e_area < r_area
            {
                reciprocal(st, ws, recv, &r, emit, &e, seed, rays, vis, &mut out);
                return out;
            }
            // Buried points receive nothing, but count for the open coefficient: a patch
            // whose points are all buried may still be partly exposed, and its links must
            // live on to be refined where it is.
            let (mut pts, mut plain) = ([Vec3::ZERO; MAX_QUADRATURE], [0.0f32; MAX_QUADRATURE]);
            let m = quadrature(&corners[..n], &mut pts, &mut plain);
            let rp = st.patch(ws, recv);
            let mut wts = [0.0f32; MAX_QUADRATURE];
            exposed_quadrature(&rp, &corners[..n], &mut pts, &mut wts);
            let (mut lo, mut hi) = ([f32::INFINITY; 2], [0.0f32; 2]);
            let mut wit = [Witnesses::EMPTY; 2];
            for q in 0..m {
                let (x, w) = (pts[q], wts[q]);
                out.partial |= w == 0.0;
                for side in 0..recv_sides(&r) {
                    let nr = if side == 0 { normal } else { -normal };
                    let qs = hash3(seed, q as u32, side as u32);
                    let (contrib, open, s_side, wq) =
                        to_point(st, ws, x, nr, poly, &e, emit, qs, rays, vis, &mut out);
                    out.open += plain[q] * open;
                    if w == 0.0 {
                        continue;
                    }
                    wit[side].offer(
                        wq.pick,
                        w * contrib,
                        hash3(seed, q as u32, 0x3F + side as u32),
                    );
                    out.k[side][s_side] += w * contrib;
                    lo[side] = lo[side].min(contrib);
                    hi[side] = hi[side].max(contrib);
                }
            }
            for side in 0..recv_sides(&r) {
                if hi[side] > 0.0 {
                    out.spread = out.spread.max(hi[side] - lo[side].min(hi[side]));
                }
            }
            if out.exact {
                out.witness = witnesses(&r, &wit);
            }
        }
        // Receiving clusters are gathered (see `gathered_link`); links with closed
        // instances are `instance_kernel`'s.
        Shape::Cluster { .. } | Shape::Source { .. } | Shape::Instance { .. } => {}
    }
    out
}

/// Irradiance coefficient at point `x` (normal `nr`, on polygon `poly`) from the emitter:
/// returns (visible coefficient, open coefficient, emitting side, and from a small cluster
/// the polygon sides its rays reached, see `Link::witness`).
#[allow(clippy::too_many_arguments)]
fn to_point<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    x: Vec3,
    nr: Vec3,
    poly: u32,
    e: &Shape,
    emit: Elem,
    seed: u32,
    rays: u32,
    vis: &V,
    out: &mut Coefficients,
) -> (f32, f32, usize, Witnesses) {
    const NO: Witnesses = Witnesses::EMPTY;
    match *e {
        Shape::Patch {
            corners,
            n,
            normal,
            poly: ep,
            ..
        } => {
            let Some(s_side) = facing_side(x, corners[0], normal) else {
                return (0.0, 0.0, 0, NO);
            };
            if !emits(e, s_side) {
                return (0.0, 0.0, s_side, NO);
            }
            let f = point_polygon(x, nr, &corners[..n]);
            if f <= 0.0 {
                return (0.0, 0.0, s_side, NO);
            }
            // Rays to points of the emitter in front of the receiving side.
            let (mut seen, mut cast) = (0.0f32, 0u32);
            for j in 0..2 * rays {
                if cast == rays {
                    break;
                }
                let (u, v) = unit2(hash3(seed, j, 0xA5));
                let y = point_on(&corners[..n], u, v);
                if nr.dot(y - x) <= 0.0 {
                    continue;
                }
                seen += vis.transmittance(x, y, [poly, ep]);
                cast += 1;
            }
            out.rays += cast;
            let v = if cast == 0 { 1.0 } else { seen / cast as f32 };
            out.partial |= v < 1.0;
            (f * v, f, s_side, NO)
        }
        Shape::Cluster { area, .. } if small_cluster(st, ws, emit) => {
            // Exact: the form factors of the cluster's polygons that face the point, times
            // the visible fraction of rays into the cluster.
            let facing = cluster_form_factor(st, ws, emit, x, nr);
            let open = facing.total.min(1.0);
            if open <= 0.0 {
                return (0.0, 0.0, 0, NO);
            }
            let _ = area;
            let (v, wit) =
                facing.visible_witnessed(st, ws, emit, x, Some(nr), poly, seed, rays, vis);
            out.rays += rays;
            out.partial |= v < 1.0;
            (open * v, open, 0, wit)
        }
        // Larger clusters are gathered polygon by polygon (see `gathered_link`), closed
        // instances are `instance_kernel`'s.
        Shape::Cluster { .. } | Shape::Instance { .. } => (0.0, 0.0, 0, NO),
        Shape::Source { towards } => {
            let c = nr.dot(towards);
            if c <= 0.0 {
                return (0.0, 0.0, 0, NO);
            }
            let skip = st.source_skip(ws, emit.index(), poly);
            let v = vis.transmittance_towards(x, st.beyond(x, towards), towards, skip);
            out.rays += 1;
            out.partial |= v < 1.0;
            (c * v, c, 0, NO)
        }
    }
}
