//! Creating, evaluating and refining links.
//!
//! A refinement pass walks every receiver in order and every link it receives; a link whose
//! transfer (emitter radiosity x coefficient x receiver area) exceeds `epsilon` times the
//! emitted power is replaced by links to the children of the larger side (clusters open into
//! their children; patches split into four). New links wait as pending until the next
//! evaluation, which computes them in fixed chunks (possibly on many threads) and applies the
//! results in order. When the workspace cannot hold the new links or patches, the link stays
//! and the run is marked as limited by its budget.

use super::exec::{Executor, Fallback, Progress};
use super::ids::{Elem, Kind};
use super::pending::evaluate_pending;
use super::records::*;
use super::state::{Shape, State};
use super::vis::Vis;
use crate::limits::NONE;
use crate::sampling::subdivide;
use crate::visibility::Visibility;
use glam::Vec3;

/// Most children any element splits into (clusters keep at most this many after grouping).
pub(crate) const MAX_KIDS: usize = 16;

/// Adds a link received by `recv` from `emit` at the head of `recv`'s list.
pub(crate) fn add_link(
    st: &mut State,
    ws: &mut [u8],
    recv: Elem,
    emit: Elem,
    flags: u32,
) -> Option<u32> {
    let mut blocks = st.blocks;
    let i = st.links.alloc(ws, &mut blocks)?;
    st.blocks = blocks;
    let head = st.links_head(ws, recv);
    mark_stale(st, ws, recv);
    st.set_link(
        ws,
        i,
        &Link {
            recv: recv.0,
            emit: emit.0,
            next: head,
            flags,
            k_open: 0.0,
            k_seen: 0.0,
            dir: [0.0; 3],
            spread: 0.0,
            witness: [NONE; 2],
        },
    );
    st.link_k_mut(ws, i).fill(0.0);
    st.set_links_head(ws, recv, i);
    if flags & PENDING != 0 {
        st.pending = (st.pending.0.min(i), st.pending.1.max(i + 1));
        st.pending_links += 1;
    }
    let t = &mut st.touched[kind_slot(recv.kind())];
    *t = (t.0.min(recv.index()), t.1.max(recv.index() + 1));
    st.stats.peak_links = st.stats.peak_links.max(st.links.live() as u64);
    Some(i)
}

fn free_link(st: &mut State, ws: &mut [u8], i: u32) {
    let mut l = st.link(ws, i);
    l.flags = FREE;
    st.set_link(ws, i, &l);
    let blocks = st.blocks;
    st.links.release(ws, &blocks, i);
}

/// Refinement passes until a pass changes nothing; true if any link was refined.
pub(crate) fn refine_until_stable<V: Visibility + ?Sized, E: Executor, P: Progress>(
    st: &mut State,
    ws: &mut [u8],
    vis: &Vis<'_, V>,
    ex: &mut Fallback<'_, E>,
    progress: &mut P,
) -> bool {
    let mut any = false;
    loop {
        if progress.cancelled() {
            return any;
        }
        st.stats.refinement_passes += 1;
        progress.report("refining (links)", st.links.live() as u64, 0);
        let changed = refine_pass(st, ws) | refine_shadows(st, ws);
        super::direct::prepare_pending(st, ws, vis, ex, progress);
        evaluate_pending(st, ws, vis, ex, progress);
        st.stats.peak_bytes = st.stats.peak_bytes.max(st.bytes_in_use() as u64);
        if !changed {
            return any;
        }
        any = true;
    }
}

/// Forgets which links were examined, so that the next pass looks at them again with new
/// radiosities.
pub(crate) fn clear_examined(st: &mut State, ws: &mut [u8]) {
    st.touched = [(0, u32::MAX); 4];
    st.shadow_checked = [0; 2];
    for i in 0..st.links.len {
        let mut l = st.link(ws, i);
        if l.flags & FREE == 0 && l.flags & EXAMINED != 0 {
            l.flags &= !EXAMINED;
            st.set_link(ws, i, &l);
        }
    }
}

/// The slot of a receiver kind in [`State::touched`].
fn kind_slot(k: Kind) -> usize {
    match k {
        Kind::Patch1 => 1,
        Kind::Patch2 => 2,
        Kind::Instance => 3,
        _ => 0,
    }
}

