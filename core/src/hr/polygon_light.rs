//! The direct light of suns and sky on each polygon of a closed instance whose tables keep
//! its polygons apart (see `tables::single`) and that blocks with them (see
//! `original_geometry`): which share of each polygon's self-lit part the rest of the level
//! leaves lit, polygon by polygon. Its first scattering is then where the light really
//! falls: under a dense canopy a plant's lower leaves lie in its neighbours' shade, which one
//! lit fraction for the whole plant spread evenly over its leaves (their isolated lighting),
//! so the soil below read their light as if they were lit (240 plants: the darkest soil 21%
//! too much NIR, 8% too much PAR).
//!
//! Per polygon, `rays` points for each sun and twice as many for the sky (its directions
//! drawn by their irradiance times the cosine), each first tested against the instance's
//! own polygons (its tables know that shade) and, where open, traced through the level. The
//! fraction lit of the open points scales the polygon's isolated irradiance; the instance's
//! whole light per source (intercepted, scattered more than once) comes from the same
//! fractions weighed by each polygon's share of the cross-section.
//!
//! Work goes in fixed chunks of (instance, block of polygons); every point comes from a hash
//! of the instance, the polygon, the source group and the point's number, so results never
//! depend on the thread count.

use super::blockers::SKIP_INSTANCE;
use super::exec::{Executor, Fallback, Progress, run_chunks};
use super::ids::{Elem, Kind};
use super::state::State;
use super::vis::{Ray, Vis, WsPolygons};
use crate::limits::{MAX_BANDS, NONE};
use crate::sampling::{hash3, unit2};
use crate::visibility::Visibility;
use glam::Vec3;

/// Most polygons per chunk.
const BLOCK: u32 = 64;
/// Most sources a level may have for its instances to be lit polygon by polygon (the
/// per-source sums live on the stack); beyond, the whole-instance fractions serve.
pub(crate) const MAX_SOURCES: usize = 1024;
/// Points per polygon for the sky, per point for each sun.
const SKY_FACTOR: u32 = 2;

/// True when closed instance `i` is lit polygon by polygon: its tables keep its polygons
/// apart in the order of the polygons it blocks with.
pub(crate) fn lit_by_polygon(st: &State, ws: &[u8], i: u32) -> bool {
    if st.sources == 0 || st.sources as usize > MAX_SOURCES {
        return false;
    }
    let leaf = st.instance(ws, i);
    let slot = st.slot(ws, leaf.slot);
    if slot.polygons_kept == 0 {
        return false;
    }
    let Some(g) = st.original_geometry(ws, leaf.slot) else {
        return false;
    };
    let placed = st.placed(ws, i);
    placed
        .tables()
        .single()
        .is_some_and(|s| s.polygons() == g.polygons() as usize)
}

/// Polygons per chunk for `suns` suns, so that a chunk's output (the rays, then per sun and
/// for the sky one fraction per polygon) fits the executor's scratch.
fn block(st: &State) -> u32 {
    let groups = st.suns as usize + 1;
    (((st.lay.scratch_floats.saturating_sub(1)) / groups) as u32).clamp(1, BLOCK)
}

/// Largest polygon count of the level's instances lit by polygon (0 when none is).
fn most_polygons(st: &State, ws: &[u8]) -> u32 {
    let mut most = 0;
    for i in 0..st.instances {
        if lit_by_polygon(st, ws, i)
            && let Some(g) = st.original_geometry(ws, st.instance(ws, i).slot)
        {
            most = most.max(g.polygons());
        }
    }
    most
}

struct Ctx<'a, 'v, V: ?Sized> {
    st: &'a mut State,
    ws: &'a mut [u8],
    vis: &'a Vis<'v, V>,
    /// Per source, the instance's cross-section lit so far and all of it (m^2, the
    /// original's frame), over the blocks folded.
    sums: heapless::Vec<[f32; 2], MAX_SOURCES>,
}

