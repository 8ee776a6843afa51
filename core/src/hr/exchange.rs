//! Light between the closed instances of a level that block with their own polygons (see
//! `original_geometry`): which share of each one's escaping light, per direction, reaches
//! which other closed instance first. Neighbours in a canopy interpenetrate, and an
//! isotropic kernel between their boxes' centres gave a plant twice the light of its
//! neighbour beside it and too little of the light of a dense canopy around it; rays from
//! the emitter's own surfaces find what its light really meets.
//!
//! Once per level, [`RAYS`] rays leave each such instance `J` from points drawn on its
//! polygons by area, in cosine-distributed directions off the side drawn: the rays that meet
//! `J` itself again are its own business (its tables hold that light); the others are its
//! escaping light, evenly over its cross-section in every direction, as the tables assume.
//! Per direction cell `c` of a 64-direction grid, the share `H(c, P) / E(c)` of the
//! escaping rays that meet instance `P` first (before any polygon of the level) is kept.
//! Each iteration `P` then receives from `J`, per cell, `J`'s escaping power that way (its
//! tables' intensity times the cell's solid angle) times that share, as a beam from the
//! opposite direction (see [`gather`]).
//!
//! Workspace region (see [`bytes_needed`]): per instance the first of its entries (and the
//! total), then the entries (receiver << 6 | cell, share), then per instance, cell and band
//! the power it received from the others at the last gather (W).

use super::exec::{Executor, Fallback, Progress, run_chunks, run_chunks_scaled};
use super::ids::{Elem, Kind};
use super::layout::up;
use super::state::{Handed, State};
use super::vis::{Ray, Vis, WsPolygons};
use crate::limits::{MAX_BANDS, NONE};
use crate::sampling::{hash3, unit2};
use crate::tables::grid::DirectionGrid;
use crate::visibility::Visibility;
use glam::Vec3;

/// Rays per instance.
pub(crate) const RAYS: u32 = 1024;
/// Side of the direction grid (64 cells).
pub(crate) const SIDE: u32 = 8;
/// Cells of the direction grid.
pub(crate) const CELLS: usize = (SIDE * SIDE) as usize;
/// Rays per chunk of work.
const PER_CHUNK: u32 = 64;
/// A ray's result: it met its own instance again.
const INTERNAL: u32 = NONE;
/// A ray's receiver when it met no closed instance first.
const NOBODY: u32 = (1 << 26) - 1;

/// Bytes of one entry: the receiver and the cell of the light's direction of travel
/// (`u32`: receiver << 6 | cell), then how many of the emitter's escaping rays in that cell
/// land there and where on the receiver (`u32`: count << 21 | its polygon << 1 | side, or
/// count << 21 | [`NOWHERE`] for a receiver without polygons). The count over the cell's
/// escaping rays is the share of the emitter's escaping light in that cell it takes.
const ENTRY_BYTES: usize = 8;
/// Bits of an entry's second word that say where on the receiver it lands.
const AT_BITS: u32 = 21;
/// Where an entry lands on a receiver without polygons.
const NOWHERE: u32 = (1 << AT_BITS) - 1;

// A ray count fits above the landing place (RAYS rays per instance at most).
const _: () = assert!(RAYS < 1 << (32 - AT_BITS));
// Every blocking polygon's side (polygon indices below their count) fits below it.
const _: () = assert!(
    ((super::original_geometry::MAX_BLOCKING_POLYGONS as u64 - 1) << 1 | 1) < NOWHERE as u64
);

/// Byte offsets of the parts of the region for `n` instances and `bands` bands: heads,
/// entries, per instance and cell its escaping rays (their mean direction and how many,
/// 4 floats), received power, per instance and cell the power its escaping rays stand for
/// at the last gather (see [`escaping`]), per instance its mean radiosity before the last
/// gather, per instance and cell its links' light at the last gather (see
/// [`links_now_at`]), end. Where no instance `sends` (none blocks with polygons), the
/// entries, rays and escaping power take no room: 10 KB an instance, 25 MB of a forest's
/// top level of 2,303 closed branches.
fn parts(n: u32, bands: usize, sends: bool) -> [usize; 8] {
    let n = n as usize;
    let senders = if sends { n } else { 0 };
    let heads = 0;
    let entries = heads + up(4 * (n + 1));
    let cells = entries + up(ENTRY_BYTES * senders * RAYS as usize);
    let power = cells + up(16 * senders * CELLS);
    let sent = power + up(4 * n * CELLS * bands);
    let before = sent + up(4 * senders * CELLS * bands);
    let links = before + up(4 * n);
    let end = links + up(4 * n * CELLS * bands);
    [heads, entries, cells, power, sent, before, links, end]
}

