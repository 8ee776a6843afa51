//! What every new patch learns once, from rays, before any link is evaluated on it: which of
//! its quadrature points are buried inside closed objects, and the direct light of suns and
//! sky on each side.
//!
//! * **Buried points.** A point whose rays all meet the back of one-sided polygons lies
//!   inside a closed object (a floor under a box, a ceiling behind a lamp): it sees nothing
//!   and nothing sees it. Such points are left out of the patch's irradiance and the patch
//!   counts only its exposed area when its parent averages radiosity, so a floor patch that
//!   straddles a box's footprint gives the box's faces the radiosity of the part they see.
//! * **Direct light** does not go through links: every patch integrates its own visibility
//!   of each sun over its area, on a stratified grid whose cells are about the size of the
//!   scene's typical polygon (the shadows that cross it are cast by polygons), refined
//!   adaptively where the samples of a cell disagree (a shadow edge crosses it). Sky
//!   directions, each weak, are sampled jointly: every sample takes one direction by
//!   importance (irradiance times cosine), stratified over the patch. The measure of how
//!   unevenly a patch is lit drives its subdivision at shadow edges (see `refine`).
//!
//! Every sample comes from a hash of the patch and the sample number, so results never
//! depend on the thread count.

use super::exec::{Executor, Fallback, Progress, run_chunks_scaled};
use super::ids::{Elem, Kind};
use super::layout::{CHUNK, FINE_CHUNK};
use super::records::*;
use super::sample::{coprime_stride, cosine_direction, jacobian, mean_jacobian};
use super::state::State;
use super::vis::{Ray, Vis, WsPolygons};
use crate::limits::NONE;
use crate::sampling::{MAX_QUADRATURE, hash3, point_on, quadrature, unit2};
use crate::visibility::Visibility;
use glam::Vec3;

/// Rays per quadrature point for the buried test (stops at the first that proves the point
/// exposed).
const BURIED_RAYS: u32 = 8;
/// Points along each side of the grid that measures the exposed part of a partly buried
/// patch.
const EXPOSURE_GRID: u32 = 4;
/// Extra levels of adaptive subdivision of a grid cell for a sun.
const SUN_DEPTH: u32 = 2;
/// Most grid cells along a side of a patch.
const MAX_CELLS: u32 = 16;

