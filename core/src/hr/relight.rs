//! The relighting passes of the final gather, before the polygons' own: every leaf patch
//! gathers its light from rays into the solution as the polygons will (see `final_gather`),
//! the first pass hands what changed back to the hierarchy's links (a defect correction),
//! and the passes go on until the light leaving the surfaces settles.

use super::emitters::{Emitters, emitters_through};
use super::exec::{Executor, Fallback, Progress, run_chunks};
use super::final_gather::{leaf, leaf_grid, patch_corners};
use super::gather_rays::{adaptive_rays, gathered_share, polygon_rays, rays_per_side};
use super::ids::{Elem, Kind};
use super::layout::CHUNK;
use super::state::State;
use super::vis::{Ray, Vis, WsPolygons};
use crate::limits::{MAX_BANDS, NONE};
use crate::sampling::hash3;
use crate::visibility::Visibility;
use glam::Vec3;

/// A relighting pass that moves the light leaving the surfaces by less than this fraction of
/// what enters ends the passes when their number is automatic: the power balance after the
/// polygons' gather measures about the next pass's move, which is smaller again (a 20 x 60
/// maize canopy's NIR moved 1.0%, 0.6%, 0.4% in its second to fourth passes).
pub(crate) const SETTLED: f32 = 0.005;

/// The light leaving every exposed leaf side and what enters the scene (emitted, and the
/// direct light of suns and sky on the receiving sides), per band (W).
#[derive(Clone, Copy, Debug, Default)]
struct Leaving {
    out: [f64; MAX_BANDS],
    input: [f64; MAX_BANDS],
}

impl Leaving {
    /// The largest change of any band's leaving light from `before`, relative to what enters.
    fn change_from(&self, before: &Leaving, bands: usize) -> f32 {
        let mut worst = 0.0f64;
        for b in 0..bands {
            if self.input[b] > 0.0 {
                worst = worst.max((self.out[b] - before.out[b]).abs() / self.input[b]);
            }
        }
        worst as f32
    }
}

/// Sums [`Leaving`] over the leaf patches as the solution stands.
fn leaving_power(st: &State, ws: &[u8]) -> Leaving {
    let nb = st.bands;
    let mut sum = Leaving::default();
    for kind in [Kind::Patch1, Kind::Patch2] {
        for i in 0..st.pool(kind).len {
            let e = Elem::new(kind, i);
            let p = st.patch(ws, e);
            if p.first_child != NONE {
                continue;
            }
            let seen = (p.area * p.exposed) as f64;
            let m = st.material(ws, st.polygon(ws, p.poly).material);
            for side in 0..State::sides(e) {
                let b = st.b(ws, e, side);
                let d = st.direct(ws, e, side);
                for k in 0..nb {
                    sum.out[k] += seen * b.map_or(0.0, |b| b[k]) as f64;
                    sum.input[k] += seen * (m.emit[side][k] + d.map_or(0.0, |d| d[k])) as f64;
                }
            }
        }
    }
    sum
}

/// The relighting passes before the polygons' gather: as many as the settings ask, or
/// (for [`super::settings::Settings::AUTO`]) until one moves the leaving light by less than
/// [`SETTLED`] of what enters, at most `State::most_passes` passes in all
/// ([`super::settings::MAX_FINAL_PASSES`], or an opened level's parent's). Records the
/// passes (the polygons' own included), the last pass's move and the rays in the stats.
///
/// An opened level takes no more passes than its parent: a level of a few hundred polygons
/// does not settle by this test, as its passes' own samples move its leaving light by 1-2%
/// (noise, not convergence; the whole scene's sum averages it away), and what reaches it
/// from the levels around is no input here (it arrives by the gather's rays). The paper
/// poplar's branches took 1 to 3 relighting passes where the whole scene (and hr) took one.
pub(crate) fn relight_passes<V: Visibility + ?Sized, E: Executor>(
    st: &mut State,
    ws: &mut [u8],
    vis: &Vis<'_, V>,
    ex: &mut Fallback<'_, E>,
    progress: &mut dyn Progress,
) {
    let asked = st.settings.final_passes;
    let auto = asked == super::settings::Settings::AUTO;
    let passes = if auto {
        st.most_passes.clamp(1, super::settings::MAX_FINAL_PASSES)
    } else {
        asked
    };
    if passes > 1 {
        // Without room for them the passes relight otherwise: the budget limited the
        // result, which a level opened as a job must say (it is then opened again alone, as
        // on one thread), or its results would depend on the size of its part.
        if !st.take_corrections(ws) {
            st.stats.budget_limited = true;
        }
        st.stats.peak_bytes = st.stats.peak_bytes.max(st.bytes_in_use() as u64);
    }
    let mut before = leaving_power(st, ws);
    for pass in 1..passes {
        if progress.cancelled() {
            return;
        }
        // What the closed instances show gather rays, as the last solution left them.
        super::blockers::note_radiance(st, ws, ex);
        // What an opened level's rays read of its own light among its siblings.
        if matches!(vis, Vis::Nested(..)) {
            super::local_field::note(st, ws);
        }
        let rays = relight(st, ws, vis, ex, progress, pass - 1);
        st.stats.rays += rays;
        st.stats.rays_by_phase.final_gather += rays;
        let after = leaving_power(st, ws);
        st.stats.final_change = after.change_from(&before, st.bands);
        st.stats.final_passes = pass;
        before = after;
        if auto && st.stats.final_change < SETTLED {
            break;
        }
    }
    st.stats.final_passes += 1;
}