/// Which side of a link must open before the link can carry light: a cluster that holds
/// closed instances (its kernels see only its polygons), the receiver first.
/// `Some(true)` the receiver, `Some(false)` the emitter.
pub(crate) fn must_open(st: &State, ws: &[u8], recv: Elem, emit: Elem) -> Option<bool> {
    let holds = |e: Elem| e.kind() == Kind::Cluster && st.cluster(ws, e.index()).instances > 0;
    if holds(recv) {
        Some(true)
    } else if holds(emit) {
        Some(false)
    } else {
        None
    }
}

/// Largest radiosity of an element over its sides and bands (W/m^2); of a cluster, the
/// largest of its polygons': a cluster's link carries a mean radiosity, which is as wrong as
/// the cluster is uneven (a ceiling of dark tiles with a few lamps in it lit a plant below
/// with a third of their light, the mean of lamps and tiles being far below the threshold).
fn b_max(st: &State, ws: &[u8], e: Elem) -> f32 {
    if e.kind() == Kind::Cluster {
        return st.cluster(ws, e.index()).peak;
    }
    if e.kind() == Kind::Instance {
        // The radiosity its links carry on average: what it scatters over its reference
        // area (see `instance_kernel`).
        return super::instance_kernel::mean_radiosity(st, ws, e.index());
    }
    let mut m = 0.0f32;
    for side in 0..2 {
        if let Some(b) = st.b(ws, e, side) {
            m = b.iter().copied().fold(m, f32::max);
        }
    }
    m
}

/// Area through which an element receives (m^2): a patch's area; for a cluster, the mean
/// projected area of its surfaces, at most that of its box.
fn receiving_area(shape: &Shape) -> f32 {
    match *shape {
        Shape::Patch { area, .. } => area,
        Shape::Cluster { min, max, area } => {
            let d = max - min;
            let box_mean = 0.5 * (d.x * d.y + d.y * d.z + d.x * d.z);
            (0.5 * area).min(box_mean.max(0.0))
        }
        // Its mean cross-section.
        Shape::Instance { area_ref, .. } => 0.25 * area_ref,
        Shape::Source { .. } => 0.0,
    }
}

/// Size of an element for choosing which side of a link to split (m).
fn radius(shape: &Shape) -> f32 {
    match *shape {
        Shape::Patch { area, .. } => libm::sqrtf(area),
        Shape::Cluster { min, max, .. } | Shape::Instance { min, max, .. } => {
            0.5 * (max - min).length()
        }
        Shape::Source { .. } => 0.0,
    }
}

fn can_split(st: &State, ws: &[u8], e: Elem) -> bool {
    match e.kind() {
        Kind::Cluster => st.cluster(ws, e.index()).child_count > 0,
        // A closed instance opens in the next level, not in this one.
        Kind::Source | Kind::Instance => false,
        _ => {
            let p = st.patch(ws, e);
            p.first_child != NONE
                || (p.depth() < st.settings.max_depth && p.area * 0.25 >= st.min_area)
        }
    }
}

/// The children an element splits into (subdividing a patch if it has none yet); None when
/// the workspace cannot hold them.
fn children(st: &mut State, ws: &mut [u8], e: Elem, out: &mut [Elem; MAX_KIDS]) -> Option<usize> {
    match e.kind() {
        Kind::Cluster => {
            let c = st.cluster(ws, e.index());
            let mut n = 0;
            for k in 0..c.child_count.min(MAX_KIDS as u32) {
                let child = st.child(ws, c.children + k);
                if super::sample::area(st, ws, child) > 0.0 {
                    out[n] = child;
                    n += 1;
                }
            }
            Some(n)
        }
        Kind::Source | Kind::Instance => Some(0),
        k => {
            let p = st.patch(ws, e);
            if p.first_child == NONE {
                let pool = if k == Kind::Patch2 { 1 } else { 0 };
                if !st.patches[pool].fits(&st.blocks, 4) {
                    return None;
                }
                subdivide_patch(st, ws, e, &p, pool)?;
            }
            let first = st.patch(ws, e).first_child;
            for (j, o) in out.iter_mut().enumerate().take(4) {
                *o = Elem::new(k, first + j as u32);
            }
            Some(4)
        }
    }
}

