//! Oriented clusters: a cluster emits and receives with the orientation of each polygon
//! inside it, not as an isotropic volume.
//!
//! * Emitting: towards a direction `w` a cluster radiates the intensity of its polygons,
//!   `I(w) = sum_p [P_front max(0, n_p . w) + P_back max(0, -n_p . w)] / pi` (P: radiosity x
//!   exposed area, W). Links keep the isotropic kernel `A cos / (4 pi r^2 + A)` of the
//!   cluster's area A; the radiosity they carry is the equivalent `4 pi I(w) / A`
//!   ([`emission`]), which is the cluster's mean radiosity when its polygons face every way
//!   evenly. A flat soil cluster therefore sends its light up, none down.
//! * Receiving: a link to a cluster gives the flux density on a plane facing the emitter
//!   (W/m^2, the scalar irradiance S) and the mean direction of that light weighted by it
//!   (a vector of length c = |V| / S: 1 for a beam, 1/2 for light from a whole hemisphere,
//!   0 for light from all around). Every polygon below the cluster takes, on each side, the
//!   share a plane of its orientation would get from a uniform cone of light with that axis
//!   and collimation ([`cone_share`]) instead of a quarter on each side: a leaf facing a lamp
//!   gets all of it and one seen edge-on none, while under a wide emitter both sides of an
//!   upright leaf get their half ([`distribute`]). Visibility inside the receiving cluster
//!   stays the link's average.
//!
//! Both cost one pass over the polygons of the clusters involved per iteration (the first
//! over each emitting cluster's polygons per link, the second over each polygon's ancestor
//! clusters' links), in fixed chunks like every other phase.

use super::cone::cone_share;
use super::exec::{Executor, Fallback, run_chunks};
use super::ids::{Elem, Kind};
use super::layout::CHUNK;
use super::state::State;
use crate::limits::NONE;
use glam::Vec3;

/// Centre of an element (m): a patch's corner mean, a cluster's box centre.
pub(crate) fn centre(st: &State, ws: &[u8], e: Elem) -> Vec3 {
    match e.kind() {
        Kind::Cluster => {
            let c = st.cluster(ws, e.index());
            (Vec3::from(c.bbox_min) + Vec3::from(c.bbox_max)) * 0.5
        }
        Kind::Source => Vec3::ZERO,
        Kind::Instance => super::instance_kernel::centre_of(st, ws, e.index()),
        _ => {
            let p = st.patch(ws, e);
            let n = p.corner_count();
            let mut sum = Vec3::ZERO;
            for c in &p.corners[..n] {
                sum += Vec3::from(*c);
            }
            sum / n as f32
        }
    }
}

/// The radiosity (W/m^2 per band) that a cluster's isotropic kernel must carry towards the
/// unit direction `w` so that the link transfers the intensity of its polygons: `4 pi I(w) /
/// A`.
/// With `unit`, every emitting side has radiosity 1 (see `closure`).
pub(crate) fn emission(st: &State, ws: &[u8], cluster: u32, w: Vec3, unit: bool, out: &mut [f32]) {
    out.fill(0.0);
    let c = st.cluster(ws, cluster);
    if c.area <= 0.0 {
        return;
    }
    if c.bins != NONE {
        super::bins::emission_of(st, ws, c.bins, w, out);
        let s = 4.0 / c.area;
        for o in out.iter_mut() {
            *o *= s;
        }
        return;
    }
    for k in c.first_polygon..c.first_polygon + c.polygons {
        let poly = st.ordered(ws, k);
        let rec = st.polygon(ws, poly);
        let n = Vec3::from(rec.normal);
        let cos = n.dot(w);
        let (side, f) = if cos > 0.0 { (0, cos) } else { (1, -cos) };
        if f <= 0.0 {
            continue;
        }
        if unit {
            let root = Elem(rec.root);
            if side < State::sides(root) {
                let p = st.patch(ws, root);
                for o in out.iter_mut() {
                    *o += f * p.area * p.exposed;
                }
            }
        } else {
            for (o, p) in out.iter_mut().zip(st.polygon_power(ws, poly, side)) {
                *o += f * p;
            }
        }
    }
    let s = 4.0 / c.area;
    for o in out.iter_mut() {
        *o *= s;
    }
}

