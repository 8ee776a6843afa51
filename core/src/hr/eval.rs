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

use super::cluster_kernel::{
    Plane, SMALL_CLUSTER, Witnesses, cluster_form_factor, cluster_polygon, gathered, shared_area,
    small_cluster,
};
use super::ids::Elem;
use super::sample::point_toward;
use super::shoot::shot;
use super::state::{Shape, State};
use crate::formfactor::{facing_side, point_polygon};
use crate::limits::NONE;
use crate::sampling::{
    MAX_CLIPPED_QUADRATURE, MAX_QUADRATURE, clipped_quadrature, hash3, point_on, quadrature, unit2,
};
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
fn recv_sides(shape: &Shape) -> usize {
    match shape {
        Shape::Patch {
            two_sided: true, ..
        } => 2,
        _ => 1,
    }
}

/// True if the emitter's side `s` carries radiosity.
fn emits(shape: &Shape, s: usize) -> bool {
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

/// A link from a large cluster close by, gathered (see `cluster_kernel::gathered`): at the
/// receiver's quadrature points (per receiving side) or at `rays` points of a receiving
/// cluster's surfaces, `rays` rays each, counting what meets the emitter's polygons first.
/// The coefficients multiply the mean radiosity of the emitter's polygons facing the
/// receiver (`exact`). A sample of a receiving cluster on a one-sided face turned away from
/// the emitter is hidden from it by its own object, which the polygons' shares already
/// leave dark: it takes the mean of the samples on faces that can take the light.
#[allow(clippy::too_many_arguments)]
fn gather_link<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    recv: Elem,
    r: &Shape,
    emit: Elem,
    seed: u32,
    rays: u32,
    occlude: bool,
    vis: &V,
    out: &mut Coefficients,
) {
    out.exact = true;
    // Per receiving side of a patch; a cluster's in the first.
    let mut wit = [Witnesses::EMPTY; 2];
    // Judged by the light it would bring unoccluded: a few visibility rays into a volume of
    // leaves see little or nothing more often than not, and a large link kept on that
    // ground carries its whole noise.
    out.partial = true;
    match *r {
        Shape::Patch {
            corners,
            n,
            normal,
            poly,
            ..
        } => {
            let (mut pts, mut plain) = ([Vec3::ZERO; MAX_QUADRATURE], [0.0f32; MAX_QUADRATURE]);
            let m = quadrature(&corners[..n], &mut pts, &mut plain);
            let rp = st.patch(ws, recv);
            let mut wts = [0.0f32; MAX_QUADRATURE];
            exposed_quadrature(&rp, &corners[..n], &mut pts, &mut wts);
            let (mut lo, mut hi) = ([f32::INFINITY; 2], [0.0f32; 2]);
            for q in 0..m {
                let (x, w) = (pts[q], wts[q]);
                out.partial |= w == 0.0;
                for side in 0..recv_sides(r) {
                    let nr = if side == 0 { normal } else { -normal };
                    let qs = hash3(seed, q as u32, side as u32);
                    let (k, _, open, wq) = gathered(
                        st,
                        ws,
                        emit,
                        x,
                        Plane::Facing(nr),
                        poly,
                        qs,
                        rays,
                        occlude,
                        vis,
                    );
                    out.rays += rays;
                    out.open += plain[q] * open;
                    if w == 0.0 {
                        continue;
                    }
                    out.k[side][0] += w * k;
                    wit[side].offer(
                        wq.pick,
                        w * wq.total,
                        hash3(seed, q as u32, 0x3C + side as u32),
                    );
                    lo[side] = lo[side].min(k);
                    hi[side] = hi[side].max(k);
                }
            }
            for side in 0..recv_sides(r) {
                if hi[side] > 0.0 {
                    out.spread = out.spread.max(hi[side] - lo[side].min(hi[side]));
                }
            }
        }
        Shape::Cluster { area: r_area, .. } => {
            // The power the receiver's surfaces take, from the irradiance on the planes of
            // points drawn over them (towards the emitter, weighted back to area means).
            let (at, reach) = reach_of(st, ws, emit);
            // A patch emitter's two sides may send different radiosities: each point's
            // light counts for the side of the emitter that faces it.
            let plane = match st.shape(ws, emit) {
                Shape::Patch {
                    corners, normal, ..
                } => Some((corners[0], normal)),
                _ => None,
            };
            let (mut power, mut dir, mut open) = ([0.0f32; 2], Vec3::ZERO, 0.0f32);
            // At least 4 points: one point of a large receiver is a coin toss.
            let rc = st.cluster(ws, recv.index());
            // A small receiver gets one point on each of its polygons (stratified: drawn
            // towards the emitter, four points of a handful of leaves left whole clusters
            // 10% off), with rays shared among them; a larger one at least 4 points.
            let small = rc.polygons <= SMALL_CLUSTER;
            // A handful of polygons gets 2 or 4 points each, one per stratum of the polygon:
            // the light of a large emitter close by varies across a face (a box by a wall),
            // and one point per face made such links heavy-tailed.
            let per = if !small {
                1
            } else if 4 * rc.polygons <= SMALL_CLUSTER {
                4
            } else if 2 * rc.polygons <= SMALL_CLUSTER {
                2
            } else {
                1
            };
            let (points, rays) = if small {
                let points = rc.polygons * per;
                (points, (4 * rays).div_ceil(points.max(1)).max(1))
            } else {
                (rays.max(4), rays)
            };
            for k in 0..points {
                let (x, px, w) = if small {
                    let (poly, corners, n) = cluster_polygon(st, ws, rc.first_polygon + k / per);
                    let (u, v) = unit2(hash3(seed, k, 0xC3));
                    let s = k % per;
                    let (u, v) = match per {
                        4 => (0.5 * ((s & 1) as f32 + u), 0.5 * ((s >> 1) as f32 + v)),
                        2 => (0.5 * (s as f32 + u), v),
                        _ => (u, v),
                    };
                    let a = st.patch(ws, Elem(st.polygon(ws, poly).root)).area;
                    // Each stratum's share of the area (a quad's map is not area-preserving).
                    let jac = super::sample::jacobian(&corners[..n], u, v)
                        / super::sample::mean_jacobian(&corners[..n]);
                    (
                        point_on(&corners[..n], u, v),
                        poly,
                        a * jac * points as f32 / (per as f32 * r_area),
                    )
                } else {
                    point_toward(st, ws, recv, at, reach, hash3(seed, k, 0xC1))
                };
                if px >= st.polygons {
                    continue;
                }
                let rec = st.polygon(ws, px);
                let sides = State::sides(Elem(rec.root));
                let (irr, d, o, wq) = gathered(
                    st,
                    ws,
                    emit,
                    x,
                    Plane::Sides(Vec3::from(rec.normal), sides),
                    px,
                    hash3(seed, k, 0xE1),
                    rays,
                    occlude,
                    vis,
                );
                out.rays += rays;
                let side = match plane {
                    Some((on, n)) => facing_side(x, on, n).unwrap_or(0),
                    None => 0,
                };
                power[side] += w * irr;
                wit[0].offer(wq.pick, w * wq.total, hash3(seed, k, 0x3D));
                open += w * o;
                dir += d * (w * irr);
            }
            let inv = r_area / points as f32;
            let (power, open) = ([power[0] * inv, power[1] * inv], open * inv);
            let total = power[0] + power[1];
            let mean = if total > 0.0 {
                dir * (inv / total)
            } else {
                Vec3::ZERO
            };
            // The flux density that the polygons' shares of this cone turn into that power.
            let taken = shared_area(st, ws, recv.index(), mean);
            if taken > 0.0 {
                out.k[0][0] = power[0] / taken;
                out.k[0][1] = power[1] / taken;
                out.open = open / taken;
            }
            out.dir = mean;
        }
        Shape::Source { .. } | Shape::Instance { .. } => {}
    }
    if emit.kind() == super::ids::Kind::Cluster {
        out.witness = witnesses(r, &wit);
    }
}