fn subdivide_patch(st: &mut State, ws: &mut [u8], e: Elem, p: &Patch, pool: usize) -> Option<()> {
    let mut corners = [Vec3::ZERO; 4];
    for (c, src) in corners.iter_mut().zip(p.corners) {
        *c = src.into();
    }
    let n = p.corner_count();
    let mut kids = [[Vec3::ZERO; 4]; 4];
    subdivide(&corners[..n], &mut kids);
    let mut blocks = st.blocks;
    let first = st.patches[pool].alloc_run(ws, &mut blocks, 4)?;
    st.blocks = blocks;
    let kind = e.kind();
    let sides = State::sides(e);
    let mut parent_b = [[0.0f32; 8]; 2];
    for (side, pb) in parent_b.iter_mut().enumerate().take(sides) {
        if let Some(b) = st.b(ws, e, side) {
            pb[..b.len()].copy_from_slice(b);
        }
    }
    for (j, kid) in kids.iter().enumerate() {
        let child = Elem::new(kind, first + j as u32);
        let shape = crate::geometry::polygon_shape(&kid[..n])
            .map(|s| s.area)
            .unwrap_or(p.area * 0.25);
        let mut c = [[0.0f32; 3]; 4];
        for (d, src) in c.iter_mut().zip(kid) {
            *d = src.to_array();
        }
        let rec = Patch {
            corners: c,
            parent: e.0,
            first_child: NONE,
            poly: p.poly,
            links: NONE,
            area: shape,
            shape: n as u32 | ((p.depth() + 1) << 8) | STALE | UNPREPARED,
            closure: [0.0; 2],
            exposed: p.exposed,
            shadow: 0.0,
            gather: [0; 2],
        };
        st.set_patch(ws, child, &rec);
        for (side, pb) in parent_b.iter().enumerate().take(sides) {
            let nb = st.bands;
            st.b_mut(ws, child, side).copy_from_slice(&pb[..nb]);
            st.h_mut(ws, child, side).fill(0.0);
            if let Some(d) = st.direct_mut(ws, child, side) {
                d.fill(0.0);
            }
            if let Some(d) = st.linked_mut(ws, child, side) {
                d.fill(0.0);
            }
        }
    }
    let mut q = *p;
    q.first_child = first;
    st.set_patch(ws, e, &q);
    Some(())
}

/// Which side of a link to split: `Some(true)` the receiver, `Some(false)` the emitter.
fn choose(st: &State, ws: &[u8], recv: Elem, emit: Elem, rs: &Shape, es: &Shape) -> Option<bool> {
    let (can_r, can_e) = (can_split(st, ws, recv), can_split(st, ws, emit));
    let (rr, re) = (radius(rs), radius(es));
    let emitter_refined = emit.is_patch() && st.patch(ws, emit).first_child != NONE;
    let prefer_emitter = match (recv.kind(), emit.kind()) {
        (_, Kind::Source) => false,
        // A closed instance does not split: the other side does.
        (Kind::Instance, _) => true,
        (_, Kind::Instance) => false,
        // Clusters open before any patch splits: their isotropic kernel ignores orientation
        // (a lamp facing the floor would light it four times too weakly).
        (Kind::Cluster, Kind::Cluster) => re > rr,
        (Kind::Cluster, _) => false,
        (_, Kind::Cluster) => true,
        // Between patches the exact form factor already integrates over the emitter: split
        // it only when its radiosity is resolved finer (it has children) and it is larger.
        _ => emitter_refined && re >= rr,
    };
    match (prefer_emitter, can_r, can_e) {
        (true, _, true) => Some(false),
        (_, true, _) => Some(true),
        (false, false, true) => Some(false),
        _ => None,
    }
}

/// How much further than far ones links with a cluster close by are refined (a fraction of
/// the threshold).
const NEAR_CLUSTER: f32 = 0.1;