/// The mean radiosity (W/m^2 per band) of a cluster's polygons towards the unit direction
/// `w`, each weighted by its exposed area times its cosine to `w` (on the side that faces
/// it): what the exact form factors of a small cluster multiply.
pub(crate) fn mean_facing(
    st: &State,
    ws: &[u8],
    cluster: u32,
    w: Vec3,
    unit: bool,
    out: &mut [f32],
) {
    out.fill(0.0);
    let c = st.cluster(ws, cluster);
    if c.bins != NONE {
        super::bins::mean_facing(st, ws, c.bins, w, unit, out);
        return;
    }
    let mut weight = 0.0f32;
    for k in c.first_polygon..c.first_polygon + c.polygons {
        let poly = st.ordered(ws, k);
        let rec = st.polygon(ws, poly);
        let cos = Vec3::from(rec.normal).dot(w);
        let (side, f) = if cos > 0.0 { (0, cos) } else { (1, -cos) };
        let root = Elem(rec.root);
        if f <= 0.0 || side >= State::sides(root) {
            continue;
        }
        let p = st.patch(ws, root);
        weight += f * p.area * p.exposed;
        if unit {
            continue;
        }
        for (o, v) in out.iter_mut().zip(st.polygon_power(ws, poly, side)) {
            *o += f * v;
        }
    }
    if weight > 0.0 {
        if unit {
            out.fill(1.0);
        } else {
            for o in out.iter_mut() {
                *o /= weight;
            }
        }
    }
}

/// The radiosity an emitter carries along a link towards `towards` (a point of the receiver)
/// from its side `side`: a patch's own radiosity, a cluster's [`emission`] (side 0 only), a
/// source's irradiance. `None` when that side emits nothing.
/// With `unit`, every emitting side has radiosity 1 (see `closure`). With `exact` (a link
/// whose coefficients sum a small cluster's form factors), a cluster gives the mean
/// radiosity of its polygons that face `towards` ([`mean_facing`]).
#[allow(clippy::too_many_arguments)]
pub(crate) fn radiosity_towards(
    st: &State,
    ws: &[u8],
    emit: Elem,
    side: usize,
    towards: Vec3,
    unit: bool,
    exact: bool,
    out: &mut [f32],
) -> bool {
    match emit.kind() {
        Kind::Cluster => {
            if side != 0 {
                return false;
            }
            let w = (towards - centre(st, ws, emit)).normalize_or_zero();
            if exact {
                mean_facing(st, ws, emit.index(), w, unit, out);
            } else {
                emission(st, ws, emit.index(), w, unit, out);
            }
            true
        }
        Kind::Instance => {
            if side != 0 {
                return false;
            }
            if unit {
                out.fill(1.0);
            } else {
                super::instance_kernel::carried_radiosity(st, ws, emit.index(), towards, out);
            }
            true
        }
        _ => match st.b(ws, emit, side) {
            Some(b) => {
                if unit {
                    out.fill(1.0);
                } else {
                    out.copy_from_slice(b);
                }
                true
            }
            None => false,
        },
    }
}

/// True when link `l` carries its witnesses' radiosities (see [`witness_radiosity`]).
pub(crate) fn witnessed(l: &super::records::Link) -> bool {
    Elem(l.emit).kind() == Kind::Cluster && (l.witness[0] != NONE || l.witness[1] != NONE)
}

