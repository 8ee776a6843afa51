//! Links into a large receiving cluster estimated from the emitter's side (reciprocity):
//! rays leave points of the emitter's polygons in cosine-distributed directions, and what
//! the receiver takes is the share that meets one of its polygons first.
//!
//! Gathered at a few points of the receiver (`eval_gathered::gather_link`), the light of an emitter
//! much smaller than the receiver is heavy-tailed: most draws of four points of a furnished
//! room see nothing of a small lamp shade, a few see it whole, so the typical link carries
//! a fraction of its mean (a room lost 4% of its light that way). Shot from the emitter, the
//! estimate is a hit-or-miss fraction, bounded and well behaved when the receiver fills much
//! of the emitter's view.

use super::cluster_kernel::{Witnesses, shared_area};
use super::eval::Coefficients;
use super::ids::{Elem, Kind};
use super::sample::cosine_direction;
use super::sample::{area, point_in};
use super::state::State;
use crate::limits::NONE;
use crate::sampling::{hash3, unit2};
use crate::visibility::Visibility;
use glam::Vec3;

/// Fraction of an emitter's view that a receiving cluster's box must fill for its link to
/// be shot from the emitter ([`shoot`]) rather than gathered at points of the receiver.
const SHOOT_SHARE: f32 = 0.25;

/// The same for an emitter smaller than its receiver.
const SHOOT_SHARE_SMALL: f32 = 0.05;

/// The coefficients that link `recv <- emit` carries, shot from the emitter ([`shoot`]),
/// or `None` when it is not shot. Links from a cluster, or from a patch into a cluster, are
/// shot when the receiver's box fills much of the emitter's view (judged apart from the
/// shots themselves, so that the choice does not bias them). The decisions still come from
/// samples of the receiver (how its light varies, see `eval::evaluate`).
pub(crate) fn shot<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    recv: Elem,
    emit: Elem,
    seed: u32,
    rays: u32,
    vis: &V,
) -> Option<Coefficients> {
    let patch_emitter = !matches!(emit.kind(), Kind::Cluster | Kind::Source);
    if emit.kind() == Kind::Source || (patch_emitter && recv.kind() != Kind::Cluster) {
        return None;
    }
    // A cluster smaller than the patch it lights is shot even when it sees little of it:
    // the patch's few fixed points miss where its light peaks (a wall beside a chair), and
    // shots that miss the patch's box cost no ray. Not into a cluster: a sparse one (leaves
    // at a distance) is met by a few of the shots that enter its box, or none.
    let smaller = recv.kind() != Kind::Cluster
        && super::sample::area(st, ws, emit) < super::sample::area(st, ws, recv);
    let least = if smaller {
        SHOOT_SHARE_SMALL
    } else {
        SHOOT_SHARE
    };
    if box_share(st, ws, recv, emit, hash3(seed, 0xB0C5, 2), 32) < least {
        return None;
    }
    let n = (4 * rays * rays).max(16);
    let shot = shoot(st, ws, recv, emit, hash3(seed, 0x5407, 1), n, vis);
    let mut out = Coefficients {
        exact: true,
        rays: n,
        dir: shot.dir,
        ..Coefficients::default()
    };
    if recv.kind() == Kind::Cluster {
        let taken = shared_area(st, ws, recv.index(), shot.dir);
        if taken > 0.0 {
            out.k[0] = [shot.power[0][0] / taken, shot.power[0][1] / taken];
        }
        out.witness = shot.wit[0].pick;
    } else {
        let area = st.patch(ws, recv).area;
        if area > 0.0 {
            for (k, p) in out.k.iter_mut().zip(shot.power) {
                *k = [p[0] / area, p[1] / area];
            }
        }
        let r = st.shape(ws, recv);
        out.witness = super::eval_gathered::witnesses(&r, &shot.wit);
    }
    Some(out)
}

/// What the shots of one link found: the power the receiver takes per unit radiosity of
/// the emitter, by receiving side (a cluster's all in side 0) and emitting side (a cluster
/// emitter's all in side 0) (m^2), the mean direction towards the emitter over that power
/// (length: its collimation), and per receiving side two witnesses drawn among the
/// emitting polygon sides by their shares (see `Link::witness`).
pub(crate) struct Shot {
    pub power: [[f32; 2]; 2],
    pub dir: Vec3,
    pub wit: [Witnesses; 2],
}

/// The box of a receiver (cluster or patch), m.
fn bounds(st: &State, ws: &[u8], recv: Elem) -> (Vec3, Vec3) {
    if recv.kind() == Kind::Cluster {
        let c = st.cluster(ws, recv.index());
        return (Vec3::from(c.bbox_min), Vec3::from(c.bbox_max));
    }
    st.patch(ws, recv).bounds()
}

/// The fraction of `n` cosine-distributed directions from points of `emit` that enter the
/// box of cluster `recv` (no rays cast): how much of the emitter's view the receiver can
/// fill at most, which tells whether shooting pays ([`shoot`]).
pub(crate) fn box_share(st: &State, ws: &[u8], recv: Elem, emit: Elem, seed: u32, n: u32) -> f32 {
    let (lo, hi) = bounds(st, ws, recv);
    let mut hit = 0u32;
    for j in 0..n {
        let h = hash3(seed, j, 0xB0C5);
        let Some((y, d, _, _, _)) = emission_ray(st, ws, emit, h) else {
            continue;
        };
        if slab(y, d, lo, hi).is_some() {
            hit += 1;
        }
    }
    hit as f32 / n.max(1) as f32
}