/// Computes exposure and direct light for every unprepared patch.
pub(crate) fn prepare_pending<V: Visibility + ?Sized, E: Executor>(
    st: &mut State,
    ws: &mut [u8],
    vis: &Vis<'_, V>,
    ex: &mut Fallback<'_, E>,
    progress: &mut dyn Progress,
) {
    let nb = st.bands;
    let out = st.lay.strides.prepare_out();
    // Both pools under one phase: the count runs on over them.
    let new = |st: &State, pool: usize| {
        let len = st.patches[pool].len as u64;
        len - (st.prepared[pool] as u64).min(len)
    };
    let all = new(st, 0) + new(st, 1);
    let mut offset = 0u64;
    for (pool, kind) in [Kind::Patch1, Kind::Patch2].into_iter().enumerate() {
        // Only the patches made since the last call (they come at the end of the pool).
        let n = st.pool(kind).len as usize;
        let first = (st.prepared[pool] as usize).min(n);
        st.prepared[pool] = n as u32;
        let count = n - first;
        if count == 0 {
            continue;
        }
        let items = move |chunk: usize| {
            first + chunk * FINE_CHUNK..(first + (chunk + 1) * FINE_CHUNK).min(n)
        };
        let mut ctx = Ctx {
            st: &mut *st,
            ws: &mut *ws,
            vis,
        };
        run_chunks_scaled(
            ex,
            &mut ctx,
            count.div_ceil(FINE_CHUNK),
            CHUNK / FINE_CHUNK,
            FINE_CHUNK * out,
            |c: &Ctx<'_, '_, V>, chunk, buf| {
                let ray = Ray {
                    vis: c.vis,
                    polys: WsPolygons { st: c.st, ws: c.ws },
                };
                for (slot, i) in items(chunk).enumerate() {
                    let o = &mut buf[slot * out..(slot + 1) * out];
                    let e = Elem::new(kind, i as u32);
                    let p = c.st.patch(c.ws, e);
                    if !p.unprepared() {
                        o[0] = f32::NAN;
                        continue;
                    }
                    prepare(c.st, c.ws, e, &p, &ray, o);
                }
            },
            |c: &mut Ctx<'_, '_, V>, chunk, buf| {
                for (slot, i) in items(chunk).enumerate() {
                    let o = &buf[slot * out..(slot + 1) * out];
                    if o[0].is_nan() {
                        continue;
                    }
                    let e = Elem::new(kind, i as u32);
                    let mut p = c.st.patch(c.ws, e);
                    let bits = o[0] as u32;
                    p.shape = (p.shape & !(UNPREPARED | (0xF * BURIED))) | ((bits & 0xF) * BURIED);
                    p.exposed = o[1];
                    p.shadow = o[2];
                    c.st.set_patch(c.ws, e, &p);
                    c.st.stats.rays += o[3 + 2 * nb] as u64;
                    c.st.stats.rays_by_phase.lighting += o[3 + 2 * nb] as u64;
                    for side in 0..State::sides(e) {
                        if let Some(d) = c.st.direct_mut(c.ws, e, side) {
                            d.copy_from_slice(&o[3 + side * nb..3 + (side + 1) * nb]);
                        }
                        if let Some(d) = c.st.linked_mut(c.ws, e, side) {
                            let at = 4 + 2 * nb + side * nb;
                            d.copy_from_slice(&o[at..at + nb]);
                        }
                    }
                }
            },
            &mut |done, total| {
                progress.report(
                    "lighting patches",
                    offset + (done * FINE_CHUNK).min(count) as u64,
                    all.max(offset + (total * FINE_CHUNK).min(count) as u64),
                )
            },
        );
        offset += count as u64;
    }
}

struct Ctx<'a, 'v, V: ?Sized> {
    st: &'a mut State,
    ws: &'a mut [u8],
    vis: &'a Vis<'v, V>,
}