/// The radiosity (W/m^2 per band) a link gathered from a cluster carries to receiving side
/// `r`: that of the polygon sides its samples met, two of them drawn by their shares of its
/// coefficient (see `Link::witness`): for a two-sided patch the one drawn for that side,
/// else the mean of both. Unbiased for what the samples saw, where the mean radiosity of the
/// cluster's polygons facing the receiver is not (soil under a canopy sees its dark lower
/// leaves, not the mean leaf).
pub(crate) fn witness_radiosity(
    st: &State,
    ws: &[u8],
    l: &super::records::Link,
    r: usize,
    per_side: bool,
    unit: bool,
    out: &mut [f32],
) {
    if unit {
        out.fill(1.0);
        return;
    }
    out.fill(0.0);
    let picks: &[u32] = if per_side {
        let w = if l.witness[r] != NONE {
            l.witness[r]
        } else {
            l.witness[1 - r]
        };
        &[w][..]
    } else {
        &l.witness[..]
    };
    let mut count = 0.0f32;
    let mut acc = [0.0f32; 8];
    for &id in picks {
        if id == NONE {
            continue;
        }
        count += 1.0;
        let (poly, side) = (id & 0x7FFF_FFFF, (id >> 31) as usize);
        let root = Elem(st.polygon(ws, poly).root);
        let p = st.patch(ws, root);
        let exposed = p.area * p.exposed;
        if exposed <= 0.0 || side >= State::sides(root) {
            continue;
        }
        for (a, v) in acc.iter_mut().zip(st.polygon_power(ws, poly, side)) {
            *a += v / exposed;
        }
    }
    if count > 0.0 {
        for (o, a) in out.iter_mut().zip(&acc) {
            *o = a / count;
        }
    }
}

struct Ctx<'a> {
    st: &'a mut State,
    ws: &'a mut [u8],
}

/// Every link received by a cluster: the flux density it brings in this iteration.
pub(crate) fn link_fluxes<E: Executor>(
    st: &mut State,
    ws: &mut [u8],
    ex: &mut Fallback<'_, E>,
    unit: bool,
) {
    let n = st.links.len as usize;
    let nb = st.bands;
    let kk = st.lay.strides.link_k;
    let mut ctx = Ctx { st, ws };
    run_chunks(
        ex,
        &mut ctx,
        n.div_ceil(CHUNK),
        CHUNK * nb,
        |c: &Ctx<'_>, chunk, buf| {
            buf.fill(0.0);
            let mut b = [0.0f32; 8];
            for (slot, i) in (chunk * CHUNK..((chunk + 1) * CHUNK).min(n)).enumerate() {
                let l = c.st.link(c.ws, i as u32);
                let recv = Elem(l.recv);
                let o = &mut buf[slot * nb..(slot + 1) * nb];
                if l.flags & super::records::FREE != 0 || recv.kind() != Kind::Cluster {
                    // Not a cluster's: the (sequential) apply skips it unread.
                    o[0] = f32::NAN;
                    continue;
                }
                if l.recv == l.emit {
                    continue;
                }
                let k = c.st.link_k(c.ws, i as u32);
                let at = centre(c.st, c.ws, recv);
                if witnessed(&l) {
                    witness_radiosity(c.st, c.ws, &l, 0, false, unit, &mut b[..nb]);
                    for (f, v) in o.iter_mut().zip(&b[..nb]) {
                        *f += k[0] * v;
                    }
                    continue;
                }
                for s in 0..kk.min(2) {
                    let coef = if kk == 1 { k[0] } else { k[s] };
                    if coef == 0.0
                        || !radiosity_towards(
                            c.st,
                            c.ws,
                            Elem(l.emit),
                            s,
                            at,
                            unit,
                            l.flags & super::records::EXACT != 0,
                            &mut b[..nb],
                        )
                    {
                        continue;
                    }
                    for (f, v) in o.iter_mut().zip(&b[..nb]) {
                        *f += coef * v;
                    }
                }
            }
        },
        |c: &mut Ctx<'_>, chunk, buf| {
            for (slot, i) in (chunk * CHUNK..((chunk + 1) * CHUNK).min(n)).enumerate() {
                if buf[slot * nb].is_nan() {
                    continue;
                }
                c.st.link_flux_mut(c.ws, i as u32)
                    .copy_from_slice(&buf[slot * nb..(slot + 1) * nb]);
            }
        },
        &mut |_, _| {},
    );
}

/// Beams a cluster keeps apart in its summary; weaker light is merged into one cone.
const BEAMS: usize = 4;

