//! Handing the finished solution to the sink: every input polygon in global-id order, its
//! leaf patches first, then its area-weighted means (buried parts count as dark). With the
//! final gather on, a polygon's irradiance is its own gathered light (see `final_gather`)
//! and its radiosity follows from its material.

use super::emitters::{Emitters, emitters_through};
use super::exec::{Executor, Fallback, Progress, run_chunks};
use super::final_gather::polygon as gather_polygon;
use super::gather_rays::rays_per_side;
use super::ids::Elem;
use super::layout::CHUNK;
use super::state::State;
use super::vis::{Ray, Vis, WsPolygons};
use crate::limits::MAX_BANDS;
use crate::sink::{PatchResult, PolygonResult, Sink};
use crate::visibility::Visibility;
use core::sync::atomic::{AtomicBool, Ordering};
use glam::Vec3;

/// What the output pass measured: the power absorbed by the receiving sides as written (W
/// per band; `None` without a final gather, when the solution's own balance stands) and the
/// rays it cast.
pub(crate) struct Written {
    pub absorbed: Option<[f64; MAX_BANDS]>,
    pub rays: u64,
    /// The progress asked to stop ([`Progress::cancelled`]): the polygons from some batch
    /// on were neither gathered nor handed over.
    pub cancelled: bool,
}

/// The output phase's name for progress reports: the polygons' final gather and their
/// hand-over to the sink run chunk by chunk together.
const GATHER_PHASE: &str = "final gather: polygons and output (polygons)";
const WRITE_PHASE: &str = "writing (polygons)";

/// The name under which the output pass reports its progress.
pub(crate) fn phase(st: &State, ws: &[u8]) -> &'static str {
    if rays_per_side(st, ws) > 0 {
        GATHER_PHASE
    } else {
        WRITE_PHASE
    }
}

struct Ctx<'a, 'v, V: ?Sized> {
    st: &'a State,
    ws: &'a [u8],
    vis: &'a Vis<'v, V>,
    em: Emitters,
    rays: u32,
}

/// Hands every polygon to `sink`, gathering each one's light first when the settings ask
/// for a final gather (chunks of polygons in parallel, handed over in order).
pub(crate) fn emit<K: Sink, V: Visibility + ?Sized, E: Executor>(
    st: &State,
    ws: &[u8],
    vis: &Vis<'_, V>,
    ex: &mut Fallback<'_, E>,
    progress: &mut dyn Progress,
    sink: &mut K,
) -> Result<Written, K::Error> {
    emit_range(st, ws, vis, ex, progress, sink, 0, st.polygons, 0)
}

/// [`emit`] for the `count` polygons from `first` on, each handed over with its index plus
/// `id_offset` as its global id (a level of hierarchical instantiation: its polygons'
/// global ids leave room for its instances' contents).
#[allow(clippy::too_many_arguments)]
pub(crate) fn emit_range<K: Sink, V: Visibility + ?Sized, E: Executor>(
    st: &State,
    ws: &[u8],
    vis: &Vis<'_, V>,
    ex: &mut Fallback<'_, E>,
    progress: &mut dyn Progress,
    sink: &mut K,
    first: u32,
    count: u32,
    id_offset: u64,
) -> Result<Written, K::Error> {
    let nb = st.bands;
    let rays = rays_per_side(st, ws);
    let mut ctx = Ctx {
        st,
        ws,
        vis,
        em: emitters_through(st, ws, vis),
        rays,
    };
    let per = 2 * nb + 1;
    let n = count.min(st.polygons.saturating_sub(first)) as usize;
    let first = first as usize;
    let mut failed: Option<K::Error> = None;
    let mut absorbed = [0.0f64; MAX_BANDS];
    // Set once the progress asks to stop: the batches left do nothing.
    let stop = AtomicBool::new(false);
    // Polygons handed over: fewer than `n` without a sink failure means the run was
    // stopped (by the progress, or by an executor that skipped batches).
    let mut handed = 0usize;
    let mut cast = 0u64;
    run_chunks(
        ex,
        &mut ctx,
        n.div_ceil(CHUNK),
        CHUNK * per,
        |c: &Ctx<'_, '_, V>, chunk, buf| {
            buf.fill(0.0);
            if c.rays == 0 || stop.load(Ordering::Relaxed) {
                return;
            }
            let ray = Ray {
                vis: c.vis,
                polys: WsPolygons { st: c.st, ws: c.ws },
            };
            for (slot, i) in (chunk * CHUNK..((chunk + 1) * CHUNK).min(n)).enumerate() {
                let o = &mut buf[slot * per..(slot + 1) * per];
                let i = first + i;
                let r = gather_polygon(c.st, c.ws, &ray, i as u32, c.rays, &c.em, &mut o[1..]);
                o[0] = r as f32;
            }
        },
        |c: &mut Ctx<'_, '_, V>, chunk, buf| {
            for (slot, i) in (chunk * CHUNK..((chunk + 1) * CHUNK).min(n)).enumerate() {
                if failed.is_some() || stop.load(Ordering::Relaxed) {
                    return;
                }
                let o = &buf[slot * per..(slot + 1) * per];
                let gathered = (c.rays > 0).then(|| &o[1..]);
                cast += o[0] as u64;
                let i = (first + i) as u32;
                match polygon(c.st, c.ws, i, id_offset, gathered, sink, &mut absorbed) {
                    Ok(()) => handed += 1,
                    Err(e) => failed = Some(e),
                }
            }
        },
        &mut |done, total| {
            progress.report(
                if rays > 0 { GATHER_PHASE } else { WRITE_PHASE },
                (done * CHUNK).min(n) as u64,
                (total * CHUNK).min(n) as u64,
            );
            // A request after the last batch stops nothing: every polygon is out.
            if done < total && progress.cancelled() {
                stop.store(true, Ordering::Relaxed);
            }
        },
    );
    if let Some(e) = failed {
        return Err(e);
    }
    Ok(Written {
        absorbed: (rays > 0).then_some(absorbed),
        rays: cast,
        cancelled: handed < n,
    })
}