/// Fills `out`: buried bits, exposed fraction, shadow measure, direct irradiance per side
/// and band, rays cast.
fn prepare<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    e: Elem,
    p: &Patch,
    vis: &V,
    out: &mut [f32],
) {
    let nb = st.bands;
    out.fill(0.0);
    let poly = st.polygon(ws, p.poly);
    let normal = Vec3::from(poly.normal);
    let n = p.corner_count();
    let mut corners = [Vec3::ZERO; 4];
    for (c, src) in corners.iter_mut().zip(p.corners) {
        *c = src.into();
    }
    let corners = &corners[..n];
    let mut rays = 0u32;
    // Buried quadrature points (one-sided polygons only: a two-sided one is never inside).
    let (mut pts, mut wts) = ([Vec3::ZERO; MAX_QUADRATURE], [0.0f32; MAX_QUADRATURE]);
    let m = quadrature(corners, &mut pts, &mut wts);
    let mut bits = 0u32;
    let mut exposed = 0.0f32;
    for q in 0..m {
        let buried = e.kind() == Kind::Patch1
            && is_buried(
                st,
                ws,
                pts[q],
                normal,
                p.poly,
                hash3(e.0, q as u32, 0xB0),
                vis,
                &mut rays,
            );
        if buried {
            bits |= 1 << q;
        } else {
            exposed += wts[q];
        }
    }
    // Partly buried: the exposed fraction from a finer grid (the light that reaches the patch
    // is spread over its exposed part, and a third-or-two-thirds guess from the quadrature
    // points inflated or starved it by as much: a ceiling patch around a lamp got +50%).
    if bits != 0 && bits != (1 << m) - 1 {
        let mut open = 0u32;
        for i in 0..EXPOSURE_GRID {
            for j in 0..EXPOSURE_GRID {
                let g = EXPOSURE_GRID as f32;
                let (u, v) = ((i as f32 + 0.5) / g, (j as f32 + 0.5) / g);
                let x = point_on(corners, u, v);
                let seed = hash3(e.0, i * EXPOSURE_GRID + j, 0xB1);
                if !is_buried(st, ws, x, normal, p.poly, seed, vis, &mut rays) {
                    open += 1;
                }
            }
        }
        exposed = open as f32 / (EXPOSURE_GRID * EXPOSURE_GRID) as f32;
    }
    out[0] = bits as f32;
    out[1] = exposed.clamp(0.0, 1.0);
    let sources = st.sources;
    if sources > 0 && st.lay.strides.direct {
        let sides = State::sides(e);
        let mut direct = [[0.0f32; 8]; 2];
        // The part of it that came through links (see `Strides::links_apart`).
        let mut linked = [[0.0f32; 8]; 2];
        let cells = cells_for(st, p.area);
        let mut shadow = 0.0f32;
        // Suns: adaptive visibility per sun.
        for k in 0..st.suns {
            let src: Source = super::pool::read(ws, st.at(ws, Elem::new(Kind::Source, k)));
            let towards = Vec3::from(src.towards);
            let c = normal.dot(towards);
            let side = if c > 0.0 { 0 } else { 1 };
            if c == 0.0 || side >= sides || st.settings.sun_sides & (1 << side) == 0 {
                continue;
            }
            let seed = hash3(e.0, k, 0x5A11);
            let skip = st.source_skip(ws, k, p.poly);
            let lit = lit_fraction(st, corners, cells, seed, skip, towards, vis, &mut rays);
            let irr = st.b(ws, Elem::new(Kind::Source, k), 0).unwrap_or(&[]);
            let mut e_max = 0.0f32;
            for (b, d) in direct[side][..nb].iter_mut().enumerate() {
                let v = irr.get(b).copied().unwrap_or(0.0) * c.abs();
                *d += v * lit;
                if src.outer != NONE {
                    linked[side][b] += v * lit;
                }
                e_max = e_max.max(v);
            }
            shadow += e_max * p.area * 2.0 * lit.min(1.0 - lit);
        }
        // Sky: one importance-sampled direction per sample; the links' beams apart.
        let root_area = st.patch(ws, Elem(poly.root)).area;
        let sky = sky_samples(
            root_area / st.typical_area,
            p.area / root_area,
            st.settings.rays,
        );
        for beams in [false, true] {
            sky_light(
                st,
                ws,
                e,
                p,
                corners,
                normal,
                sides,
                sky,
                vis,
                beams,
                [&mut direct, &mut linked],
                &mut rays,
            );
        }
        // The patch's irradiance is the mean over its exposed part; buried parts are dark.
        let scale = if out[1] > 0.0 { 1.0 / out[1] } else { 0.0 };
        let apart = st.lay.strides.links_apart;
        for side in 0..sides {
            for b in 0..nb {
                out[3 + side * nb + b] = direct[side][b] * scale.min(1e6);
                if apart {
                    out[4 + 2 * nb + side * nb + b] = linked[side][b] * scale.min(1e6);
                }
            }
        }
        out[2] = shadow;
    }
    out[3 + 2 * nb] = rays as f32;
}

/// Cells along each side of a patch's sampling grid: two per typical polygon of the scene
/// along its side (a shadow is cast by a polygon, so it can be as narrow as one), at least
/// 2, at most [`MAX_CELLS`].
fn cells_for(st: &State, area: f32) -> u32 {
    if st.typical_area.is_nan() || st.typical_area <= 0.0 || area.is_nan() || area <= 0.0 {
        return 2;
    }
    let r = 2.0 * libm::sqrtf(area / st.typical_area);
    (libm::ceilf(r) as u32).clamp(2, MAX_CELLS)
}