/// Lights the polygons of every closed instance lit by polygon (see [`lit_by_polygon`]):
/// adds to the direct part of its received light each polygon's first light and the whole
/// light per source. The direct part must be cleared before.
pub(crate) fn light_polygons<V: Visibility + ?Sized, E: Executor>(
    st: &mut State,
    ws: &mut [u8],
    vis: &Vis<'_, V>,
    ex: &mut Fallback<'_, E>,
    progress: &mut dyn Progress,
) {
    let most = most_polygons(st, ws);
    if most == 0 || st.lay.scratch_floats < st.suns as usize + 2 {
        return;
    }
    let b = block(st);
    let blocks = most.div_ceil(b) as usize;
    let groups = st.suns as usize + 1;
    let out_len = 1 + groups * b as usize;
    let items = st.instances as usize * blocks;
    let mut sums = heapless::Vec::new();
    let _ = sums.resize(st.sources as usize, [0.0f32; 2]);
    let mut ctx = Ctx { st, ws, vis, sums };
    run_chunks(
        ex,
        &mut ctx,
        items,
        out_len,
        |c: &Ctx<'_, '_, V>, chunk, buf| {
            let (i, k) = ((chunk / blocks) as u32, (chunk % blocks) as u32);
            buf.fill(f32::NAN);
            buf[0] = 0.0;
            if !lit_by_polygon(c.st, c.ws, i) {
                return;
            }
            let ray = Ray {
                vis: c.vis,
                polys: WsPolygons { st: c.st, ws: c.ws },
            };
            buf[0] = fractions(c.st, c.ws, &ray, i, k * b, b, &mut buf[1..]) as f32;
        },
        |c: &mut Ctx<'_, '_, V>, chunk, buf| {
            let (i, k) = ((chunk / blocks) as u32, (chunk % blocks) as u32);
            if k == 0 {
                c.sums.iter_mut().for_each(|s| *s = [0.0; 2]);
            }
            if !lit_by_polygon(c.st, c.ws, i) {
                return;
            }
            let rays = buf[0] as u64;
            c.st.stats.rays += rays;
            c.st.stats.rays_by_phase.lighting += rays;
            add_first(c, i, k * b, b, &buf[1..]);
            if k as usize + 1 == blocks {
                add_whole(c, i);
            }
        },
        &mut |done, total| progress.report("lighting closed polygons", done as u64, total as u64),
    );
}

/// A source's direction (towards it, world) and irradiance per band (W/m^2 on a plane
/// facing it).
fn source(st: &State, ws: &[u8], k: u32) -> Option<(Vec3, [f32; MAX_BANDS])> {
    let src = Elem::new(Kind::Source, k);
    let super::state::Shape::Source { towards } = st.shape(ws, src) else {
        return None;
    };
    let mut e = [0.0f32; MAX_BANDS];
    if let Some(b) = st.b(ws, src, 0) {
        for (o, v) in e.iter_mut().zip(b) {
            *o = *v;
        }
    }
    Some((towards, e))
}

/// Fills `out` (per sun, then for the sky: `b` fractions, one per polygon from `first` on)
/// with the lit share of each polygon's self-lit points (NaN where none was self-lit);
/// returns the rays cast.
fn fractions<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    ray: &Ray<'_, V>,
    i: u32,
    first: u32,
    b: u32,
    out: &mut [f32],
) -> u32 {
    let leaf = st.instance(ws, i);
    let Some(g) = st.original_geometry(ws, leaf.slot) else {
        return 0;
    };
    let place = leaf.place();
    let inverse = place.rotation.conjugate();
    let far = st.far / place.scale.max(f32::MIN_POSITIVE);
    let per = st.settings.rays.max(1);
    let mut rays = 0u32;
    // Every source's direction (world, local) and its largest band's irradiance, read once
    // for the block (by source number: suns first, then the sky).
    let mut dirs: heapless::Vec<(Vec3, Vec3, f32), MAX_SOURCES> = heapless::Vec::new();
    for k in 0..st.sources {
        let (towards, e) = source(st, ws, k).unwrap_or((Vec3::ZERO, [0.0; MAX_BANDS]));
        let w = e[..st.bands].iter().copied().fold(0.0f32, f32::max);
        let _ = dirs.push((towards, (inverse * towards).normalize_or_zero(), w));
    }
    let (suns, skies) = dirs.split_at(st.suns as usize);
    // One point: open to the source through the instance's own polygons, and what the
    // level lets through from there (None when its own polygons shade it).
    let mut point = |q: u32, k: u32, towards: Vec3, local: Vec3, h: u32| -> Option<f32> {
        let (u, v) = unit2(h);
        let (p, _) = g.point_on(q, u, v)?;
        rays += 1;
        if g.first_hit_local(p, p + local * far, q).is_some() {
            return None;
        }
        let x = place.point(p);
        let end = st.beyond(x, towards);
        let skip = [SKIP_INSTANCE | i, st.source_skip(ws, k, NONE)[1]];
        rays += 1;
        Some(ray.transmittance_towards(x, end, towards, skip))
    };
    let last = (first + b).min(g.polygons());
    for q in first..last {
        let slot = (q - first) as usize;
        let n = g.normal(q);
        for (k, &(towards, local, _)) in suns.iter().enumerate() {
            let k = k as u32;
            if n.dot(local) == 0.0 {
                continue;
            }
            let (mut lit, mut open) = (0.0f32, 0u32);
            for j in 0..per {
                if let Some(t) = point(q, k, towards, local, hash3(i, q, j ^ (k << 16))) {
                    lit += t;
                    open += 1;
                }
            }
            if open > 0 {
                out[k as usize * b as usize + slot] = lit / open as f32;
            }
        }
        if skies.is_empty() {
            continue;
        }
        // The sky: directions drawn by irradiance times cosine, stratified.
        let total: f32 = skies.iter().map(|s| s.2 * n.dot(s.1).abs()).sum();
        if total <= 0.0 {
            continue;
        }
        let m = SKY_FACTOR * per;
        let (jitter, _) = unit2(hash3(i, q, 0x5C7E));
        let (mut lit, mut open) = (0.0f32, 0u32);
        let (mut j, mut acc) = (0u32, 0.0f32);
        for (s, &(towards, local, w)) in skies.iter().enumerate() {
            acc += w * n.dot(local).abs();
            while j < m && (j as f32 + jitter) / m as f32 * total < acc {
                let k = st.suns + s as u32;
                if let Some(t) = point(q, k, towards, local, hash3(i, q, 0x5C00_0000 ^ j)) {
                    lit += t;
                    open += 1;
                }
                j += 1;
            }
        }
        if open > 0 {
            out[st.suns as usize * b as usize + slot] = lit / open as f32;
        }
    }
    rays
}