/// Whether and where to refine link `i` (receiver `recv` <- `emit`): `Some(true)` split the
/// receiver, `Some(false)` the emitter, `None` keep it.
///
/// A link whose transfer (emitter radiosity x coefficient x receiving area, the open
/// coefficient where it is partly hidden) is below `threshold` is kept. Links with a cluster
/// on either side are refined above it (their isotropic and averaged parts are as wrong as
/// the transfer is large). Between patches the exact form factor already integrates over the
/// emitter, so a far link is refined only where constancy is wrong: the coefficient varies
/// over the receiver (its spread, visibility included), or the emitter's radiosity varies
/// over the emitter (its children differ) while the receiver sees only part of it; near
/// links (within twice their sizes) always, as a few quadrature points can miss a peak.
#[allow(clippy::too_many_arguments)]
fn decide(
    st: &mut State,
    ws: &mut [u8],
    recv: Elem,
    emit: Elem,
    l: &Link,
    rs: &Shape,
    es: &Shape,
    threshold: f32,
) -> Option<bool> {
    // Only what the refinement's own samples saw (see `eval::evaluate`).
    let k = l.k_seen;
    let k_eff = if l.flags & PARTIAL != 0 { l.k_open } else { k };
    let b = b_max(st, ws, emit);
    let area = receiving_area(rs);
    let transfer = b * k_eff * area;
    if transfer <= threshold * NEAR_CLUSTER {
        return None;
    }
    let (rr, re) = (radius(rs), radius(es));
    let gap =
        (super::oriented::centre(st, ws, recv) - super::oriented::centre(st, ws, emit)).length();
    let near = gap < 2.0 * (rr + re);
    if !(recv.is_patch() && emit.is_patch()) {
        // A cluster stands in for its parts as if they were all alike: close by, that is
        // wrong by about the whole transfer (a soil cluster under a plant), so such links
        // are refined ten times further than far ones.
        if transfer <= threshold && !near {
            return None;
        }
        return choose(st, ws, recv, emit, rs, es);
    }
    if transfer <= threshold {
        return None;
    }
    // A receiver with buried points is seen only in part: refine it like a shadow edge.
    let buried = recv.is_patch() && (0..4).any(|q| st.patch(ws, recv).buried(q));
    // Partly hidden: a few rays per point can miss what shows; the hidden part is uncertain.
    let hidden = if l.flags & PARTIAL != 0 {
        (l.k_open - k).max(0.0)
    } else {
        0.0
    };
    let e_recv = if buried {
        b * k_eff * area
    } else {
        b * (l.spread + hidden) * area
    };
    let e_emit = k * b_spread(st, ws, emit) * area;
    if !near && e_recv.max(e_emit) <= threshold {
        return None;
    }
    let (can_r, can_e) = (can_split(st, ws, recv), can_split(st, ws, emit));
    if e_emit > e_recv && can_e {
        Some(false)
    } else if near {
        // Close by, the emitter's radiosity may vary where the receiver sees it most: split
        // the larger of the two.
        if (re > rr && can_e) || !can_r {
            can_e.then_some(false)
        } else {
            Some(true)
        }
    } else if can_r {
        Some(true)
    } else if can_e {
        Some(false)
    } else {
        None
    }
}

/// How much an emitter patch's radiosity varies over its children (W/m^2, the largest band
/// and side; 0 for a leaf).
fn b_spread(st: &State, ws: &[u8], e: Elem) -> f32 {
    let p = st.patch(ws, e);
    if p.first_child == NONE {
        return 0.0;
    }
    let mut spread = 0.0f32;
    for side in 0..State::sides(e) {
        for band in 0..st.bands {
            let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
            for j in 0..4 {
                let child = Elem::new(e.kind(), p.first_child + j);
                if st.patch(ws, child).exposed <= 0.0 {
                    continue;
                }
                if let Some(b) = st.b(ws, child, side) {
                    lo = lo.min(b[band]);
                    hi = hi.max(b[band]);
                }
            }
            if hi >= lo {
                spread = spread.max(hi - lo);
            }
        }
    }
    spread
}