/// A link's witnesses from those drawn per receiving side: one per side for a two-sided
/// patch, both of the first otherwise (see `Link::witness`).
pub(crate) fn witnesses(r: &Shape, wit: &[Witnesses; 2]) -> [u32; 2] {
    if recv_sides(r) == 2 {
        [wit[0].pick[0], wit[1].pick[0]]
    } else {
        wit[0].pick
    }
}

/// Where an emitter sits and how far it reaches (its centre and radius, m): where the points
/// of a receiving cluster are drawn towards ([`point_toward`]).
fn reach_of(st: &State, ws: &[u8], emit: Elem) -> (Vec3, f32) {
    match st.shape(ws, emit) {
        Shape::Cluster { min, max, .. } | Shape::Instance { min, max, .. } => {
            ((min + max) * 0.5, 0.5 * (max - min).length())
        }
        Shape::Patch {
            corners, n, area, ..
        } => {
            let mut sum = Vec3::ZERO;
            for c in &corners[..n] {
                sum += *c;
            }
            (sum / n as f32, libm::sqrtf(area))
        }
        // A direction: every part of the receiver alike.
        Shape::Source { .. } => (Vec3::ZERO, f32::INFINITY),
    }
}

/// A patch's coefficients from a smaller patch, by reciprocity: the emitter's form factors
/// to the receiver, integrated at the emitter's own quadrature points (where they vary
/// little: the emitter is the smaller), times emitter area over receiver area. Integrating at
/// the larger receiver's points instead can land a point right beside a small bright
/// emitter and credit the whole receiver with its peak (a 1 mm lamp over a 1000 m floor
/// gave the floor 1000 times the lamp's power); this way a patch never receives more than
/// its emitter sends. The spread over the receiver comes from the open form factors at the
/// receiver's points.
#[allow(clippy::too_many_arguments)]
fn reciprocal<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    recv: Elem,
    r: &Shape,
    emit: Elem,
    e: &Shape,
    seed: u32,
    rays: u32,
    vis: &V,
    out: &mut Coefficients,
) {
    let (
        Shape::Patch {
            corners: rc,
            n: rn,
            normal: r_normal,
            poly: r_poly,
            area: r_area,
            ..
        },
        Shape::Patch {
            corners: ec,
            n: en,
            normal: e_normal,
            poly: e_poly,
            area: e_area,
            two_sided: e_two,
        },
    ) = (*r, *e)
    else {
        return;
    };
    let (rc, ec) = (&rc[..rn], &ec[..en]);
    let rp = st.patch(ws, recv);
    let ep = st.patch(ws, emit);
    let r_sides = recv_sides(r);
    // Per unit of the receiver's exposed area, from the emitter's exposed points.
    let (mut pts, mut wts) = ([Vec3::ZERO; MAX_QUADRATURE], [0.0f32; MAX_QUADRATURE]);
    let m = exposed_quadrature(&ep, ec, &mut pts, &mut wts);
    let seen_r = r_area * rp.exposed;
    let (dist, scale) = (
        |c: Vec3| r_normal.dot(c - rc[0]),
        ec.iter().fold(0.0f32, |a, &c| a.max((c - rc[0]).length())),
    );
    let straddles =
        ec.iter().any(|&c| dist(c) > 1e-6 * scale) && ec.iter().any(|&c| dist(c) < -1e-6 * scale);
    // A straddling emitter is integrated over its whole area in front (a buried part there
    // is dark to the rays), so its exposure is not counted again.
    let e_seen = if straddles {
        e_area
    } else {
        e_area * ep.exposed
    };
    let ratio_open = e_seen / r_area;
    let ratio = if seen_r > 0.0 { e_seen / seen_r } else { 0.0 };
    // The emitter's points, each with the receiving side it faces. An emitter straddling
    // the receiver's plane is integrated over the part on each side.
    const N: usize = 2 * MAX_CLIPPED_QUADRATURE;
    let (mut ys, mut yw, mut ysd) = ([Vec3::ZERO; N], [0.0f32; N], [0usize; N]);
    let mut count = 0;
    if straddles {
        for side in 0..r_sides {
            let nr = if side == 0 { r_normal } else { -r_normal };
            let (mut cp, mut cw) = (
                [Vec3::ZERO; MAX_CLIPPED_QUADRATURE],
                [0.0f32; MAX_CLIPPED_QUADRATURE],
            );
            let k = clipped_quadrature(ec, rc[0], nr, &mut cp, &mut cw);
            for i in 0..k {
                (ys[count], yw[count], ysd[count]) = (cp[i], cw[i], side);
                count += 1;
            }
        }
    } else {
        for q in 0..m {
            let Some(side) = facing_side(pts[q], rc[0], r_normal) else {
                continue;
            };
            if wts[q] > 0.0 && side < r_sides {
                (ys[count], yw[count], ysd[count]) = (pts[q], wts[q], side);
                count += 1;
            }
        }
    }
    for q in 0..count {
        let (y, w, r_side) = (ys[q], yw[q], ysd[q]);
        for s in 0..if e_two { 2 } else { 1 } {
            let ns = if s == 0 { e_normal } else { -e_normal };
            let f = point_polygon(y, ns, rc);
            if f <= 0.0 {
                continue;
            }
            let qs = hash3(seed, q as u32, 0x5E + s as u32);
            let (mut seen, mut cast) = (0.0f32, 0u32);
            for j in 0..2 * rays {
                if cast == rays {
                    break;
                }
                let (u, v) = unit2(hash3(qs, j, 0xA6));
                let x = point_on(rc, u, v);
                if ns.dot(x - y) <= 0.0 {
                    continue;
                }
                seen += vis.transmittance(y, x, [e_poly, r_poly]);
                cast += 1;
            }
            out.rays += cast;
            let v = if cast == 0 { 1.0 } else { seen / cast as f32 };
            out.partial |= v < 1.0;
            out.k[r_side][s] += ratio * w * f * v;
            out.open += ratio_open * w * f;
        }
    }
    out.partial |= (0..4).any(|q| rp.buried(q));
    // How the open coefficient varies over the receiver.
    let (mut rpts, mut rwts) = ([Vec3::ZERO; MAX_QUADRATURE], [0.0f32; MAX_QUADRATURE]);
    let rm = quadrature(rc, &mut rpts, &mut rwts);
    for side in 0..r_sides {
        let nr = if side == 0 { r_normal } else { -r_normal };
        let (mut lo, mut hi) = (f32::INFINITY, 0.0f32);
        for &x in &rpts[..rm] {
            let Some(s_side) = facing_side(x, ec[0], e_normal) else {
                continue;
            };
            let f = if emits(e, s_side) {
                point_polygon(x, nr, ec)
            } else {
                0.0
            };
            lo = lo.min(f);
            hi = hi.max(f);
        }
        if hi > 0.0 {
            out.spread = out.spread.max(hi - lo.min(hi));
        }
    }
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