/// `n` shots from `emit` into `recv`, a cluster or a patch (see the module's text).
pub(crate) fn shoot<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    recv: Elem,
    emit: Elem,
    seed: u32,
    n: u32,
    vis: &V,
) -> Shot {
    let (lo, hi) = bounds(st, ws, recv);
    let margin = 1e-3 * (hi - lo).length() + 1e-6;
    let a = area(st, ws, emit);
    let (mut power, mut dir, mut wit) = ([[0.0f32; 2]; 2], Vec3::ZERO, [Witnesses::EMPTY; 2]);
    let n = n.max(1);
    for j in 0..n {
        let h = hash3(seed, j, 0x5407);
        let Some((y, d, poly, side, sides)) = emission_ray(st, ws, emit, h) else {
            continue;
        };
        let Some((_, t1)) = slab(y, d, lo, hi) else {
            continue;
        };
        let end = y + d * (t1 + margin);
        let Some((hp, t)) = vis.first_hit(y, end, [poly, NONE]) else {
            continue;
        };
        if hp >= st.polygons || !takes(st, ws, recv, hp, y + (end - y) * t) {
            continue;
        }
        // The back of a one-sided polygon takes nothing (it is the inside of its object).
        let rec = st.polygon(ws, hp);
        let back = usize::from(Vec3::from(rec.normal).dot(d) > 0.0);
        if back >= State::sides(Elem(rec.root)) {
            continue;
        }
        let w = a * sides as f32;
        let s = if emit.kind() == Kind::Cluster {
            0
        } else {
            side
        };
        let r = if recv.kind() == Kind::Cluster {
            0
        } else {
            back
        };
        power[r][s] += w;
        dir -= d * w;
        wit[r].offer([poly | ((side as u32) << 31); 2], w, hash3(h, j, 0x3B));
    }
    let total: f32 = power.iter().flatten().sum();
    let inv = 1.0 / n as f32;
    for p in power.iter_mut().flatten() {
        *p *= inv;
    }
    Shot {
        power,
        dir: if total > 0.0 { dir / total } else { Vec3::ZERO },
        wit,
    }
}

/// A ray leaving a point of `emit`'s surfaces (area-weighted) from one of its polygon's
/// sides (drawn evenly), cosine-distributed: its start, direction, polygon, side and the
/// polygon's number of sides.
fn emission_ray(
    st: &State,
    ws: &[u8],
    emit: Elem,
    h: u32,
) -> Option<(Vec3, Vec3, u32, usize, usize)> {
    let (y, poly) = point_in(st, ws, emit, h);
    if poly >= st.polygons {
        return None;
    }
    let rec = st.polygon(ws, poly);
    let sides = State::sides(Elem(rec.root));
    let side = if sides == 2 {
        (hash3(h, 0x51DE, 7) >> 31) as usize
    } else {
        0
    };
    let n = Vec3::from(rec.normal);
    let n = if side == 0 { n } else { -n };
    let (u, v) = unit2(hash3(h, 0xD1, 0x5C));
    let d = cosine_direction(n, u, v);
    (d != Vec3::ZERO).then_some((y, d, poly, side, sides))
}

/// Where the ray `y + t d` (t >= 0) crosses the box `lo..hi`: entry and exit t.
fn slab(y: Vec3, d: Vec3, lo: Vec3, hi: Vec3) -> Option<(f32, f32)> {
    let (mut t0, mut t1) = (0.0f32, f32::INFINITY);
    for k in 0..3 {
        if d[k] == 0.0 {
            if y[k] < lo[k] || y[k] > hi[k] {
                return None;
            }
            continue;
        }
        let inv = 1.0 / d[k];
        let (a, b) = ((lo[k] - y[k]) * inv, (hi[k] - y[k]) * inv);
        t0 = t0.max(a.min(b));
        t1 = t1.min(a.max(b));
    }
    (t0 <= t1 && t1.is_finite()).then_some((t0, t1))
}

/// True when the point `x` on polygon `poly` lies in `recv`: in the cluster, or on the patch.
fn takes(st: &State, ws: &[u8], recv: Elem, poly: u32, x: Vec3) -> bool {
    if recv.kind() == Kind::Cluster {
        return inside(st, ws, poly, recv.index());
    }
    let p = st.patch(ws, recv);
    if p.poly != poly {
        return false;
    }
    if p.depth() == 0 {
        return true;
    }
    // A sub-patch: inside its convex outline (edges taken about the polygon's normal).
    let n = Vec3::from(st.polygon(ws, poly).normal);
    let m = p.corner_count();
    let mut sign = 0.0f32;
    for i in 0..m {
        let a = Vec3::from(p.corners[i]);
        let b = Vec3::from(p.corners[(i + 1) % m]);
        let s = (b - a).cross(x - a).dot(n);
        if s * sign < 0.0 {
            return false;
        }
        if s != 0.0 {
            sign = s;
        }
    }
    true
}

/// True when polygon `poly` lies inside cluster `cluster` (its root patch's chain of
/// parent clusters passes through it).
fn inside(st: &State, ws: &[u8], poly: u32, cluster: u32) -> bool {
    let parent = Elem(st.patch(ws, Elem(st.polygon(ws, poly).root)).parent);
    if parent.0 == NONE || parent.kind() != Kind::Cluster {
        return false;
    }
    // Cluster parents are plain indices; clusters nest at most a few hundred deep.
    let mut cur = parent.index();
    for _ in 0..4096 {
        if cur == cluster {
            return true;
        }
        if cur == NONE {
            return false;
        }
        cur = st.cluster(ws, cur).parent;
    }
    false
}