/// Floats of a cluster's summary: the links of its [`BEAMS`] beams (indices, as bits), then
/// the total of every link it and its ancestors receive: flux per band, and the sum of
/// their direction vectors weighted by their flux summed over bands; last, the scale of the
/// merged rest that keeps its power (see `rest_scale`).
pub(crate) const fn summary_floats(bands: usize) -> usize {
    BEAMS + bands + 4
}

/// Every cluster's summary of the light that reaches its polygons through the links it and
/// its ancestors receive: the [`BEAMS`] strongest links as they are, the rest merged into
/// one equivalent cone (total minus beams). A polygon then takes its share of a handful of
/// cones from its own cluster instead of one per link up its ancestry, which would cost
/// tens of evaluations per polygon and iteration in a tree. Parents come before children,
/// so one pass in cluster order carries every summary down.
///
/// With `select`, the beams are chosen anew (the strongest by their flux now); otherwise the
/// choice of the last selection stands, so that within a solution the sharing is linear in
/// the radiosities (a choice that changed from one iteration to the next would keep the
/// solution from settling).
fn summarize(st: &State, ws: &mut [u8], select: bool) {
    let nb = st.bands;
    let len = summary_floats(nb);
    let mut sum = [0.0f32; 32];
    let strength = |st: &State, ws: &[u8], i: u32| -> f32 {
        if i == NONE {
            return -1.0;
        }
        st.link_flux(ws, i).iter().sum()
    };
    for c_index in 0..st.clusters {
        let c = st.cluster(ws, c_index);
        let mut beams = [NONE; BEAMS];
        if c.parent == NONE {
            sum[..len].fill(0.0);
            for b in sum[..BEAMS].iter_mut() {
                *b = f32::from_bits(NONE);
            }
        } else {
            sum[..len].copy_from_slice(st.summary(ws, c.parent));
        }
        if !select {
            // Keep this cluster's own stored choice.
            for (k, b) in beams.iter_mut().enumerate() {
                *b = st.summary(ws, c_index)[k].to_bits();
            }
        } else {
            for (k, b) in beams.iter_mut().enumerate() {
                *b = sum[k].to_bits();
            }
        }
        let mut cur = c.links;
        while cur != NONE {
            let l = st.link(ws, cur);
            let index = cur;
            cur = l.next;
            if l.recv == l.emit {
                continue;
            }
            let flux = st.link_flux(ws, index);
            let weight: f32 = flux.iter().sum();
            for (t, f) in sum[BEAMS..BEAMS + nb].iter_mut().zip(flux) {
                *t += f;
            }
            for a in 0..3 {
                sum[BEAMS + nb + a] += weight * l.dir[a];
            }
            if select {
                let s_new = weight;
                let (mut weakest, mut w) = (0usize, f32::INFINITY);
                for (k, &b) in beams.iter().enumerate() {
                    let sk = strength(st, ws, b);
                    if sk < w {
                        (weakest, w) = (k, sk);
                    }
                }
                if s_new > w && s_new > 0.0 {
                    beams[weakest] = index;
                }
            }
        }
        for (k, b) in beams.iter().enumerate() {
            sum[k] = f32::from_bits(*b);
        }
        // The rest's scale: kept with the beams, chosen anew with them (by `distribute`,
        // once every cluster has its beams).
        sum[len - 1] = if select {
            0.0
        } else {
            st.summary(ws, c_index)[len - 1]
        };
        st.summary_mut(ws, c_index).copy_from_slice(&sum[..len]);
    }
}

