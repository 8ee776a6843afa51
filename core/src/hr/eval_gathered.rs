//! Links evaluated polygon by polygon: from a large cluster close by, or to a cluster, each
//! sample counting what meets the emitter's polygons first (see `cluster_kernel::gathered`).

use super::cluster_kernel::{
    Plane, SMALL_CLUSTER, Witnesses, cluster_polygon, gathered, shared_area,
};
use super::eval::{Coefficients, exposed_quadrature, recv_sides};
use super::ids::Elem;
use super::sample::point_toward;
use super::state::{Shape, State};
use crate::formfactor::facing_side;
use crate::sampling::{MAX_QUADRATURE, hash3, point_on, quadrature, unit2};
use crate::visibility::Visibility;
use glam::Vec3;

/// A link from a large cluster close by, gathered (see `cluster_kernel::gathered`): at the
/// receiver's quadrature points (per receiving side) or at `rays` points of a receiving
/// cluster's surfaces, `rays` rays each, counting what meets the emitter's polygons first.
/// The coefficients multiply the mean radiosity of the emitter's polygons facing the
/// receiver (`exact`). A sample of a receiving cluster on a one-sided face turned away from
/// the emitter is hidden from it by its own object, which the polygons' shares already
/// leave dark: it takes the mean of the samples on faces that can take the light.
#[allow(clippy::too_many_arguments)]
pub(super) fn gather_link<V: Visibility + ?Sized>(
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
