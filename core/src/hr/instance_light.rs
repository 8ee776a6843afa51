//! The direct light of suns and sky on the closed instances of a level: each instance sees
//! each source through the level's polygons and the other closed instances, on average over
//! points spread through its original's box (placed), and keeps that light as a beam of its
//! received light (see `tables::closed`). Its own contents' shadows are in its tables.
//!
//! Work goes in fixed chunks of (instance, source) pairs; every point comes from a hash of
//! the instance, the source and the point's number, so results never depend on the thread
//! count.

use super::blockers::SKIP_INSTANCE;
use super::exchange::CELLS;
use super::exec::{Executor, Fallback, Progress, run_chunks};
use super::ids::{Elem, Kind};
use super::layout::CHUNK;
use super::state::{Handed, State};
use super::vis::{Ray, Vis, WsPolygons};
use crate::limits::NONE;
use crate::sampling::hash3;
use crate::visibility::Visibility;
use glam::Vec3;

/// Points per instance for a sun, per visibility ray of the settings.
const SUN_POINTS: u32 = 16;
/// Points per instance for one sky direction, per visibility ray of the settings.
const SKY_POINTS: u32 = 2;

/// Points of a box for source `k` of `suns` suns at `rays` rays per setting.
fn points(k: u32, suns: u32, rays: u32) -> u32 {
    rays.max(1) * if k < suns { SUN_POINTS } else { SKY_POINTS }
}

/// A point of the unit cube from three hashes, stratified along a Halton-like sequence.
fn unit3(i: u32, k: u32, j: u32) -> Vec3 {
    let h = hash3(i, k, j);
    let f = |x: u32| (x & 0x3FF) as f32 / 1024.0 + 0.5 / 1024.0;
    Vec3::new(f(h), f(h >> 10), f(h >> 20))
}

/// The mean transmittance from points of closed instance `i`'s box to source `k`, and the
/// rays cast.
fn visible_fraction<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    ray: &Ray<'_, V>,
    i: u32,
    k: u32,
) -> (f32, u32) {
    let src = st.shape(ws, Elem::new(Kind::Source, k));
    let super::state::Shape::Source { towards } = src else {
        return (0.0, 0);
    };
    let placed = st.placed(ws, i);
    let (lo, hi) = placed.tables().bounds();
    let place = placed.place();
    let n = points(k, st.suns, st.settings.rays);
    if let Some(g) = st.original_geometry(ws, st.instance(ws, i).slot) {
        return surface_fraction(st, ws, ray, i, k, &g, &place, towards, n);
    }
    let mut sum = 0.0f32;
    for j in 0..n {
        let local = lo + (hi - lo) * unit3(i, k, j);
        let x = place.point(local);
        let end = st.beyond(x, towards);
        let skip = [SKIP_INSTANCE | i, st.source_skip(ws, k, NONE)[1]];
        sum += ray.transmittance_towards(x, end, towards, skip);
    }
    (sum / n as f32, n)
}

/// [`visible_fraction`] of an instance that blocks with its own polygons: over points of
/// its polygons (by area, each weighed by its cosine to the source) that its own polygons
/// leave lit, the share the rest of the level leaves lit too: the part of its lit
/// cross-section that is lit where it stands (points of its box were lit where its leaves
/// are not: under a canopy, the open air below its leaves).
#[allow(clippy::too_many_arguments)]
fn surface_fraction<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    ray: &Ray<'_, V>,
    i: u32,
    k: u32,
    g: &super::original_geometry::OriginalGeometry<'_>,
    place: &crate::geometry::Similarity,
    towards: Vec3,
    n: u32,
) -> (f32, u32) {
    let local = (place.rotation.conjugate() * towards).normalize_or_zero();
    let tries = 4 * n;
    let (mut lit, mut open, mut rays) = (0.0f32, 0.0f32, 0u32);
    for j in 0..tries {
        let h = hash3(i, k, j ^ 0x5F00_0000);
        let (a0, _) = crate::sampling::unit2(hash3(h, 1, 0xB1));
        let (u, v) = crate::sampling::unit2(hash3(h, 2, 0xB2));
        let a = ((j as f32 + a0) / tries as f32).min(1.0 - f32::EPSILON);
        let Some(sp) = g.sample(a, u, v) else {
            continue;
        };
        // The side facing the source, weighed by its cosine.
        let c = g.normal(sp.polygon).dot(local);
        let w = c.abs();
        if w <= 0.0 {
            continue;
        }
        let far = st.far / place.scale.max(f32::MIN_POSITIVE);
        rays += 1;
        if g.first_hit_local(sp.point, sp.point + local * far, sp.polygon)
            .is_some()
        {
            continue;
        }
        open += w;
        let x = place.point(sp.point);
        let end = st.beyond(x, towards);
        let skip = [SKIP_INSTANCE | i, st.source_skip(ws, k, NONE)[1]];
        rays += 1;
        lit += w * ray.transmittance_towards(x, end, towards, skip);
    }
    if open > 0.0 {
        (lit / open, rays)
    } else {
        (0.0, rays)
    }
}