/// [`parts`] of the level `st`.
fn parts_of(st: &State) -> [usize; 8] {
    parts(st.instances, st.bands, st.lay.exchange_sends)
}

/// Bytes of the region for `n` closed instances (0 without any), whether any `sends`.
pub(crate) fn bytes_needed(n: u32, bands: usize, sends: bool) -> usize {
    if n == 0 { 0 } else { parts(n, bands, sends)[7] }
}

/// Bytes of the region written: everything but the entries never reached (0 without
/// closed instances).
pub(crate) fn bytes_written(st: &State, ws: &[u8]) -> usize {
    let n = st.instances;
    if n == 0 {
        return 0;
    }
    let p = parts_of(st);
    let written: u32 = super::pool::read(ws, st.lay.exchange + p[0] + 4 * n as usize);
    p[7] - (p[2] - p[1]) + ENTRY_BYTES * written as usize
}

/// True when closed instance `i` sends its light to the others through the exchange (it
/// blocks with its own polygons), not through links.
pub(crate) fn sends(st: &State, ws: &[u8], i: u32) -> bool {
    let leaf = st.instance(ws, i);
    st.slot(ws, leaf.slot).blocking_polygons > 0
}

/// True when a link `recv <- emit` would carry light the exchange carries.
pub(crate) fn carries(st: &State, ws: &[u8], recv: Elem, emit: Elem) -> bool {
    recv.kind() == Kind::Instance && emit.kind() == Kind::Instance && sends(st, ws, emit.index())
}

pub(crate) fn grid() -> DirectionGrid {
    // Side 8 is a valid grid.
    DirectionGrid::new(SIDE).unwrap_or(DirectionGrid::ONE)
}

/// Where the ray `j` of instance `i` goes: `INTERNAL`, or its receiver (`NOBODY`) << 6 |
/// the cell of its direction; its direction; and where on the receiver it lands (its
/// polygon << 1 | the side met, `NONE` for a receiver without polygons).
fn trace<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    ray: &Ray<'_, V>,
    i: u32,
    j: u32,
) -> (u32, Vec3, u32) {
    let leaf = st.instance(ws, i);
    let Some(g) = st.original_geometry(ws, leaf.slot) else {
        return (INTERNAL, Vec3::ZERO, NONE);
    };
    let place = leaf.place();
    let h = hash3(i, j, 0xE8C4);
    let (a0, _) = unit2(hash3(h, 1, 0xA1));
    let a = (j as f32 + a0) / RAYS as f32;
    let (u, v) = unit2(hash3(h, 2, 0xA2));
    let (du, dv) = unit2(hash3(h, 3, 0xA3));
    let Some(sp) = g.sample(a.min(1.0 - f32::EPSILON), u, v) else {
        return (INTERNAL, Vec3::ZERO, NONE);
    };
    let d = super::sample::cosine_direction(sp.normal, du, dv);
    if d == Vec3::ZERO {
        return (INTERNAL, Vec3::ZERO, NONE);
    }
    let x = place.point(sp.point);
    let w = place.direction(d).normalize_or_zero();
    let end = st.beyond(x, w);
    // Its own polygons first (in its frame: the same parameter along the segment).
    let local_end = crate::tables::closed::local_point(&place, end);
    if g.first_hit_local(sp.point, local_end, sp.polygon).is_some() {
        return (INTERNAL, Vec3::ZERO, NONE);
    }
    let cell = grid().cell_of(w);
    let wall = ray.first_hit(x, end, [NONE, NONE]).map_or(1.0, |(_, t)| t);
    let to = x + (end - x) * wall;
    let met = super::blockers::first_instance(st, ws, x, to, i, hash3(h, 4, 0xA4));
    let who = met.map_or(NOBODY, |(p, _, _)| p);
    // Where on the receiver: its polygon and the side the ray meets.
    let at = match met {
        Some((p, _, q)) if q != NONE => {
            let pl = st.instance(ws, p);
            let rot = glam::Quat::from_array(pl.rotation);
            st.original_geometry(ws, pl.slot).map_or(NONE, |pg| {
                let n = rot * pg.normal(q);
                (q << 1) | u32::from(n.dot(w) > 0.0)
            })
        }
        _ => NONE,
    };
    ((who << 6) | cell, w, at)
}

