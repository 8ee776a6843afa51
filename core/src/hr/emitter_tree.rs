//! One emitting polygon for a point that gathers light, in scenes with many emitters, with
//! the probability it was drawn with, so that the final gather can add emitted light
//! directly (exact form factor and one visibility ray over that probability) where rays into
//! the scene would rarely meet a small bright emitter (a stand under bulbs of 1,000 facets
//! made 7% of its light). A light cut per receiving leaf: the cluster tree opened from the
//! root, the most important cluster first, into at most [`CUT`] clusters weighed at the
//! leaf's centre; then, per sample point, one of them by weight and down from it, each child
//! by its emitted power over its squared distance (none behind the point's plane, none for a
//! polygon whose side facing the point emits nothing). Unbiased: every polygon that can
//! light the point has a positive probability.

use super::emitters::{Receiver, hidden_share};
use super::final_gather::patch_corners;
use super::ids::{Elem, Kind};
use super::state::State;
use crate::formfactor::{facing_side, point_polygon};
use crate::sampling::{hash3, point_in_front, unit2};
use crate::visibility::Visibility;
use glam::Vec3;

/// Clusters in a light cut.
pub(crate) const CUT: usize = 32;

/// A drawn emitting polygon and the probability it was drawn with.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Drawn {
    pub poly: u32,
    pub prob: f32,
}

/// The clusters a receiving leaf draws emitters from, with their weights.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Cut {
    clusters: [u32; CUT],
    weights: [f64; CUT],
    count: usize,
}

impl Cut {
    /// True when nothing emits in front of the leaf.
    pub(crate) fn is_empty(&self) -> bool {
        self.count == 0
    }
}

/// The light cut of a leaf whose receiving side faces `n`, weighed at its centre `x`. A
/// cluster is opened only when all its children are clusters (the plane test is then the
/// same for every point of the leaf; a polygon's emitting side may not be).
pub(crate) fn cut(st: &State, ws: &[u8], x: Vec3, n: Vec3, skip: u32) -> Cut {
    let mut out = Cut {
        clusters: [0; CUT],
        weights: [0.0; CUT],
        count: 0,
    };
    if st.clusters == 0 {
        return out;
    }
    let root = Elem::new(Kind::Cluster, 0);
    let w = importance(st, ws, root, x, n, skip);
    if w.is_nan() || w <= 0.0 {
        return out;
    }
    (out.clusters[0], out.weights[0], out.count) = (0, w, 1);
    let mut closed = [false; CUT];
    // The heaviest cluster still open to splitting, first.
    while let Some(i) = (0..out.count)
        .filter(|&i| !closed[i])
        .max_by(|&a, &b| out.weights[a].total_cmp(&out.weights[b]))
    {
        let c = st.cluster(ws, out.clusters[i]);
        let children = (0..c.child_count).map(|k| st.child(ws, c.children + k));
        let all_clusters = c.child_count > 0 && children.clone().all(|e| e.kind() == Kind::Cluster);
        let lit = children
            .clone()
            .filter(|&e| importance(st, ws, e, x, n, skip) > 0.0)
            .count();
        if !all_clusters || out.count - 1 + lit > CUT {
            closed[i] = true;
            continue;
        }
        // Replace it by its lit children.
        let last = out.count - 1;
        (out.clusters[i], out.weights[i], closed[i]) =
            (out.clusters[last], out.weights[last], closed[last]);
        out.count = last;
        for e in children {
            let w = importance(st, ws, e, x, n, skip);
            if w > 0.0 {
                (out.clusters[out.count], out.weights[out.count]) = (e.index(), w);
                closed[out.count] = false;
                out.count += 1;
            }
        }
    }
    out
}

/// Draws an emitting polygon for the point `x` of a leaf with light cut `cut`, whose
/// receiving side faces `n`, from `u` in [0, 1); `None` when nothing emits in front of it.
/// `skip` (the point's own polygon) is never drawn.
pub(crate) fn draw(
    st: &State,
    ws: &[u8],
    cut: &Cut,
    x: Vec3,
    n: Vec3,
    u: f64,
    skip: u32,
) -> Option<Drawn> {
    let total: f64 = cut.weights[..cut.count].iter().sum();
    if total.is_nan() || total <= 0.0 {
        return None;
    }
    let mut u = u.clamp(0.0, 1.0);
    let (k, before, w) = pick(cut.count, |k| cut.weights[k], u * total)?;
    let mut prob = w / total;
    u = ((u * total - before) / w).clamp(0.0, 1.0 - f64::EPSILON);
    let mut cluster = cut.clusters[k];
    loop {
        let c = st.cluster(ws, cluster);
        let weight = |k: usize| importance(st, ws, st.child(ws, c.children + k as u32), x, n, skip);
        let count = c.child_count as usize;
        // Each child's weight once (a cluster has at most 16 children; more are weighed
        // twice).
        let mut kept = [0.0f64; 16];
        let total: f64 = if count <= kept.len() {
            for (k, w) in kept[..count].iter_mut().enumerate() {
                *w = weight(k);
            }
            kept[..count].iter().sum()
        } else {
            (0..count).map(weight).sum()
        };
        if total.is_nan() || total <= 0.0 {
            return None;
        }
        let (k, before, w) = if count <= kept.len() {
            pick(count, |k| kept[k], u * total)?
        } else {
            pick(count, weight, u * total)?
        };
        prob *= w / total;
        u = ((u * total - before) / w).clamp(0.0, 1.0 - f64::EPSILON);
        let e = st.child(ws, c.children + k as u32);
        if e.kind() == Kind::Cluster {
            cluster = e.index();
        } else {
            return Some(Drawn {
                poly: st.patch(ws, e).poly,
                prob: prob as f32,
            });
        }
    }
}