struct Ctx<'a, 'v, V: ?Sized> {
    st: &'a mut State,
    ws: &'a mut [u8],
    vis: &'a Vis<'v, V>,
    em: Emitters,
    rays: u32,
    pass: u32,
}

/// One pass of the gather over every leaf patch before the polygons' own: each leaf's
/// irradiance from its own rays into the solution (as `final_gather::polygon` samples it), then the
/// radiosities follow from the materials and are averaged up the hierarchy. What a leaf
/// shows others then carries its own visibility, not its links' average, so the final
/// gather reads better radiosities (a Jacobi step with exact visibility; the links' error
/// shrinks by about the reflectance).
///
/// The gathered light is kept as a correction of each leaf side's irradiance (gathered less
/// what the links bring, see `State::correction`), and the first pass hands it to the
/// solver: the links carry the change on to everything it lights (a defect correction: the
/// hierarchy's transport, wrong locally but right in the large, solves for the change). A
/// Jacobi step moves the light of a canopy of NIR albedo 0.9 by only 35-40% of the way per
/// pass (the default maize canopy was still moving 1% after four); corrected, one pass
/// lands within 0.1% of the balance. Later passes are plain Jacobi steps: the correction
/// also carries the samples' noise, which the links spread in rooms of bright walls (their
/// moves went 3.5%, 0.5%, 1.6% with every pass corrected). Without workspace blocks left
/// for the corrections, every pass is a Jacobi step. Pass `pass` (from 0) draws samples of
/// its own: passes that cast the same rays iterate one sampled transport to its fixed point,
/// whose inverse
/// amplifies the samples' errors into light that no emitter sent (a room at 64 rays made
/// 1.5% more light with four passes than with two). Returns the rays cast.
fn relight<V: Visibility + ?Sized, E: Executor>(
    st: &mut State,
    ws: &mut [u8],
    vis: &Vis<'_, V>,
    ex: &mut Fallback<'_, E>,
    progress: &mut dyn Progress,
    pass: u32,
) -> u64 {
    let full = rays_per_side(st, ws);
    if full == 0 {
        return 0;
    }
    // Half the polygons' rays: what a leaf patch gathers here is read by the rays of many
    // polygons, which average its noise, and with up to three passes before the polygons'
    // own the gather's time doubled. Measured on 2026-12-03, full -> half: the worst of the
    // random scenes of `tests/hr_physics.rs` (a 2.5 cm lamp 200 m over a 790 m floor, few
    // rays meet what it lights) 0.68% -> 1.53%; the maize 2 x 2 per triangle (median 1.4%,
    // p90 7.7% NIR) and the rooms' and canopies' balance the same within 0.15%.
    let rays = (full / 2).max(1);
    let nb = st.bands;
    let per = 1 + 2 * nb;
    let em = emitters_through(st, ws, vis);
    let mut cast = 0u64;
    // Both pools under one phase: the count runs on over them.
    let all = st.pool(Kind::Patch1).len as u64 + st.pool(Kind::Patch2).len as u64;
    let mut offset = 0u64;
    for kind in [Kind::Patch1, Kind::Patch2] {
        let n = st.pool(kind).len as usize;
        let mut ctx = Ctx {
            st: &mut *st,
            ws: &mut *ws,
            vis,
            em,
            rays,
            pass,
        };
        run_chunks(
            ex,
            &mut ctx,
            n.div_ceil(CHUNK),
            CHUNK * per,
            |c: &Ctx<'_, '_, V>, chunk, buf| {
                buf.fill(0.0);
                let ray = Ray {
                    vis: c.vis,
                    polys: WsPolygons { st: c.st, ws: c.ws },
                };
                for (slot, i) in (chunk * CHUNK..((chunk + 1) * CHUNK).min(n)).enumerate() {
                    let e = Elem::new(kind, i as u32);
                    let p = c.st.patch(c.ws, e);
                    let o = &mut buf[slot * per..(slot + 1) * per];
                    if p.first_child != NONE {
                        o[0] = f32::NAN;
                        continue;
                    }
                    let rec = c.st.polygon(c.ws, p.poly);
                    let total = c.st.patch(c.ws, Elem(rec.root)).area;
                    let (corners, k) = patch_corners(c.st, c.ws, e);
                    let normal = Vec3::from(rec.normal);
                    let mut cast = 0u32;
                    for side in 0..State::sides(e) {
                        let share = gathered_share(c.st, c.ws, core::iter::once(e), side);
                        let side_rays = adaptive_rays(polygon_rays(c.st, c.rays, total), share);
                        if side_rays == 0 {
                            // Nothing to gather: keep what the links bring (nothing).
                            let mut h = [0.0f32; 8];
                            super::closure::leaf_irradiance(c.st, c.ws, e, side, &mut h[..nb]);
                            if let Some(d) = c.st.direct(c.ws, e, side) {
                                for (hv, dv) in h.iter_mut().zip(d) {
                                    *hv -= dv;
                                }
                            }
                            for (dst, v) in o[1 + side * nb..1 + (side + 1) * nb].iter_mut().zip(&h)
                            {
                                *dst = *v;
                            }
                            continue;
                        }
                        let g = leaf_grid(side_rays, p.area, total);
                        let nrm = if side == 0 { normal } else { -normal };
                        let seed = hash3(e.0, side as u32 | c.pass << 1, 0x4E11);
                        let mut h = [0.0f64; 8];
                        cast += leaf(
                            c.st,
                            c.ws,
                            &ray,
                            p.poly,
                            &corners[..k],
                            nrm,
                            g,
                            seed,
                            &c.em,
                            &mut h[..nb],
                        );
                        // As `final_gather::polygon`: the light through links was gathered.
                        if let Some(l) = c.st.linked(c.ws, e, side) {
                            for (hb, lb) in h[..nb].iter_mut().zip(l) {
                                *hb -= *lb as f64;
                            }
                        }
                        for (d, v) in o[1 + side * nb..1 + (side + 1) * nb].iter_mut().zip(&h) {
                            *d = *v as f32;
                        }
                    }
                    o[0] = cast as f32;
                }
            },
            |c: &mut Ctx<'_, '_, V>, chunk, buf| {
                for (slot, i) in (chunk * CHUNK..((chunk + 1) * CHUNK).min(n)).enumerate() {
                    let o = &buf[slot * per..(slot + 1) * per];
                    if o[0].is_nan() {
                        continue;
                    }
                    cast += o[0] as u64;
                    let e = Elem::new(kind, i as u32);
                    if c.st.correction != NONE as usize {
                        // The correction that makes the irradiance read what was gathered (plus
                        // direct) with the links as they stand: the gathered light less
                        // what the links bring.
                        for side in 0..State::sides(e) {
                            let mut now = [0.0f32; 8];
                            super::closure::leaf_irradiance(c.st, c.ws, e, side, &mut now[..nb]);
                            let mut d = [0.0f32; 8];
                            if let Some(v) = c.st.direct(c.ws, e, side) {
                                d[..nb].copy_from_slice(v);
                            }
                            let g = &o[1 + side * nb..1 + (side + 1) * nb];
                            if let Some(corr) = c.st.correction_mut(c.ws, e, side) {
                                for b in 0..nb {
                                    let links = now[b] - d[b] - corr[b];
                                    corr[b] = g[b] - links;
                                }
                            }
                        }
                        continue;
                    }
                    let p = c.st.patch(c.ws, e);
                    // leaf_irradiance reads (1 + closure) (h + the polygon's share of cluster
                    // links) + direct: set h so that it reads the gathered light + direct.
                    for side in 0..State::sides(e) {
                        let scale = 1.0 + p.closure[side.min(1)];
                        if scale.abs() < 1e-6 {
                            continue;
                        }
                        let mut hc = [0.0f32; 8];
                        hc[..nb].copy_from_slice(c.st.polygon_h(c.ws, p.poly, side));
                        let g = &o[1 + side * nb..1 + (side + 1) * nb];
                        for ((h, gv), hcv) in c.st.h_mut(c.ws, e, side).iter_mut().zip(g).zip(&hc) {
                            *h = gv / scale - hcv;
                        }
                    }
                }
            },
            &mut |done, total| {
                progress.report(
                    "final gather: relighting patches (patches)",
                    offset + (done * CHUNK).min(n) as u64,
                    all.max(offset + (total * CHUNK).min(n) as u64),
                )
            },
        );
        offset += n as u64;
    }
    super::correction_filter::filter_corrections(st, ws, rays);
    if st.correction != NONE as usize && pass < CORRECTED_PASSES {
        // The links carry the change to everything it lights (a defect correction).
        let tol = st.settings.tolerance;
        super::solve::iterate(st, ws, ex, &mut Relabel(progress), tol);
    } else {
        super::solve::pull(st, ws);
    }
    cast
}

/// Relighting passes whose change the links carry on (see `relight`): the first.
const CORRECTED_PASSES: u32 = 1;

/// The solver's iterations inside the final gather, reported as part of it.
struct Relabel<'a>(&'a mut dyn Progress);

impl Progress for Relabel<'_> {
    fn report(&mut self, what: &str, done: u64, total: u64) {
        let what = if what.starts_with("solving") {
            "final gather: solving again (iterations)"
        } else {
            what
        };
        self.0.report(what, done, total)
    }

    fn cancelled(&mut self) -> bool {
        self.0.cancelled()
    }
}