struct Ctx<'a, 'v, V: ?Sized> {
    st: &'a State,
    ws: &'a mut [u8],
    vis: &'a Vis<'v, V>,
    /// The instance whose rays are being gathered: its escaping rays' directions summed
    /// and count per cell, and its hits so far (receiver and cell, where they land).
    towards: [[f32; 4]; CELLS],
    hits: heapless::Vec<u64, { RAYS as usize }>,
    written: u32,
}

/// Traces every closed instance's rays and writes the shares (see the module
/// documentation). Instances without polygons of their own send nothing here.
pub(crate) fn build<V: Visibility + ?Sized, E: Executor>(
    st: &mut State,
    ws: &mut [u8],
    vis: &Vis<'_, V>,
    ex: &mut Fallback<'_, E>,
    progress: &mut dyn Progress,
) {
    let n = st.instances;
    if n == 0 {
        return;
    }
    if !st.lay.exchange_sends {
        // None blocks with polygons: every instance's entries are empty.
        let p = parts_of(st);
        ws[st.lay.exchange + p[0]..st.lay.exchange + p[1]].fill(0);
        return;
    }
    let parts_per = RAYS / PER_CHUNK;
    let chunks = n as usize * parts_per as usize;
    let per = 5;
    let mut rays = 0u64;
    let mut ctx = Ctx {
        st,
        ws,
        vis,
        towards: [[0.0; 4]; CELLS],
        hits: heapless::Vec::new(),
        written: 0,
    };
    run_chunks(
        ex,
        &mut ctx,
        chunks,
        PER_CHUNK as usize * per,
        |c: &Ctx<'_, '_, V>, chunk, buf| {
            let i = (chunk / parts_per as usize) as u32;
            let part = (chunk % parts_per as usize) as u32;
            let ray = Ray {
                vis: c.vis,
                polys: WsPolygons { st: c.st, ws: c.ws },
            };
            let sends = sends(c.st, c.ws, i);
            for (k, o) in buf.chunks_exact_mut(per).enumerate() {
                let (r, w, at) = if sends {
                    trace(c.st, c.ws, &ray, i, part * PER_CHUNK + k as u32)
                } else {
                    (INTERNAL, Vec3::ZERO, NONE)
                };
                o[0] = f32::from_bits(r);
                if r != INTERNAL {
                    o[1..4].copy_from_slice(&w.to_array());
                    o[4] = f32::from_bits(at);
                }
            }
        },
        |c: &mut Ctx<'_, '_, V>, chunk, buf| {
            let i = (chunk / parts_per as usize) as u32;
            let part = (chunk % parts_per as usize) as u32;
            if part == 0 {
                c.towards = [[0.0; 4]; CELLS];
                c.hits.clear();
            }
            for o in buf.chunks_exact(per) {
                let r = o[0].to_bits();
                if r == INTERNAL {
                    continue;
                }
                rays += 1;
                let cell = (r & 63) as usize;
                for (t, d) in c.towards[cell].iter_mut().zip(&o[1..4]) {
                    *t += d;
                }
                c.towards[cell][3] += 1.0;
                if r >> 6 != NOBODY {
                    let _ = c.hits.push((r as u64) << 32 | o[4].to_bits() as u64);
                }
            }
            if part + 1 == parts_per {
                flush(c, i);
            }
        },
        &mut |done, total| {
            progress.report("light between closed instances", done as u64, total as u64)
        },
    );
    let written = ctx.written;
    let p = parts_of(st);
    let at = st.lay.exchange + p[0] + 4 * n as usize;
    super::pool::write(ws, at, &written);
    st.stats.rays += rays;
    st.stats.rays_by_phase.links += rays;
}