struct Ctx<'a, 'v, V: ?Sized> {
    st: &'a mut State,
    ws: &'a mut [u8],
    vis: &'a Vis<'v, V>,
}

/// Lights every closed instance by every source: clears its whole light, fills it with
/// the suns' and sky's, and notes that as its direct light.
pub(crate) fn light_instances<V: Visibility + ?Sized, E: Executor>(
    st: &mut State,
    ws: &mut [u8],
    vis: &Vis<'_, V>,
    ex: &mut Fallback<'_, E>,
    progress: &mut dyn Progress,
) {
    let (instances, sources) = (st.instances as usize, st.sources as usize);
    for i in 0..st.instances {
        st.with_received(ws, i, |_, r| r.clear());
    }
    let pairs = instances * sources;
    if pairs > 0 {
        let mut ctx = Ctx { st, ws, vis };
        run_chunks(
            ex,
            &mut ctx,
            pairs.div_ceil(CHUNK),
            2 * CHUNK,
            |c: &Ctx<'_, '_, V>, chunk, buf| {
                let ray = Ray {
                    vis: c.vis,
                    polys: WsPolygons { st: c.st, ws: c.ws },
                };
                for (slot, p) in (chunk * CHUNK..((chunk + 1) * CHUNK).min(pairs)).enumerate() {
                    let (i, k) = ((p / sources) as u32, (p % sources) as u32);
                    // Those lit polygon by polygon are lit below.
                    let (t, rays) = if super::polygon_light::lit_by_polygon(c.st, c.ws, i) {
                        (0.0, 0)
                    } else {
                        visible_fraction(c.st, c.ws, &ray, i, k)
                    };
                    buf[2 * slot] = t;
                    buf[2 * slot + 1] = rays as f32;
                }
            },
            |c: &mut Ctx<'_, '_, V>, chunk, buf| {
                for (slot, p) in (chunk * CHUNK..((chunk + 1) * CHUNK).min(pairs)).enumerate() {
                    let (i, k) = ((p / sources) as u32, (p % sources) as u32);
                    let (t, rays) = (buf[2 * slot], buf[2 * slot + 1] as u64);
                    c.st.stats.rays += rays;
                    c.st.stats.rays_by_phase.lighting += rays;
                    let src = Elem::new(Kind::Source, k);
                    let super::state::Shape::Source { towards } = c.st.shape(c.ws, src) else {
                        continue;
                    };
                    let mut e = [0.0f32; crate::limits::MAX_BANDS];
                    let nb = c.st.bands;
                    if let Some(b) = c.st.b(c.ws, src, 0) {
                        for (o, v) in e.iter_mut().zip(b) {
                            *o = v * t;
                        }
                    }
                    c.st.with_received(c.ws, i, |placed, r| r.receive(placed, towards, &e[..nb]));
                }
            },
            &mut |done, total| {
                progress.report("lighting closed instances", done as u64, total as u64)
            },
        );
    }
    super::polygon_light::light_polygons(st, ws, vis, ex, progress);
    note_direct(st, ws);
    // The height profile of the direct light, while the light is the direct light alone.
    super::blockers::note_profiles(st, ws);
}

/// Notes every closed instance's light, lit by suns, sky and emitting polygons alone, as
/// its direct light (see `State::note_direct`).
pub(crate) fn note_direct(st: &State, ws: &mut [u8]) {
    for i in 0..st.instances {
        st.note_direct(ws, i);
    }
}

/// Hands closed instance `i` the beams `now` (per cell of the exchange's grid, from the
/// cell's direction, W/m^2 per band) as `part`: its light takes each cell's change since
/// `part` last handed it (see `Received::change`; `first` as there), and `now` is noted.
pub(crate) fn hand(
    st: &State,
    ws: &mut [u8],
    i: u32,
    part: Handed,
    now: &[[f32; crate::limits::MAX_BANDS]; CELLS],
    first: bool,
) {
    st.with_handed(ws, i, part, |placed, r, had| {
        hand_into(placed, r, had, now, first)
    });
}