/// One pass over every receiver's links. Returns true if any link was split.
fn refine_pass(st: &mut State, ws: &mut [u8]) -> bool {
    let threshold = st.settings.epsilon * st.power.max(st.unit_power);
    let mut changed = false;
    // The receivers present when the pass starts (patches created during the pass only hold
    // pending links).
    let counts = [
        st.clusters,
        st.patches[0].len,
        st.patches[1].len,
        st.instances,
    ];
    let kinds = [Kind::Cluster, Kind::Patch1, Kind::Patch2, Kind::Instance];
    // Only receivers that got links since the last pass (or since examination was cleared)
    // hold links left to examine; links added during this pass are for the next.
    let touched = st.touched;
    st.touched = [(u32::MAX, 0); 4];
    for ((kind, count), (lo, hi)) in kinds.into_iter().zip(counts).zip(touched) {
        for index in lo..hi.min(count) {
            let recv = Elem::new(kind, index);
            let mut prev = NONE;
            let mut cur = st.links_head(ws, recv);
            if cur == NONE {
                continue;
            }
            // The receiver's shape does not change while its links are refined (splitting
            // it only adds children).
            let rs = st.shape(ws, recv);
            while cur != NONE {
                let l = st.link(ws, cur);
                let next = l.next;
                // New links go to the head of their receiver's list, and every link a pass
                // walks ends examined or removed: past the first examined link, all are.
                if l.flags & EXAMINED != 0 {
                    break;
                }
                if l.flags & PENDING != 0 {
                    prev = cur;
                    cur = next;
                    continue;
                }
                let emit = Elem(l.emit);
                let self_link = l.recv == l.emit;
                let es = st.shape(ws, emit);
                // No exchange seen. Between patches the open coefficient is exact at the
                // quadrature points (facing away, coplanar): drop the link. A cluster is seen
                // through a few sample points, which may all miss what faces the emitter (a
                // room sampled once on its ceiling, behind the lamp, lost the lamp's light):
                // unless the emitter's plane hides the whole cluster, split it and look
                // closer.
                // A link that must open first carries nothing yet (see `must_open`).
                let opening = must_open(st, ws, recv, emit);
                let dark = !self_link && opening.is_none() && l.k_open <= 0.0;
                // Only the exact open coefficient of a patch emitter proves a patch receiver
                // dark; a cluster emitter's is sampled, and such a link stays (its light is
                // estimated apart, see `eval::evaluate`).
                let certain = recv.is_patch() && emit.is_patch();
                if dark
                    && (certain
                        || super::reach::hidden_behind(&rs, &es)
                        || !can_split(st, ws, recv))
                {
                    unlink(st, ws, recv, prev, cur, next);
                    free_link(st, ws, cur);
                    cur = next;
                    continue;
                }
                let split = if self_link {
                    Some(split_self(st, ws, recv))
                } else if let Some(on_recv) = opening {
                    Some(split_link(st, ws, recv, emit, on_recv))
                } else if dark && !recv.is_patch() {
                    Some(split_link(st, ws, recv, emit, true))
                } else {
                    decide(st, ws, recv, emit, &l, &rs, &es, threshold)
                        .map(|on_recv| split_link(st, ws, recv, emit, on_recv))
                };
                match split {
                    Some(Some(added)) => {
                        // The link is replaced: unlink it (new links for this receiver went to
                        // the head of its list).
                        let p = if prev == NONE {
                            find_prev(st, ws, recv, cur)
                        } else {
                            prev
                        };
                        unlink(st, ws, recv, p, cur, next);
                        free_link(st, ws, cur);
                        let _ = added;
                        changed = true;
                        if prev == NONE {
                            prev = p;
                        }
                    }
                    Some(None) => {
                        st.stats.budget_limited = true;
                        mark_examined(st, ws, cur);
                        prev = cur;
                    }
                    None => {
                        mark_examined(st, ws, cur);
                        prev = cur;
                    }
                }
                cur = next;
            }
        }
    }
    changed
}

/// Subdivides every leaf patch across which the direct light of suns varies by more than
/// epsilon allows (a shadow edge crosses it; see `direct`). Returns true if any was split.
fn refine_shadows(st: &mut State, ws: &mut [u8]) -> bool {
    if st.suns == 0 {
        return false;
    }
    let threshold = st.settings.epsilon * st.power.max(st.unit_power);
    let mut changed = false;
    for (kind, pool) in [(Kind::Patch1, 0usize), (Kind::Patch2, 1)] {
        // Within a round a checked patch's answer does not change (its shadow measure, the
        // threshold and whether it can split are fixed): only patches prepared since the
        // last pass are new to it.
        let count = st.prepared[pool].min(st.patches[pool].len);
        let first = st.shadow_checked[pool].min(count);
        st.shadow_checked[pool] = count;
        for i in first..count {
            let e = Elem::new(kind, i);
            let p = st.patch(ws, e);
            if p.first_child != NONE || p.unprepared() || p.shadow <= threshold {
                continue;
            }
            // Only what the surface reflects or transmits of it shows.
            let m = st.material(ws, st.polygon(ws, p.poly).material);
            let albedo = (0..st.bands)
                .map(|b| (m.rho[0][b] + m.tau[b]).max(m.rho[1][b] + m.tau[b]))
                .fold(0.0f32, f32::max);
            if p.shadow * albedo <= threshold || !can_split(st, ws, e) {
                continue;
            }
            if !st.patches[pool].fits(&st.blocks, 4) {
                st.stats.budget_limited = true;
                continue;
            }
            if subdivide_patch(st, ws, e, &p, pool).is_some() {
                changed = true;
            } else {
                st.stats.budget_limited = true;
            }
        }
    }
    changed
}