/// Writes instance `i`'s entries from its rays' keys.
fn flush<V: ?Sized>(c: &mut Ctx<'_, '_, V>, i: u32) {
    let p = parts_of(c.st);
    let base = c.st.lay.exchange;
    super::pool::write(c.ws, base + p[0] + 4 * i as usize, &c.written);
    for (cell, t) in c.towards.iter().enumerate() {
        let d = Vec3::new(t[0], t[1], t[2]).normalize_or_zero();
        let v = [d.x, d.y, d.z, t[3]];
        super::pool::write(c.ws, base + p[2] + 16 * (i as usize * CELLS + cell), &v);
    }
    c.hits.sort_unstable();
    let mut k = 0;
    while k < c.hits.len() {
        let both = c.hits[k];
        let (key, at_on) = ((both >> 32) as u32, both as u32);
        let mut m = k;
        while m < c.hits.len() && c.hits[m] == both {
            m += 1;
        }
        // How many of the cell's escaping rays land there, and where.
        let landing = if at_on == NONE { NOWHERE } else { at_on };
        let word = ((m - k) as u32) << AT_BITS | landing;
        let at = base + p[1] + ENTRY_BYTES * c.written as usize;
        super::pool::write(c.ws, at, &key);
        super::pool::write(c.ws, at + 4, &word);
        c.written += 1;
        k = m;
    }
}

/// The power (W per band) closed instance `i` received from the others at the last
/// [`gather`], per cell of the direction it came from.
fn power_at(st: &State, i: u32, cell: usize) -> usize {
    let p = parts_of(st);
    st.lay.exchange + p[3] + 4 * ((i as usize * CELLS + cell) * st.bands)
}

/// Hands every closed instance's escaping light to the instances it reaches (see the
/// module documentation), from the light they hold now: notes what each one's escaping rays
/// stand for (for [`land`]) and fills the received power of every instance by cell, which
/// [`receive`] then adds to its light.
pub(crate) fn gather<E: Executor>(st: &State, ws: &mut [u8], ex: &mut Fallback<'_, E>) {
    let n = st.instances;
    if n == 0 {
        return;
    }
    let nb = st.bands;
    let p = parts_of(st);
    let base = st.lay.exchange;
    ws[base + p[3]..base + p[5]].fill(0);
    let grid = grid();
    let mut opposite = [0u32; CELLS];
    for (c, o) in opposite.iter_mut().enumerate() {
        *o = grid.cell_of(-grid.direction(c as u32));
    }
    // Each emitter's escaping power (the tables' intensity, the costly part) in chunks on
    // the executor's threads; then, emitter after emitter, what its entries carry, so that
    // every receiver's sums are added in the same order on any number of threads.
    let per = CELLS * nb + 1;
    let mut ctx = GatherCtx { st, ws };
    run_chunks_scaled(
        ex,
        &mut ctx,
        (n as usize).div_ceil(ESCAPING_CHUNK),
        1,
        ESCAPING_CHUNK * per,
        |c: &GatherCtx<'_>, chunk, buf| {
            buf.fill(0.0);
            for (slot, j) in
                (chunk * ESCAPING_CHUNK..((chunk + 1) * ESCAPING_CHUNK).min(n as usize)).enumerate()
            {
                let (first, last) = entries_of(c.ws, &p, base, j as u32);
                if first >= last {
                    continue;
                }
                let Some(sent) = escaping(c.st, c.ws, j as u32, &p) else {
                    continue;
                };
                let out = &mut buf[slot * per..(slot + 1) * per];
                out[0] = 1.0;
                for (cell, v) in sent.iter().enumerate() {
                    out[1 + cell * nb..1 + (cell + 1) * nb].copy_from_slice(&v[..nb]);
                }
            }
        },
        |c: &mut GatherCtx<'_>, chunk, buf| {
            let (st, ws) = (c.st, &mut *c.ws);
            for (slot, j) in
                (chunk * ESCAPING_CHUNK..((chunk + 1) * ESCAPING_CHUNK).min(n as usize)).enumerate()
            {
                let out = &buf[slot * per..(slot + 1) * per];
                if out[0] == 0.0 {
                    continue;
                }
                let j = j as u32;
                let mut sent = [[0.0f32; MAX_BANDS]; CELLS];
                for (cell, v) in sent.iter_mut().enumerate() {
                    v[..nb].copy_from_slice(&out[1 + cell * nb..1 + (cell + 1) * nb]);
                    let at = sent_at(&p, base, j, cell, nb);
                    super::pool::floats_mut(ws, at, nb).copy_from_slice(&v[..nb]);
                }
                let (first, last) = entries_of(ws, &p, base, j);
                for e in first..last {
                    let Some((to, cell, _, power)) = entry(st, ws, &p, j, e, &sent) else {
                        continue;
                    };
                    let acc: &mut [f32] =
                        super::pool::floats_mut(ws, power_at(st, to, opposite[cell] as usize), nb);
                    for (a, x) in acc.iter_mut().zip(&power) {
                        *a += x;
                    }
                }
            }
        },
        &mut |_, _| {},
    );
}