/// Adds to `c` the irradiance at the leaf's sample from one emitting polygon drawn down the
/// leaf's light cut (`pick` in [0, 1)): its exact unoccluded form factor from the point times
/// one visibility ray, over the probability it was drawn with. Returns the rays cast.
#[allow(clippy::too_many_arguments)]
pub(crate) fn light<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    vis: &V,
    leaf: &Receiver,
    cut: &Cut,
    pick: f64,
    h: u32,
    c: &mut [f32],
) -> u32 {
    let (x, n) = (leaf.x, leaf.nrm);
    let Some(d) = draw(st, ws, cut, x, n, pick, leaf.poly) else {
        return 0;
    };
    if d.prob.is_nan() || d.prob <= 0.0 {
        return 0;
    }
    let lp = st.polygon(ws, d.poly);
    let (lc, k) = patch_corners(st, ws, Elem(lp.root));
    let Some(side) = facing_side(x, lc[0], Vec3::from(lp.normal)) else {
        return 0;
    };
    let m = st.material(ws, lp.material);
    let f = point_polygon(x, n, &lc[..k]);
    if !(f.is_finite() && f > 0.0) {
        return 0;
    }
    // A point of the part of it in front of x, by area; where hidden, the form factor less
    // that point's share (see `emitters::hidden_share`: unbiased in a penumbra).
    let (u, v) = unit2(hash3(h, 0, 0x9F));
    let pick = unit2(hash3(h, 1, 0x9F)).0;
    let Some(y) = point_in_front(&lc[..k], x, n, pick, u, v) else {
        return 0;
    };
    let t = vis.transmittance(x, y, [leaf.poly, d.poly]);
    let visible = if t < 1.0 {
        f - hidden_share(x, n, y, &lc[..k], Vec3::from(lp.normal), side, t)
    } else {
        f
    };
    if visible.is_finite() && visible != 0.0 {
        let scale = visible / d.prob;
        for (ck, e) in c.iter_mut().zip(&m.emit[side][..st.bands]) {
            *ck += scale * e;
        }
    }
    1
}

/// The item among `count` whose cumulative weight passes `target`: (index, weight before
/// it, its weight); the last positive one if rounding leaves `target` beyond them all.
fn pick(count: usize, weight: impl Fn(usize) -> f64, target: f64) -> Option<(usize, f64, f64)> {
    let (mut acc, mut chosen) = (0.0f64, None);
    for k in 0..count {
        let w = weight(k);
        if w <= 0.0 {
            continue;
        }
        chosen = Some((k, acc, w));
        if target < acc + w {
            break;
        }
        acc += w;
    }
    chosen
}

/// How much a child of a cluster may light `x` (facing `n`): emitted power (W) over the
/// squared distance to its centre (at least its own squared size), times the cosines
/// towards it (floored: a part of it may face better than its centre); 0 when it lies
/// wholly behind the point's plane or emits nothing towards the point.
fn importance(st: &State, ws: &[u8], e: Elem, x: Vec3, n: Vec3, skip: u32) -> f64 {
    const FLOOR: f32 = 0.05;
    if e.kind() == Kind::Cluster {
        let c = st.cluster(ws, e.index());
        if c.emitted.is_nan() || c.emitted <= 0.0 {
            return 0.0;
        }
        let (lo, hi) = (Vec3::from(c.bbox_min), Vec3::from(c.bbox_max));
        // The box's corner furthest along n: behind the plane if even that one is.
        let far = Vec3::select(n.cmpge(Vec3::ZERO), hi, lo);
        if n.dot(far - x) <= 0.0 {
            return 0.0;
        }
        let centre = (lo + hi) * 0.5;
        let r2 = (0.5 * (hi - lo)).length_squared();
        let d = centre - x;
        let d2 = d.length_squared().max(r2).max(f32::MIN_POSITIVE);
        let cos = (n.dot(d) / libm::sqrtf(d2)).max(FLOOR);
        return (c.emitted * cos / d2) as f64;
    }
    // A closed instance beside the emitters in a level of hierarchical instantiation:
    // its contents emit nothing here (their light is in its tables).
    if !matches!(e.kind(), Kind::Patch1 | Kind::Patch2) {
        return 0.0;
    }
    let p = st.patch(ws, e);
    if p.poly == skip {
        return 0.0;
    }
    let rec = st.polygon(ws, p.poly);
    let normal = Vec3::from(rec.normal);
    let corners = &p.corners[..p.corner_count()];
    let first = Vec3::from(corners[0]);
    if !corners.iter().any(|&c| n.dot(Vec3::from(c) - x) > 0.0) {
        return 0.0;
    }
    let Some(side) = facing_side(x, first, normal) else {
        return 0.0;
    };
    if side >= State::sides(e) {
        return 0.0;
    }
    let m = st.material(ws, rec.material);
    let exitance = m.emit[side][..st.bands]
        .iter()
        .copied()
        .fold(0.0f32, f32::max);
    if exitance.is_nan() || exitance <= 0.0 {
        return 0.0;
    }
    let centre = corners.iter().map(|&c| Vec3::from(c)).sum::<Vec3>() / corners.len() as f32;
    let d = centre - x;
    let d2 = d.length_squared().max(p.area).max(f32::MIN_POSITIVE);
    let inv = 1.0 / libm::sqrtf(d2);
    let cos_r = (n.dot(d) * inv).max(FLOOR);
    let cos_e = (normal.dot(d) * inv).abs().max(FLOOR);
    (exitance * p.area * cos_r * cos_e / d2) as f64
}