/// Sky samples of a patch that covers the share `share` of its polygon, whose area is
/// `ratio` times the scene's typical polygon: the polygon's count (`8 x rays` for one of
/// typical size, 32 at the default, growing as the ratio to the power 2.5, at most 4096)
/// times the share, at least [`MIN_SKY`]. Each sample tests one direction, so a side's sky
/// light is a plain Monte Carlo estimate with a relative noise of about
/// `sqrt((1 - p) / (p N))` at a lit fraction `p`; a polygon larger than the polygons that
/// shadow it (soil under leaves) is worth more samples, and such polygons are few. Its
/// patches share them by area: the density stays that of the polygon however finely it is
/// subdivided (4096 for every patch cost a maize canopy's soil seven times its polygons'
/// count), so its mean keeps its accuracy. Measured under random canopies of LAI 2: see
/// `tests/sunlight.rs`.
fn sky_samples(ratio: f32, share: f32, rays: u32) -> u32 {
    let base = 8.0 * rays.max(1) as f32;
    let r = if ratio.is_finite() {
        ratio.max(1.0)
    } else {
        1.0
    };
    let share = if share.is_finite() {
        share.clamp(0.0, 1.0)
    } else {
        1.0
    };
    ((base * r * r * libm::sqrtf(r)).clamp(base, 4096.0) * share).max(MIN_SKY) as u32
}

/// The fewest sky samples of a patch (a small part of a subdivided polygon).
const MIN_SKY: f32 = 4.0;

/// True when every ray from `x` (on polygon `poly`, front normal `n`) meets the back of a
/// one-sided polygon.
#[allow(clippy::too_many_arguments)]
fn is_buried<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    x: Vec3,
    n: Vec3,
    poly: u32,
    seed: u32,
    vis: &V,
    rays: &mut u32,
) -> bool {
    for j in 0..BURIED_RAYS {
        // The normal first, then cosine-distributed directions, stratified.
        let d = if j == 0 {
            n
        } else {
            let (u, v) = unit2(hash3(seed, j, 0xD1));
            let strata = BURIED_RAYS - 1;
            let u = ((j - 1) as f32 + u) / strata as f32;
            cosine_direction(n, u, v)
        };
        *rays += 1;
        let Some((hit, _)) = vis.first_hit(x, st.beyond(x, d), [poly, NONE]) else {
            return false;
        };
        if hit >= st.polygons {
            return false;
        }
        let hp = st.polygon(ws, hit);
        let m = st.material(ws, hp.material);
        let back = Vec3::from(hp.normal).dot(d) > 0.0;
        if m.two_sided != 0 || !back {
            return false;
        }
    }
    true
}

/// Whether no ray from the points, in 4 stratified cosine-distributed directions each about
/// `n`, leaves the scene; and whether one of them met the back of a one-sided polygon (which
/// absorbs: see `no_steady_state`).
#[allow(clippy::too_many_arguments)]
fn is_closed<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    points: &[Vec3],
    n: Vec3,
    poly: u32,
    seed: u32,
    vis: &V,
    rays: &mut u32,
) -> (bool, bool) {
    let mut backs = false;
    for (q, &x) in points.iter().enumerate() {
        for j in 0..4u32 {
            let (u, v) = unit2(hash3(seed, q as u32 * 4 + j, 0xE5C));
            let u = ((j % 2) as f32 + u) * 0.5;
            let v = ((j / 2) as f32 + v) * 0.5;
            let d = cosine_direction(n, u, v);
            *rays += 1;
            match vis.first_hit(x, st.beyond(x, d), [poly, NONE]) {
                None => return (false, backs),
                Some((hit, _)) if hit < st.polygons => {
                    let hp = st.polygon(ws, hit);
                    let one_sided = st.material(ws, hp.material).two_sided == 0;
                    backs |= one_sided && Vec3::from(hp.normal).dot(d) > 0.0;
                }
                Some(_) => {}
            }
        }
    }
    (true, backs)
}