/// Emitters per chunk of [`gather`]'s escaping power: two fit the executor's scratch
/// (`CHUNK` times at least `4 + 2 bands` floats) at any number of bands. A call takes the
/// executor's batch of chunks (its outputs, about 1 KB a chunk at two bands, stay small).
const ESCAPING_CHUNK: usize = 2;

/// The state shared by [`gather`]'s chunks.
struct GatherCtx<'a> {
    st: &'a State,
    ws: &'a mut [u8],
}

/// The range of emitter `j`'s entries (see [`parts`]).
fn entries_of(ws: &[u8], p: &[usize; 8], base: usize, j: u32) -> (u32, u32) {
    let at = base + p[0] + 4 * j as usize;
    (super::pool::read(ws, at), super::pool::read(ws, at + 4))
}

/// Where closed instance `j`'s escaping power in cell `cell` lies (see [`parts`]).
fn sent_at(p: &[usize; 8], base: usize, j: u32, cell: usize, bands: usize) -> usize {
    base + p[4] + 4 * ((j as usize * CELLS + cell) * bands)
}

/// Entry `e` of emitter `j` whose escaping power per cell is `sent`: its receiver, the cell
/// of the light's direction of travel, where it lands (polygon << 1 | side, or `NONE`) and
/// the power it carries (W per band). `None` for an entry of no receiver.
fn entry(
    st: &State,
    ws: &[u8],
    p: &[usize; 8],
    j: u32,
    e: u32,
    sent: &[[f32; MAX_BANDS]; CELLS],
) -> Option<(u32, usize, u32, [f32; MAX_BANDS])> {
    let at = st.lay.exchange + p[1] + ENTRY_BYTES * e as usize;
    let key: u32 = super::pool::read(ws, at);
    let word: u32 = super::pool::read(ws, at + 4);
    let on = match word & NOWHERE {
        NOWHERE => NONE,
        x => x,
    };
    let cell = (key & 63) as usize;
    let to = key >> 6;
    if to >= st.instances {
        return None;
    }
    // The share of the cell's escaping rays that land there.
    let escaped = cell_rays(st, ws, j, cell, p);
    let share = if escaped > 0.0 {
        (word >> AT_BITS) as f32 / escaped
    } else {
        0.0
    };
    let mut power = [0.0f32; MAX_BANDS];
    for (band, x) in power.iter_mut().enumerate().take(st.bands) {
        *x = sent[cell][band] * share;
    }
    Some((to, cell, on, power))
}

