//! A diagnostic of the transport, link by link (not a stable interface): the power each link
//! carries in the current solution against the power that rays traced forward from the
//! emitting polygons actually take from its emitter to its receiver. A ray from point `y`
//! of one polygon that first meets point `z` of another is counted for the one link whose
//! receiver holds `z` and whose emitter holds `y`.

use super::final_gather::leaf_at;
use super::ids::{Elem, Kind};
use super::state::State;
use crate::limits::NONE;
use crate::sampling::{hash3, point_on, unit2};
use crate::visibility::Visibility;
use glam::Vec3;

/// Power (W per band) not carried by any link, by where the traced rays went.
#[derive(Clone, Copy, Debug, Default)]
pub struct Leftover {
    /// Left the scene.
    pub escaped: [f64; 8],
    /// Met the back of a one-sided polygon.
    pub backs: [f64; 8],
    /// Met a receiving side that no link from the ray's emitter covers.
    pub uncovered: [f64; 8],
    /// Covered by more than one link (counted once, for the first).
    pub overlapped: [f64; 8],
    /// Covered only by a self-link (which carries nothing).
    pub self_linked: [f64; 8],
}

/// The elements above `e` and `e` itself, leaf first.
fn chain(st: &State, ws: &[u8], e: Elem, out: &mut [Elem; 64]) -> usize {
    let mut n = 0;
    let mut at = e;
    loop {
        out[n] = at;
        n += 1;
        let up = match at.kind() {
            Kind::Cluster => {
                let p = st.cluster(ws, at.index()).parent;
                if p == NONE {
                    NONE
                } else {
                    Elem::new(Kind::Cluster, p).0
                }
            }
            Kind::Source => NONE,
            _ => st.patch(ws, at).parent,
        };
        if up == NONE || n == 64 {
            return n;
        }
        at = Elem(up);
    }
}

/// Power carried by each link in the current solution (W per band, `carried[link * bands +
/// band]`): to a patch, coefficient x emitter radiosity x exposed area; to a cluster, its
/// flux density x the area through which the cluster's polygons take it.
pub(crate) fn carried(st: &State, ws: &[u8], carried: &mut [f64]) {
    let nb = st.bands;
    let kk = st.lay.strides.link_k;
    let mut b = [0.0f32; 8];
    for i in 0..st.links.len {
        let l = st.link(ws, i);
        if l.flags & super::records::FREE != 0 || l.recv == l.emit {
            continue;
        }
        let recv = Elem(l.recv);
        let out = &mut carried[i as usize * nb..(i as usize + 1) * nb];
        if recv.kind() == Kind::Cluster {
            let a = super::cluster_kernel::shared_area(st, ws, recv.index(), Vec3::from(l.dir));
            for (o, f) in out.iter_mut().zip(st.link_flux(ws, i)) {
                *o += (*f * a) as f64;
            }
            continue;
        }
        let p = st.patch(ws, recv);
        let area = (p.area * p.exposed) as f64;
        let k = st.link_k(ws, i);
        let at = super::oriented::centre(st, ws, recv);
        if super::oriented::witnessed(&l) {
            for r in 0..if kk == 1 { 1 } else { 2 } {
                let coef = if kk == 1 { k[0] } else { k[r * 2] };
                let per_side = State::sides(recv) == 2;
                super::oriented::witness_radiosity(st, ws, &l, r, per_side, false, &mut b[..nb]);
                for (o, v) in out.iter_mut().zip(&b[..nb]) {
                    *o += (coef * v) as f64 * area;
                }
            }
            continue;
        }
        for s in 0..kk.min(2) {
            if !super::oriented::radiosity_towards(
                st,
                ws,
                Elem(l.emit),
                s,
                at,
                false,
                l.flags & super::records::EXACT != 0,
                &mut b[..nb],
            ) {
                continue;
            }
            for r in 0..if kk == 1 { 1 } else { 2 } {
                let coef = if kk == 1 { k[0] } else { k[r * 2 + s] };
                for (o, v) in out.iter_mut().zip(&b[..nb]) {
                    *o += (coef * v) as f64 * area;
                }
            }
        }
    }
}