/// Hands polygon `i` (its leaf patches, then its means) to `sink`; with `gathered` (its
/// final gather, per side and band, without suns and sky) its irradiance is that plus its
/// patches' direct light. Adds what its receiving sides absorb to `absorbed`.
fn polygon<K: Sink>(
    st: &State,
    ws: &[u8],
    i: u32,
    id_offset: u64,
    gathered: Option<&[f32]>,
    sink: &mut K,
    absorbed: &mut [f64; MAX_BANDS],
) -> Result<(), K::Error> {
    let nb = st.bands;
    let poly = st.polygon(ws, i);
    let root = Elem(poly.root);
    let sides = State::sides(root);
    let normal = Vec3::from(poly.normal);
    let m = st.material(ws, poly.material);
    let (mut b_sum, mut h_sum) = ([[0.0f64; 8]; 2], [[0.0f64; 8]; 2]);
    let mut d_sum = [[0.0f64; 8]; 2];
    let mut area = 0.0f64;
    for (e, p) in st.leaves(ws, root) {
        let mut corners = [Vec3::ZERO; 4];
        for (c, src) in corners.iter_mut().zip(p.corners) {
            *c = src.into();
        }
        let front = st.b(ws, e, 0).unwrap_or(&[]);
        let back = if sides == 2 {
            st.b(ws, e, 1).unwrap_or(&[])
        } else {
            &[]
        };
        sink.patch(&PatchResult {
            id: i as u64 + id_offset,
            corners: &corners[..p.corner_count()],
            normal,
            material: poly.material,
            radiosity: [front, back],
        })?;
        // Buried parts receive nothing and show only their emission.
        let a = p.area as f64;
        let seen = a * p.exposed as f64;
        area += a;
        for side in 0..sides {
            let b = st.b(ws, e, side).unwrap_or(&[]);
            let mut h = [0.0f32; 8];
            super::closure::leaf_irradiance(st, ws, e, side, &mut h[..nb]);
            for k in 0..nb {
                let bk = b.get(k).copied().unwrap_or(0.0) as f64;
                b_sum[side][k] += seen * bk + (a - seen) * m.emit[side][k] as f64;
                h_sum[side][k] += seen * h[k] as f64;
            }
            if let Some(d) = st.direct(ws, e, side) {
                for (ds, dk) in d_sum[side][..nb].iter_mut().zip(d) {
                    *ds += seen * *dk as f64;
                }
            }
        }
    }
    let inv = if area > 0.0 { 1.0 / area } else { 0.0 };
    let mut b = [[0.0f32; 8]; 2];
    let mut h = [[0.0f32; 8]; 2];
    for side in 0..sides {
        for k in 0..nb {
            b[side][k] = (b_sum[side][k] * inv) as f32;
            h[side][k] = (h_sum[side][k] * inv) as f32;
        }
    }
    if let Some(g) = gathered {
        // The polygon's own light: gathered, plus the direct light of its patches.
        for side in 0..sides {
            for k in 0..nb {
                // Never below zero (in an opened level, the light through links comes off
                // the gathered light, and both are estimates).
                h[side][k] = (g[side * nb + k] + (d_sum[side][k] * inv) as f32).max(0.0);
            }
        }
        for side in 0..sides {
            for k in 0..nb {
                let other = if sides == 2 { h[1 - side][k] } else { 0.0 };
                b[side][k] = m.emit[side][k] + m.rho[side][k] * h[side][k] + m.tau[k] * other;
            }
        }
    }
    for (side, hs) in h.iter().enumerate().take(sides) {
        for k in 0..nb {
            let absorb = 1.0 - m.rho[side][k] as f64 - m.tau[k] as f64;
            absorbed[k] += area * absorb * hs[k] as f64;
        }
    }
    let back = if sides == 2 { nb } else { 0 };
    sink.polygon(&PolygonResult {
        id: i as u64 + id_offset,
        area: st.patch(ws, root).area,
        two_sided: sides == 2,
        radiosity: [&b[0][..nb], &b[1][..back]],
        irradiance: [&h[0][..nb], &h[1][..back]],
    })?;
    Ok(())
}