/// Adds to the whole light (part 1) of every closed instance whose tables keep its
/// polygons apart the light the last [`gather`]'s rays brought to the polygons they met, as
/// irradiance on the side met: their first scattering then starts where the light landed,
/// not from beams (a neighbour's light reaches leaves inside the neighbour's box, which light
/// from beyond the box would not). Straight into the whole light, by the change of each
/// emitter's escaping power since it was last landed (`Handed::Sent`), so that nothing per
/// polygon is kept apart for it.
pub(crate) fn land(st: &State, ws: &mut [u8]) {
    let n = st.instances;
    if n == 0 {
        return;
    }
    let nb = st.bands;
    let p = parts_of(st);
    let base = st.lay.exchange;
    for j in 0..n {
        let (first, last) = entries_of(ws, &p, base, j);
        if first >= last {
            continue;
        }
        // The change of its escaping power since it was last landed.
        let mut sent = [[0.0f32; MAX_BANDS]; CELLS];
        let mut now = [0.0f32; CELLS * MAX_BANDS];
        for (cell, v) in sent.iter_mut().enumerate() {
            let x = super::pool::floats(ws, sent_at(&p, base, j, cell, nb), nb);
            let had = &st.handed(ws, j, Handed::Sent)[cell * nb..(cell + 1) * nb];
            for (band, o) in v.iter_mut().enumerate().take(nb) {
                *o = x[band] - had[band];
                now[cell * nb + band] = x[band];
            }
        }
        st.handed_mut(ws, j, Handed::Sent)
            .copy_from_slice(&now[..CELLS * nb]);
        if sent.iter().all(|v| v[..nb].iter().all(|&x| x == 0.0)) {
            continue;
        }
        for e in first..last {
            let Some((to, _, on, power)) = entry(st, ws, &p, j, e, &sent) else {
                continue;
            };
            if on == NONE || !keeps_polygons(st, ws, to) {
                continue;
            }
            let (q, side) = ((on >> 1) as usize, (on & 1) as usize);
            let leaf = st.instance(ws, to);
            let (at, len) = st.received_at(ws, to);
            let (area, start) = {
                let placed = st.placed(ws, to);
                let Ok(r) = crate::tables::closed::Received::over(
                    &placed,
                    super::pool::floats(ws, at, len),
                ) else {
                    continue;
                };
                match placed.tables().single() {
                    Some(single) if q < single.polygons() => (
                        single.polygon(q, 0).1 * leaf.scale * leaf.scale,
                        r.first_range().start,
                    ),
                    _ => (0.0, 0),
                }
            };
            if area > 0.0 {
                let v = super::pool::floats_mut(ws, at, len);
                let first = start + (q * 2 + side) * nb;
                for (band, x) in power.iter().enumerate().take(nb) {
                    let e = x / area;
                    if e.is_finite() {
                        v[first + band] += e;
                    }
                }
            }
        }
    }
}

/// Closed instance `i`'s mean radiosity before the last gather (see
/// `instance_gather::gather_instances`), kept here and read back.
pub(crate) fn set_before(st: &State, ws: &mut [u8], i: u32, v: f32) {
    let p = parts_of(st);
    super::pool::write(ws, st.lay.exchange + p[5] + 4 * i as usize, &v);
}

/// What [`set_before`] kept for closed instance `i`.
pub(crate) fn before(st: &State, ws: &[u8], i: u32) -> f32 {
    let p = parts_of(st);
    super::pool::read(ws, st.lay.exchange + p[5] + 4 * i as usize)
}

/// Closed instance `j`'s escaping rays in cell `cell` (see [`build`]).
fn cell_rays(st: &State, ws: &[u8], j: u32, cell: usize, p: &[usize; 8]) -> f32 {
    let v: [f32; 4] = super::pool::read(
        ws,
        st.lay.exchange + p[2] + 16 * (j as usize * CELLS + cell),
    );
    v[3]
}

/// True when closed instance `i`'s tables keep its polygons apart, in the order of its own
/// polygons (the exchange hands it its light polygon by polygon).
fn keeps_polygons(st: &State, ws: &[u8], i: u32) -> bool {
    st.slot(ws, st.instance(ws, i).slot).polygons_kept != 0
}