/// Adds the first light of instance `i`'s polygons `first..first + b` from their
/// fractions (see [`fractions`]; a polygon without one takes its block's mean), and their
/// part of the cross-section per source to the sums.
fn add_first<V: ?Sized>(c: &mut Ctx<'_, '_, V>, i: u32, first: u32, b: u32, f: &[f32]) {
    let (st, ws) = (&*c.st, &mut *c.ws);
    let nb = st.bands;
    let groups = st.suns as usize + 1;
    // Each group's mean over the block's polygons that have a fraction.
    let mut means: heapless::Vec<f32, { MAX_SOURCES + 1 }> = heapless::Vec::new();
    for g in 0..groups {
        let (mut sum, mut count) = (0.0f32, 0u32);
        for &x in &f[g * b as usize..(g + 1) * b as usize] {
            if x.is_finite() {
                sum += x;
                count += 1;
            }
        }
        let _ = means.push(if count > 0 { sum / count as f32 } else { 0.0 });
    }
    let sources = st.sources;
    for k in 0..sources {
        let Some((towards, e)) = source(st, ws, k) else {
            continue;
        };
        let g = (k.min(st.suns)) as usize;
        let sum = &mut c.sums[k as usize];
        st.with_received(ws, i, |placed, r| {
            let Some(single) = placed.tables().single() else {
                return;
            };
            let d = placed.local(towards);
            if d == Vec3::ZERO {
                return;
            }
            let wd = single.grid().weights(d);
            let last = (first + b).min(single.polygons() as u32);
            for q in first..last {
                let (n, a, _) = single.polygon(q as usize, 0);
                let cd = n.dot(d);
                if cd == 0.0 {
                    continue;
                }
                let iso = single.fraction(&wd, q as usize);
                if iso <= 0.0 {
                    continue;
                }
                let x = f[g * b as usize + (q - first) as usize];
                let lit = if x.is_finite() { x } else { means[g] };
                let w = a * cd.abs() * iso;
                sum[0] += w * lit;
                sum[1] += w;
                let side = usize::from(cd < 0.0);
                for (band, &eb) in e.iter().enumerate().take(nb) {
                    r.add_first(q as usize, side, band, eb * cd.abs() * iso * lit);
                }
            }
        });
    }
}

/// Adds instance `i`'s whole light per source: each source's beam times the lit share of
/// its cross-section, without the first light polygon by polygon (added already).
fn add_whole<V: ?Sized>(c: &mut Ctx<'_, '_, V>, i: u32) {
    let (st, ws) = (&*c.st, &mut *c.ws);
    let nb = st.bands;
    for k in 0..st.sources {
        let Some((towards, mut e)) = source(st, ws, k) else {
            continue;
        };
        let [lit, all] = c.sums[k as usize];
        let t = if all > 0.0 { lit / all } else { 0.0 };
        if t <= 0.0 {
            continue;
        }
        for v in &mut e[..nb] {
            *v *= t;
        }
        st.with_received(ws, i, |placed, r| {
            r.receive_spread(placed, towards, &e[..nb])
        });
    }
}