/// [`hand`] over an instance's light (`r`, in place or a copy) and what `part` handed it
/// (`had`, `CELLS * bands` floats, updated).
pub(crate) fn hand_into(
    placed: &crate::tables::closed::Placed<'_>,
    r: &mut crate::tables::closed::Received<&mut [f32]>,
    had: &mut [f32],
    now: &[[f32; crate::limits::MAX_BANDS]; CELLS],
    first: bool,
) {
    let nb = had.len() / CELLS;
    let grid = super::exchange::grid();
    for (c, cell) in now.iter().enumerate() {
        let Some(d) = change(&had[c * nb..(c + 1) * nb], &cell[..nb]) else {
            continue;
        };
        r.change(placed, grid.direction(c as u32), &d[..nb], first);
        had[c * nb..(c + 1) * nb].copy_from_slice(&cell[..nb]);
    }
}

/// A cell's change from `had` to `now` (per band), `None` when nothing changed.
fn change(had: &[f32], now: &[f32]) -> Option<[f32; crate::limits::MAX_BANDS]> {
    let mut d = [0.0f32; crate::limits::MAX_BANDS];
    for ((o, n), h) in d.iter_mut().zip(now).zip(had) {
        *o = n - h;
    }
    if d[..now.len()].iter().all(|&x| x == 0.0) {
        None
    } else {
        Some(d)
    }
}

/// The flux density (W/m^2 per band, on a plane facing the emitter) that link `i` brings a
/// closed instance centred at `at`: its coefficients times its emitter's radiosity, as a
/// patch's front gathers it.
pub(crate) fn link_flux(st: &State, ws: &[u8], i: u32, at: Vec3, kk: usize, out: &mut [f32]) {
    let l = st.link(ws, i);
    let k = st.link_k(ws, i);
    let emit = Elem(l.emit);
    let nb = out.len();
    let mut b = [0.0f32; crate::limits::MAX_BANDS];
    out.fill(0.0);
    if super::oriented::witnessed(&l) {
        let coef = k[0];
        if coef != 0.0 {
            super::oriented::witness_radiosity(st, ws, &l, 0, false, false, &mut b[..nb]);
            for (o, v) in out.iter_mut().zip(&b[..nb]) {
                *o += coef * v;
            }
        }
        return;
    }
    for s in 0..kk.min(2) {
        let coef = if kk == 1 { k[0] } else { k[s] };
        if coef == 0.0 {
            continue;
        }
        let exact = l.flags & super::records::EXACT != 0;
        if !super::oriented::radiosity_towards(st, ws, emit, s, at, false, exact, &mut b[..nb]) {
            continue;
        }
        for (o, v) in out.iter_mut().zip(&b[..nb]) {
            *o += coef * v;
        }
    }
}

/// Most directions a link's light is spread over (see [`cone_directions`]).
pub(crate) const MAX_CONE: usize = 16;

/// Solid angle each direction of a spread cone stands for, at most (sr).
const CONE_CELL: f32 = 0.4;

/// The directions, each with an equal share, over which light of mean direction `dir`
/// reaches a closed instance (its length is the light's collimation `c`, as
/// `cluster_kernel::gathered` gives it): a uniform cone of half-angle `acos(2c - 1)` around
/// it (the soil under a plant sends light from a whole hemisphere, `c = 1/2`, which from its
/// mean direction alone would miss every vertical stem). Points of a Fibonacci spiral over
/// the cap, one per [`CONE_CELL`] of its solid angle, at most [`MAX_CONE`]; the axis alone
/// for nearly collimated light. Returns how many (0 without a direction).
pub(crate) fn cone_directions(dir: Vec3, out: &mut [Vec3; MAX_CONE]) -> usize {
    let len = dir.length();
    if !(len.is_finite() && len > 0.0) {
        return 0;
    }
    let axis = dir / len;
    let c = len.min(1.0);
    let cos_a = (2.0 * c - 1.0).max(-1.0);
    let omega = 2.0 * core::f32::consts::PI * (1.0 - cos_a);
    let m = (libm::ceilf(omega / CONE_CELL) as usize).clamp(1, MAX_CONE);
    if m == 1 {
        out[0] = axis;
        return 1;
    }
    let (u, v) = axis.any_orthonormal_pair();
    // The golden angle (rad).
    const GOLDEN: f32 = 2.399_963;
    for (j, o) in out.iter_mut().enumerate().take(m) {
        let z = 1.0 - (j as f32 + 0.5) / m as f32 * (1.0 - cos_a);
        let r = libm::sqrtf((1.0 - z * z).max(0.0));
        let phi = GOLDEN * j as f32;
        *o = (axis * z + (u * libm::cosf(phi) + v * libm::sinf(phi)) * r).normalize();
    }
    m
}