/// The power (W per band) closed instance `j`'s escaping rays of each cell stand for, from
/// the light it holds now: its radiance their way (intensity over cross-section) times the
/// etendue of as many rays drawn over its sides' area (each ray pi A / RAYS). The cell's
/// solid angle times the intensity at its centre lost the light of cells across a flat
/// emitter's horizon. `None` without polygons of its own.
fn escaping(st: &State, ws: &[u8], j: u32, p: &[usize; 8]) -> Option<[[f32; MAX_BANDS]; CELLS]> {
    let nb = st.bands;
    let base = st.lay.exchange;
    let placed = st.placed(ws, j);
    let r = crate::tables::closed::Received::over(&placed, st.received(ws, j)).ok()?;
    let leaf = st.instance(ws, j);
    let g = st.original_geometry(ws, leaf.slot)?;
    let sides_area = g.sides_area() * leaf.scale * leaf.scale;
    let mut sent = [[0.0f32; MAX_BANDS]; CELLS];
    for (cell, s) in sent.iter_mut().enumerate() {
        let v: [f32; 4] = super::pool::read(ws, base + p[2] + 16 * (j as usize * CELLS + cell));
        let d = Vec3::new(v[0], v[1], v[2]);
        if v[3] <= 0.0 || d == Vec3::ZERO {
            continue;
        }
        let shadow = placed.shadow(d);
        if shadow <= 0.0 {
            continue;
        }
        r.intensity_all(&placed, d, &mut s[..nb]);
        for x in s.iter_mut().take(nb) {
            *x = x.max(0.0) / shadow * core::f32::consts::PI * sides_area * v[3] / RAYS as f32;
        }
    }
    Some(sent)
}

/// Adds to closed instance `i`'s whole light what the last [`gather`] handed it, beam by
/// beam (each cell's power over its cross-section that way), by the change since the
/// gather before (`Handed::Exchange`); where its tables keep its polygons apart, without
/// their first scattering, which [`land`] adds from where the rays landed.
pub(crate) fn receive(st: &State, ws: &mut [u8], i: u32) {
    let (now, first) = received_now(st, ws, i);
    super::instance_light::hand(st, ws, i, Handed::Exchange, &now, first);
}

/// What [`receive`] hands closed instance `i`: the beams of the last [`gather`] per cell
/// (W/m^2 per band over its cross-section that way) and whether they bring their first
/// scattering (not where [`land`] adds it).
pub(crate) fn received_now(st: &State, ws: &[u8], i: u32) -> ([[f32; MAX_BANDS]; CELLS], bool) {
    let nb = st.bands;
    let grid = grid();
    let landed = keeps_polygons(st, ws, i);
    let placed = st.placed(ws, i);
    let mut now = [[0.0f32; MAX_BANDS]; CELLS];
    for (cell, e) in now.iter_mut().enumerate() {
        let power = super::pool::floats(ws, power_at(st, i, cell), nb);
        if power.iter().all(|&v| v <= 0.0) {
            continue;
        }
        let s = placed.shadow(grid.direction(cell as u32));
        if s > 0.0 {
            for (o, v) in e.iter_mut().zip(power) {
                *o = v.max(0.0) / s;
            }
        }
    }
    (now, !landed)
}

/// Where closed instance `i`'s links' light of the last gather lies: the byte offset of
/// its `CELLS * bands` floats (see `instance_gather`).
pub(crate) fn links_now_at(st: &State, i: u32) -> usize {
    let p = parts_of(st);
    st.lay.exchange + p[6] + 4 * (i as usize * CELLS * st.bands)
}

/// The beams (direction towards the emitters, flux density per band, W/m^2) closed
/// instance `i` received from the others at the last [`gather`], through `f`.
pub(crate) fn beams(st: &State, ws: &[u8], i: u32, mut f: impl FnMut(Vec3, &[f32])) {
    if st.instances == 0 {
        return;
    }
    let nb = st.bands;
    let grid = grid();
    let placed = st.placed(ws, i);
    for cell in 0..CELLS {
        let power = super::pool::floats(ws, power_at(st, i, cell), nb);
        if power.iter().all(|&v| v <= 0.0) {
            continue;
        }
        let d = grid.direction(cell as u32);
        let s = placed.shadow(d);
        if s <= 0.0 {
            continue;
        }
        let mut e = [0.0f32; MAX_BANDS];
        for (o, v) in e.iter_mut().zip(power) {
            *o = v / s;
        }
        f(d, &e[..nb]);
    }
}