/// Whether the scene is closed: no ray from any input polygon's quadrature points (4
/// stratified cosine-distributed directions each, every receiving side) leaves it; and
/// whether one of those rays met the back of a one-sided polygon. Polygons are tested in
/// order and the test stops at the first ray that leaves, so an open scene costs a few
/// rays.
pub(crate) fn test_closed<V: Visibility + ?Sized>(st: &mut State, ws: &[u8], vis: &Vis<'_, V>) {
    let ray = Ray {
        vis,
        polys: WsPolygons { st, ws },
    };
    let mut backs = false;
    let mut rays = 0u32;
    for i in 0..st.polygons {
        let rec = st.polygon(ws, i);
        let e = Elem(rec.root);
        let p = st.patch(ws, e);
        let mut corners = [Vec3::ZERO; 4];
        for (c, src) in corners.iter_mut().zip(p.corners) {
            *c = src.into();
        }
        let (mut pts, mut wts) = ([Vec3::ZERO; MAX_QUADRATURE], [0.0f32; MAX_QUADRATURE]);
        let m = quadrature(&corners[..p.corner_count()], &mut pts, &mut wts);
        let normal = Vec3::from(rec.normal);
        for side in 0..State::sides(e) {
            let n = if side == 0 { normal } else { -normal };
            let seed = hash3(e.0, side as u32, 0xC105);
            let (closed, b) = is_closed(st, ws, &pts[..m], n, i, seed, &ray, &mut rays);
            backs |= b;
            if !closed {
                st.closed = false;
                st.sees_backs = backs;
                st.stats.rays += rays as u64;
                st.stats.rays_by_phase.lighting += rays as u64;
                return;
            }
        }
    }
    st.closed = st.polygons > 0;
    st.sees_backs = backs;
    st.stats.rays += rays as u64;
    st.stats.rays_by_phase.lighting += rays as u64;
}

/// A band in which the scene has no steady state: no ray from any patch leaves it, none met
/// the back of a one-sided polygon, every material reflects or transmits all of that band
/// on every side light can reach, and something emits in it. Light there would grow without
/// bound.
pub(crate) fn no_steady_state(st: &State, ws: &[u8]) -> Option<usize> {
    if !st.closed || st.sees_backs {
        return None;
    }
    let mut emits = [false; 8];
    let mut lossy = [false; 8];
    for kind in [Kind::Patch1, Kind::Patch2] {
        for i in 0..st.pool(kind).len {
            let e = Elem::new(kind, i);
            let p = st.patch(ws, e);
            let m = st.material(ws, st.polygon(ws, p.poly).material);
            for b in 0..st.bands {
                for side in 0..State::sides(e) {
                    emits[b] |= m.emit[side][b] > 0.0;
                    lossy[b] |= m.rho[side][b] + m.tau[b] < 1.0 - 1e-6;
                }
            }
        }
    }
    (0..st.bands).find(|&b| emits[b] && !lossy[b])
}