/// Traces `rays` rays in all from the polygons' emitting sides (by power, cosine-distributed
/// from uniform points) and adds what each carries to the link that covers it
/// (`traced[link * bands + band]`, W).
pub(crate) fn traced<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    vis: &V,
    rays: u32,
    traced: &mut [f64],
) -> Leftover {
    let nb = st.bands;
    let mut left = Leftover::default();
    // Total emitted power (largest band) to share the rays.
    let mut total = 0.0f64;
    each_leaf(st, ws, |e, p| {
        for side in 0..State::sides(e) {
            if let Some(b) = st.b(ws, e, side) {
                let m = b.iter().fold(0.0f32, |a, v| a.max(*v));
                total += (m * p.area * p.exposed) as f64;
            }
        }
    });
    if total <= 0.0 {
        return left;
    }
    let mut emit_chain = [Elem(0); 64];
    let mut recv_chain = [Elem(0); 64];
    each_leaf(st, ws, |leaf, p| {
        let poly = p.poly;
        let rec = st.polygon(ws, poly);
        let root = Elem(rec.root);
        let n = p.corner_count();
        let mut corners = [Vec3::ZERO; 4];
        for (c, s) in corners.iter_mut().zip(p.corners) {
            *c = s.into();
        }
        let normal = Vec3::from(rec.normal);
        for side in 0..State::sides(leaf) {
            let Some(b) = st.b(ws, leaf, side) else {
                continue;
            };
            let m = b.iter().fold(0.0f32, |a, v| a.max(*v));
            let power = (m * p.area * p.exposed) as f64;
            if power <= 0.0 {
                continue;
            }
            let k = (libm::ceil(power / total * rays as f64) as u32).max(1);
            let mut each = [0.0f64; 8];
            for (e, v) in each.iter_mut().zip(&b[..nb]) {
                *e = (*v * p.area * p.exposed) as f64 / k as f64;
            }
            let ns = if side == 0 { normal } else { -normal };
            for j in 0..k {
                let (u, v) = unit2(hash3(leaf.0, j, 0x5A1 + side as u32));
                let y = point_on(&corners[..n], u, v);
                let (a, c) = unit2(hash3(leaf.0, j, 0x5B2 + side as u32));
                let d = super::sample::cosine_direction(ns, a, c);
                let end = st.beyond(y, d);
                let add = |to: &mut [f64; 8]| {
                    for (t, e) in to.iter_mut().zip(&each[..nb]) {
                        *t += e;
                    }
                };
                let Some((q, t)) = vis.first_hit(y, end, [poly, NONE]) else {
                    add(&mut left.escaped);
                    continue;
                };
                let z = y + (end - y) * t;
                let qrec = st.polygon(ws, q);
                let qroot = Elem(qrec.root);
                let qn = Vec3::from(qrec.normal);
                let qside = if qn.dot(d) < 0.0 { 0 } else { 1 };
                if qside >= State::sides(qroot) {
                    add(&mut left.backs);
                    continue;
                }
                let e_leaf = leaf;
                let _ = root;
                let r_leaf = leaf_at(st, ws, qroot, z, qn);
                let ne = chain(st, ws, e_leaf, &mut emit_chain);
                let nr = chain(st, ws, r_leaf, &mut recv_chain);
                let (mut found, mut count, mut selfish) = (NONE, 0, false);
                for r in &recv_chain[..nr] {
                    let mut cur = st.links_head(ws, *r);
                    while cur != NONE {
                        let l = st.link(ws, cur);
                        if emit_chain[..ne].iter().any(|e| e.0 == l.emit) {
                            if l.emit == l.recv {
                                selfish = true;
                            } else {
                                count += 1;
                                if found == NONE {
                                    found = cur;
                                }
                            }
                        }
                        cur = l.next;
                    }
                }
                if found == NONE {
                    if selfish {
                        add(&mut left.self_linked);
                    } else {
                        add(&mut left.uncovered);
                    }
                    continue;
                }
                if count > 1 {
                    add(&mut left.overlapped);
                }
                let out = &mut traced[found as usize * nb..(found as usize + 1) * nb];
                for (o, e) in out.iter_mut().zip(&each[..nb]) {
                    *o += e;
                }
            }
        }
    });
    left
}

/// Every leaf patch with its record.
fn each_leaf(st: &State, ws: &[u8], mut f: impl FnMut(Elem, super::records::Patch)) {
    for kind in [Kind::Patch1, Kind::Patch2] {
        for i in 0..st.pool(kind).len {
            let e = Elem::new(kind, i);
            let p = st.patch(ws, e);
            if p.first_child == NONE {
                f(e, p);
            }
        }
    }
}

/// What the links into clusters hand the polygons, summed (W per band): each polygon's
/// share on each of its receiving sides times its area.
pub(crate) fn distributed(st: &State, ws: &[u8]) -> [f64; 8] {
    let mut out = [0.0f64; 8];
    for poly in 0..st.polygons {
        let root = Elem(st.polygon(ws, poly).root);
        let a = st.patch(ws, root).area as f64;
        for side in 0..State::sides(root) {
            for (o, h) in out.iter_mut().zip(st.polygon_h(ws, poly, side)) {
                *o += *h as f64 * a;
            }
        }
    }
    out
}