/// Every polygon's share of what its clusters receive: the light of each beam of its
/// cluster's summary, as a plane of its orientation takes it from a cone of light (see
/// [`cone_share`]), on each side.
pub(crate) fn distribute<E: Executor>(
    st: &mut State,
    ws: &mut [u8],
    ex: &mut Fallback<'_, E>,
    select: bool,
) {
    summarize(st, ws, select);
    let nb = st.bands;
    let mut ctx = Ctx { st, ws };
    if select {
        let clusters = ctx.st.clusters as usize;
        let len = summary_floats(nb);
        run_chunks(
            ex,
            &mut ctx,
            clusters.div_ceil(CHUNK),
            CHUNK,
            |c: &Ctx<'_>, chunk, buf| {
                for (slot, i) in (chunk * CHUNK..((chunk + 1) * CHUNK).min(clusters)).enumerate() {
                    let sum = c.st.summary(c.ws, i as u32);
                    let mut beams = [NONE; BEAMS];
                    for (b, v) in beams.iter_mut().zip(&sum[..BEAMS]) {
                        *b = v.to_bits();
                    }
                    buf[slot] = super::rest_scale::rest_scale(c.st, c.ws, i as u32, &beams);
                }
            },
            |c: &mut Ctx<'_>, chunk, buf| {
                for (slot, i) in (chunk * CHUNK..((chunk + 1) * CHUNK).min(clusters)).enumerate() {
                    c.st.summary_mut(c.ws, i as u32)[len - 1] = buf[slot];
                }
            },
            &mut |_, _| {},
        );
    }
    let n = ctx.st.polygons as usize;
    run_chunks(
        ex,
        &mut ctx,
        n.div_ceil(CHUNK),
        CHUNK * 2 * nb,
        |c: &Ctx<'_>, chunk, buf| {
            buf.fill(0.0);
            for (slot, i) in (chunk * CHUNK..((chunk + 1) * CHUNK).min(n)).enumerate() {
                let o = &mut buf[slot * 2 * nb..(slot + 1) * 2 * nb];
                share(c.st, c.ws, i as u32, o);
            }
        },
        |c: &mut Ctx<'_>, chunk, buf| {
            for (slot, i) in (chunk * CHUNK..((chunk + 1) * CHUNK).min(n)).enumerate() {
                for side in 0..2 {
                    let src = &buf[slot * 2 * nb + side * nb..slot * 2 * nb + (side + 1) * nb];
                    c.st.polygon_h_mut(c.ws, i as u32, side)
                        .copy_from_slice(src);
                }
            }
        },
        &mut |_, _| {},
    );
}

/// Polygon `poly`'s irradiance from its cluster's summary, front then back (`out` holds
/// 2 x bands, added to).
fn share(st: &State, ws: &[u8], poly: u32, out: &mut [f32]) {
    let nb = st.bands;
    let rec = st.polygon(ws, poly);
    let normal = Vec3::from(rec.normal);
    let cluster = Elem(st.patch(ws, Elem(rec.root)).parent);
    if cluster.kind() != Kind::Cluster {
        return;
    }
    let sum = st.summary(ws, cluster.index());
    let mut rest = [0.0f32; 8];
    rest[..nb].copy_from_slice(&sum[BEAMS..BEAMS + nb]);
    let mut rest_dir = Vec3::new(sum[BEAMS + nb], sum[BEAMS + nb + 1], sum[BEAMS + nb + 2]);
    let add = |flux: &[f32], dir: Vec3, out: &mut [f32]| {
        let collimation = dir.length().min(1.0);
        let t = if collimation > 0.0 {
            normal.dot(dir) / dir.length()
        } else {
            0.0
        };
        let shares = [cone_share(collimation, t), cone_share(collimation, -t)];
        for (side, f) in shares.into_iter().enumerate() {
            if f > 0.0 {
                for (o, v) in out[side * nb..(side + 1) * nb].iter_mut().zip(flux) {
                    *o += f * v;
                }
            }
        }
    };
    for &b in &sum[..BEAMS] {
        let index = b.to_bits();
        if index == NONE {
            continue;
        }
        let l = st.link(ws, index);
        let flux = st.link_flux(ws, index);
        let dir = Vec3::from(l.dir);
        let weight: f32 = flux.iter().sum();
        for (r, f) in rest[..nb].iter_mut().zip(flux) {
            *r -= f;
        }
        rest_dir -= dir * weight;
        add(flux, dir, out);
    }
    let weight: f32 = rest[..nb].iter().sum();
    if weight > 0.0 {
        // 0: not chosen yet (a summary read before any selection).
        let scale = match sum[summary_floats(nb) - 1] {
            s if s > 0.0 => s,
            _ => 1.0,
        };
        for r in rest[..nb].iter_mut() {
            *r = r.max(0.0) * scale;
        }
        add(&rest[..nb], rest_dir / weight, out);
    }
}
