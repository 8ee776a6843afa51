//! The scale of a cluster's merged light (see `oriented::summarize`) that keeps its power.
//!
//! A cluster's polygons take the weaker links of it and its ancestors as one cone: the sum
//! of their flux densities along their mean direction. A polygon's share of a cone depends
//! on the cone's axis and width, so the merged cone does not hand out what the links would
//! apart: two links from opposite sides merge into light from all around, which a floor
//! takes a quarter of instead of half (a furnished room lost 1.1% of the light its clusters
//! received that way). The scale is what the links would hand the cluster's own polygons
//! apart over what the merged cone hands them, weighted by the links' flux when the beams are
//! chosen, and kept with them, so that the solution stays linear.

use super::cone::cone_share;
use super::ids::{Elem, Kind};
use super::state::State;
use crate::limits::NONE;
use glam::Vec3;

/// The bounds of a scale: a cluster's polygons may take far more or less of one cone than of
/// another, but not without limit (a merged cone nearly edge-on to every polygon).
const SCALE: (f32, f32) = (0.1, 10.0);

/// Most polygons a cluster holds as its own children that the scale is computed for.
const OWN: usize = 64;

/// The scale of cluster `c`'s merged rest, given the beams it keeps apart (1 when it has no
/// polygons of its own or the rest is empty).
pub(crate) fn rest_scale(st: &State, ws: &[u8], c: u32, beams: &[u32]) -> f32 {
    let cluster = st.cluster(ws, c);
    // Its own polygons (normal, area, sides), read once.
    let mut own = [(Vec3::ZERO, 0.0f32, false); OWN];
    let mut count = 0;
    for k in 0..cluster.child_count {
        let e = st.child(ws, cluster.children + k);
        if matches!(e.kind(), Kind::Cluster | Kind::Instance) {
            continue;
        }
        if count == OWN {
            // More than a cluster holds in practice: leave its rest as it is.
            return 1.0;
        }
        let p = st.patch(ws, e);
        own[count] = (
            Vec3::from(st.polygon(ws, p.poly).normal),
            p.area,
            State::sides(Elem(e.0)) == 2,
        );
        count += 1;
    }
    if count == 0 {
        return 1.0;
    }
    let own = &own[..count];
    let (mut apart, mut weight, mut dir) = (0.0f32, 0.0f32, Vec3::ZERO);
    let mut at = c;
    // The rest: every link of the cluster and its ancestors that is not a beam.
    for _ in 0..4096 {
        let mut cur = st.cluster(ws, at).links;
        while cur != NONE {
            let l = st.link(ws, cur);
            let index = cur;
            cur = l.next;
            if l.recv == l.emit || beams.contains(&index) {
                continue;
            }
            let w: f32 = st.link_flux(ws, index).iter().sum();
            if w.is_nan() || w <= 0.0 {
                continue;
            }
            let d = Vec3::from(l.dir);
            apart += w * taken(own, d);
            weight += w;
            dir += d * w;
        }
        at = st.cluster(ws, at).parent;
        if at == NONE {
            break;
        }
    }
    if !(weight > 0.0 && apart > 0.0) {
        return 1.0;
    }
    let merged = weight * taken(own, dir / weight);
    if merged > 0.0 {
        (apart / merged).clamp(SCALE.0, SCALE.1)
    } else {
        1.0
    }
}

/// What a cluster's own polygons (`own`: normal, area, two-sided) take of a cone of unit
/// flux density with `dir`'s axis and collimation (m^2), on every side they have, as
/// `oriented::share` hands it out.
fn taken(own: &[(Vec3, f32, bool)], dir: Vec3) -> f32 {
    let collimation = dir.length().min(1.0);
    let axis = if collimation > 0.0 {
        dir / dir.length()
    } else {
        Vec3::ZERO
    };
    let mut sum = 0.0f32;
    for &(normal, area, two) in own {
        let t = normal.dot(axis);
        let mut share = cone_share(collimation, t);
        if two {
            share += cone_share(collimation, -t);
        }
        sum += area * share;
    }
    sum
}