/// The lit fraction of a patch towards a directional source: a `cells x cells` grid, 2 x 2
/// jittered samples per cell, every sample weighted by its share of the area.
///
/// Cells are split (up to [`SUN_DEPTH`] levels) where a shadow edge may cross them: a cell
/// whose samples disagree, or differ from a neighbour's (top cells) or a sibling's (deeper
/// cells): an edge between them may clip its corner. Samples that decide a split do
/// not also estimate: a cell kept whole because its samples agreed would count a gap (or a
/// shadow) that they all missed as shadow (or light), and under fine foliage, whose gaps
/// are small holes in a shadow, that made the soil 5 to 10% too dark. A cell kept whole is
/// estimated from fresh samples, so the estimate is unbiased whatever the decisions.
#[allow(clippy::too_many_arguments)]
fn lit_fraction<V: Visibility + ?Sized>(
    st: &State,
    corners: &[Vec3],
    cells: u32,
    seed: u32,
    skip: [u32; 2],
    towards: Vec3,
    vis: &V,
    rays: &mut u32,
) -> f32 {
    let (mut lit, mut total) = (0.0f32, 0.0f32);
    let mut id = 0u32;
    // 2 x 2 jittered samples of the cell at (u0, v0) of side s: visibility and area weight.
    let mut sample4 = |u0: f32, v0: f32, s: f32| {
        let (mut vals, mut wts) = ([0.0f32; 4], [0.0f32; 4]);
        let half = 0.5 * s;
        for (k, (v, w)) in vals.iter_mut().zip(wts.iter_mut()).enumerate() {
            id += 1;
            let (ju, jv) = unit2(hash3(seed, id, 0x7E));
            let u = u0 + ((k % 2) as f32 + ju) * half;
            let vv = v0 + ((k / 2) as f32 + jv) * half;
            let x = point_on(corners, u, vv);
            *rays += 1;
            *v = vis.transmittance_towards(x, st.beyond(x, towards), towards, skip);
            *w = jacobian(corners, u, vv);
        }
        (vals, wts)
    };
    // What a cell's samples saw: 0 all shadow, 1 all lit, 2 both.
    let class = |vals: &[f32; 4]| -> u8 {
        if vals.iter().any(|&v| v != vals[0]) {
            2
        } else {
            (vals[0] > 0.0) as u8
        }
    };
    let n = cells.clamp(1, MAX_CELLS) as usize;
    let size = 1.0 / n as f32;
    let mut seen = [0u8; (MAX_CELLS * MAX_CELLS) as usize];
    for (c, slot) in seen.iter_mut().enumerate().take(n * n) {
        let (i, j) = (c % n, c / n);
        *slot = class(&sample4(i as f32 * size, j as f32 * size, size).0);
    }
    // (u0, v0, size, depth) of cells still to sample.
    let mut stack: heapless::Vec<(f32, f32, f32, u32), 64> = heapless::Vec::new();
    for c in 0..n * n {
        let (i, j) = (c % n, c / n);
        let own = seen[c];
        let edge = own == 2
            || (i > 0 && seen[c - 1] != own)
            || (i + 1 < n && seen[c + 1] != own)
            || (j > 0 && seen[c - n] != own)
            || (j + 1 < n && seen[c + n] != own);
        let _ = stack.push((
            i as f32 * size,
            j as f32 * size,
            size,
            if edge { 0 } else { SUN_DEPTH },
        ));
        while let Some((u0, v0, s, depth)) = stack.pop() {
            if depth < SUN_DEPTH {
                // Split: the children decide for themselves from their own samples, each
                // also split where a sibling saw otherwise (an edge between them).
                let half = 0.5 * s;
                let d = depth + 1;
                let corner = |k: usize| (u0 + (k % 2) as f32 * half, v0 + (k / 2) as f32 * half);
                let mut kids = [0u8; 4];
                if d < SUN_DEPTH {
                    for (k, c) in kids.iter_mut().enumerate() {
                        let (cu, cv) = corner(k);
                        *c = class(&sample4(cu, cv, half).0);
                    }
                }
                let uniform = kids.iter().all(|&c| c == kids[0] && c != 2);
                for k in 0..4 {
                    let (cu, cv) = corner(k);
                    let split = d < SUN_DEPTH && !uniform;
                    let _ = stack.push((cu, cv, half, if split { d } else { SUN_DEPTH }));
                }
                continue;
            }
            // Estimated from fresh samples.
            let (vals, wts) = sample4(u0, v0, s);
            // A cell's area share is its parameter area times the mean Jacobian of its samples.
            let area = s * s;
            for k in 0..4 {
                lit += area * wts[k] * vals[k];
                total += area * wts[k];
            }
        }
    }
    if total > 0.0 {
        (lit / total).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// Adds the direct light of one group of the sources after the suns to `direct` (per side
/// and band), the scene's sky directions (`beams` false) or the beams of light that came
/// through links (`beams` true: those whose rays see only some outer levels, see
/// `records::Source::outer`): `count` samples, each at a stratified point of the patch with
/// a direction drawn by irradiance x |cosine| (front directions for one-sided patches). The
/// two groups are drawn apart, `count` samples each: drawn together, the beams (strong in the near infrared, where leaves scatter most)
/// took most of the samples, and the sky of a leaf deep in a crown, seen through a few
/// gaps, was left to a handful (the paper poplar's dimmest leaves' PAR was off by a median of
/// 18% against hr's 11%).
#[allow(clippy::too_many_arguments)]
fn sky_light<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    e: Elem,
    p: &Patch,
    corners: &[Vec3],
    normal: Vec3,
    sides: usize,
    count: u32,
    vis: &V,
    beams: bool,
    [direct, linked]: [&mut [[f32; 8]; 2]; 2],
    rays: &mut u32,
) {
    let nb = st.bands;
    let first = st.suns;
    let total_sources = st.sources;
    if total_sources <= first {
        return;
    }
    // Weights: the largest band's irradiance times |cosine|, on the sides the patch has, for
    // the group's sources.
    let weight = |k: u32| -> (f32, usize, f32) {
        let src: Source = super::pool::read(ws, st.at(ws, Elem::new(Kind::Source, k)));
        let c = normal.dot(Vec3::from(src.towards));
        let side = if c > 0.0 { 0 } else { 1 };
        if c == 0.0
            || side >= sides
            || st.settings.sun_sides & (1 << side) == 0
            || (src.outer != NONE) != beams
        {
            return (0.0, side, c);
        }
        let irr = st.b(ws, Elem::new(Kind::Source, k), 0).unwrap_or(&[]);
        let e_max = irr.iter().copied().fold(0.0f32, f32::max);
        (e_max * c.abs(), side, c)
    };
    let mut w_total = 0.0f32;
    for k in first..total_sources {
        w_total += weight(k).0;
    }
    if w_total.is_nan() || w_total <= 0.0 {
        return;
    }
    let grid = libm::floorf(libm::sqrtf(count as f32)).max(1.0) as u32;
    let seed = if beams {
        hash3(e.0, 0xBEA, p.poly)
    } else {
        hash3(e.0, 0x5C1, p.poly)
    };
    let inv = w_total / count as f32;
    // Directions are stratified over the weights' CDF in sample order; points over a grid
    // in a shuffled order (a stride coprime with the count), so the two do not align.
    let stride = coprime_stride(count, hash3(seed, 0, 0xC3));
    for j in 0..count {
        let cell = ((j as u64 * stride as u64) % count as u64) as u32 % (grid * grid);
        let (ju, jv) = unit2(hash3(seed, j, 0xA1));
        let u = ((cell % grid) as f32 + ju) / grid as f32;
        let v = ((cell / grid) as f32 + jv) / grid as f32;
        let (jt, _) = unit2(hash3(seed, j, 0xE5));
        let target = (j as f32 + jt) / count as f32 * w_total;
        let mut acc = 0.0f32;
        let mut pick = NONE;
        for k in first..total_sources {
            let w = weight(k).0;
            if w <= 0.0 {
                continue;
            }
            acc += w;
            pick = k;
            if target < acc {
                break;
            }
        }
        if pick == NONE {
            continue;
        }
        let (w, side, c) = weight(pick);
        if w <= 0.0 {
            continue;
        }
        let src: Source = super::pool::read(ws, st.at(ws, Elem::new(Kind::Source, pick)));
        let x = point_on(corners, u, v);
        *rays += 1;
        let towards = Vec3::from(src.towards);
        let skip = st.source_skip(ws, pick, p.poly);
        let t = vis.transmittance_towards(x, st.beyond(x, towards), towards, skip);
        if t <= 0.0 {
            continue;
        }
        let jw = jacobian(corners, u, v) / mean_jacobian(corners);
        let irr = st.b(ws, Elem::new(Kind::Source, pick), 0).unwrap_or(&[]);
        for (b, d) in direct[side][..nb].iter_mut().enumerate() {
            let e_b = irr.get(b).copied().unwrap_or(0.0) * c.abs();
            *d += inv * jw * t * e_b / w;
            if src.outer != NONE {
                linked[side][b] += inv * jw * t * e_b / w;
            }
        }
    }
}