/// Notes that a patch's received links changed: its sub-patches' closure is out of date.
fn mark_stale(st: &State, ws: &mut [u8], e: Elem) {
    if e.is_patch() {
        let mut p = st.patch(ws, e);
        if !p.stale() {
            p.shape |= STALE;
            st.set_patch(ws, e, &p);
        }
    }
}

fn mark_examined(st: &mut State, ws: &mut [u8], i: u32) {
    let mut l = st.link(ws, i);
    l.flags |= EXAMINED;
    st.set_link(ws, i, &l);
}

/// The link before `target` in `recv`'s list (NONE if it is the head).
fn find_prev(st: &State, ws: &[u8], recv: Elem, target: u32) -> u32 {
    let mut prev = NONE;
    let mut cur = st.links_head(ws, recv);
    while cur != NONE && cur != target {
        prev = cur;
        cur = st.link(ws, cur).next;
    }
    prev
}

fn unlink(st: &mut State, ws: &mut [u8], recv: Elem, prev: u32, _cur: u32, next: u32) {
    mark_stale(st, ws, recv);
    if prev == NONE {
        st.set_links_head(ws, recv, next);
    } else {
        let mut p = st.link(ws, prev);
        p.next = next;
        st.set_link(ws, prev, &p);
    }
}

/// Replaces a cluster's self-link by links between every pair of its children (and
/// self-links on child clusters). None when the workspace cannot hold them.
fn split_self(st: &mut State, ws: &mut [u8], x: Elem) -> Option<usize> {
    let mut kids = [Elem::NONE; MAX_KIDS];
    let n = children(st, ws, x, &mut kids)?;
    let need = (n * n) as u32;
    if !st.links.fits(&st.blocks, need) {
        return None;
    }
    let mut added = 0;
    for &a in &kids[..n] {
        for &b in &kids[..n] {
            if a == b && a.kind() != Kind::Cluster {
                continue;
            }
            if a == b {
                add_link(st, ws, a, b, 0)?;
                added += 1;
            } else if must_open(st, ws, a, b).is_some() {
                added += link_pair(st, ws, a, b)?;
            } else if !super::exchange::carries(st, ws, a, b) {
                add_link(st, ws, a, b, PENDING)?;
                added += 1;
            }
        }
    }
    Some(added)
}

/// Replaces link recv <- emit by links from the children of one side.
fn split_link(
    st: &mut State,
    ws: &mut [u8],
    recv: Elem,
    emit: Elem,
    on_recv: bool,
) -> Option<usize> {
    let mut kids = [Elem::NONE; MAX_KIDS];
    let side = if on_recv { recv } else { emit };
    if !st.links.fits(&st.blocks, MAX_KIDS as u32) {
        return None;
    }
    let n = children(st, ws, side, &mut kids)?;
    for &k in &kids[..n] {
        let (r, e) = if on_recv { (k, emit) } else { (recv, k) };
        link_pair(st, ws, r, e)?;
    }
    Some(n)
}

/// Links `recv <- emit` for evaluation and returns how many links that made: none where
/// the exchange carries that light (between closed instances) or nothing can pass (see
/// [`unreachable`]); a pair that must open before it can carry light (see [`must_open`])
/// is opened at once, down to pairs that can, so that links only to be split again are
/// never made (between the clusters that hold a canopy's 2,400 closed instances they were
/// 93% of its top level's links at their peak: 495,407 made for 35,271 kept).
fn link_pair(st: &mut State, ws: &mut [u8], recv: Elem, emit: Elem) -> Option<usize> {
    if super::exchange::carries(st, ws, recv, emit) || super::reach::unreachable(st, ws, recv, emit)
    {
        return Some(0);
    }
    if let Some(on_recv) = must_open(st, ws, recv, emit) {
        let before = st.links.live();
        split_link(st, ws, recv, emit, on_recv)?;
        return Some((st.links.live() - before) as usize);
    }
    add_link(st, ws, recv, emit, PENDING)?;
    Some(1)
}
