//! The final gather: every input polygon's irradiance from rays of its own into the solved
//! scene, so that each polygon gets the light its own position, orientation and side see.
//!
//! The hierarchy gets radiosities right where they come from, but a polygon that receives
//! through a coarse link (a cluster's share by its cosine, a floor's mean beside a contact
//! shadow, a few visibility rays for a whole plant) gets its link's average: right on
//! average, wrong by tens of percent for one stem or one shaded leaf. Here each receiving
//! side of each polygon casts stratified, cosine-distributed rays from stratified points and
//! takes, for each, the solved radiosity of the patch it meets (its side; nothing from the
//! back of a one-sided polygon or from outside the scene). Emission is taken apart where
//! there are few emitting polygons: rays count only what the hit reflects, and each point
//! adds the light of the emitting polygons directly (exact unoccluded form factor times a
//! visibility ray), so a small bright lamp costs no noise. The light of suns and sky is the
//! patches' own direct light (see `direct`).
//!
//! Samples come from hashes of the polygon and the sample number: results never depend on
//! the thread count.

use super::direct::{coprime_stride, cosine_direction, jacobian, mean_jacobian};
use super::exec::{Executor, Fallback, Progress, run_chunks};
use super::gather_rays::{adaptive_rays, gathered_share, polygon_rays, rays_per_side};
use super::ids::{Elem, Kind};
use super::layout::CHUNK;
use super::state::State;
use super::vis::{Ray, Vis, WsPolygons};
use crate::formfactor::{facing_side, point_polygon};
use crate::limits::{MAX_BANDS, NONE};
use crate::sampling::{MAX_QUADRATURE, hash3, point_on, quadrature, unit2};
use crate::visibility::Visibility;
use glam::Vec3;

/// Emitting polygons up to which each leaf weighs every one of them; with more, each sample
/// draws one down the cluster tree (see `emitter_tree`).
pub(crate) const MAX_DIRECT_EMITTERS: usize = 64;

/// The emitting polygons whose light is added directly, each weighed by every leaf, or none
/// when there are more than [`MAX_DIRECT_EMITTERS`] (then `count` is 0, `direct` false and
/// `tree` true: each sample draws one emitter down the cluster tree).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Emitters {
    pub ids: [u32; MAX_DIRECT_EMITTERS],
    pub count: usize,
    pub direct: bool,
    pub tree: bool,
}

impl Emitters {
    /// True when emission is added directly, not gathered by the rays.
    fn apart(&self) -> bool {
        self.direct || self.tree
    }
}

/// Finds the scene's emitting polygons (see [`Emitters`]).
pub(crate) fn emitters(st: &State, ws: &[u8]) -> Emitters {
    let mut out = Emitters {
        ids: [NONE; MAX_DIRECT_EMITTERS],
        count: 0,
        direct: true,
        tree: false,
    };
    for i in 0..st.polygons {
        let m = st.material(ws, st.polygon(ws, i).material);
        let emits = (0..st.bands).any(|b| m.emit[0][b] > 0.0 || m.emit[1][b] > 0.0);
        if emits {
            if out.count == MAX_DIRECT_EMITTERS {
                return Emitters {
                    ids: [NONE; MAX_DIRECT_EMITTERS],
                    count: 0,
                    direct: false,
                    tree: true,
                };
            }
            out.ids[out.count] = i;
            out.count += 1;
        }
    }
    out
}

/// Gathers polygon `poly`'s irradiance (W/m^2, per side and band, the mean over its whole
/// area) into `out[side * bands + band]`, without the direct light of suns and sky. Returns
/// the rays cast.
///
/// The samples are spread over the polygon's leaf patches by area, at least one per leaf:
/// the hierarchy subdivided where the light varies (beside a lamp, at a shadow edge), so a
/// peak that uniform samples of a large polygon would miss gets its own.
pub(crate) fn polygon<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    vis: &V,
    poly: u32,
    rays: u32,
    em: &Emitters,
    out: &mut [f32],
) -> u32 {
    let nb = st.bands;
    out.fill(0.0);
    let rec = st.polygon(ws, poly);
    let root = Elem(rec.root);
    let total_area = st.patch(ws, root).area as f64;
    let normal = Vec3::from(rec.normal);
    let mut cast = 0u32;
    let mut sums = [[0.0f64; 8]; 2];
    let mut area = 0.0f64;
    let mut leaf_no = 0u32;
    let mut side_rays = [0u32; 2];
    for (side, r) in side_rays.iter_mut().enumerate().take(State::sides(root)) {
        *r = adaptive_rays(
            polygon_rays(st, rays, total_area as f32),
            gathered_share(st, ws, st.leaves(ws, root).map(|l| l.0), side),
        );
    }
    for (e, p) in st.leaves(ws, root) {
        let (corners, k) = patch_corners(st, ws, e);
        let a = p.area as f64;
        area += a;
        leaf_no += 1;
        for (side, sum) in sums.iter_mut().enumerate().take(State::sides(root)) {
            if side_rays[side] == 0 {
                continue;
            }
            let g = leaf_grid(side_rays[side], p.area, total_area as f32);
            let nrm = if side == 0 { normal } else { -normal };
            let seed = hash3(poly, leaf_no, 0xF1A1 + side as u32);
            let mut c = [0.0f64; 8];
            cast += leaf(
                st,
                ws,
                vis,
                poly,
                &corners[..k],
                nrm,
                g,
                seed,
                em,
                &mut c[..nb],
            );
            for (sb, cb) in sum[..nb].iter_mut().zip(&c[..nb]) {
                *sb += a * cb;
            }
        }
    }
    if area > 0.0 {
        for side in 0..State::sides(root) {
            for b in 0..nb {
                out[side * nb + b] = (sums[side][b] / area) as f32;
            }
        }
    }
    cast
}

/// Samples along each side of the grid of a leaf patch of area `leaf` (m^2) in a polygon
/// of area `polygon`: its share by area of `rays`, at least one.
fn leaf_grid(rays: u32, leaf: f32, polygon: f32) -> u32 {
    let share = if polygon > 0.0 {
        rays as f64 * leaf as f64 / polygon as f64
    } else {
        rays as f64
    };
    libm::ceil(libm::sqrt(share)).max(1.0) as u32
}

/// The mean irradiance over one leaf patch (`corners`) on the side facing `nrm`, from
/// `g x g` samples: points on one stratified grid, cosine-distributed directions on another,
/// paired through a coprime stride. Returns the rays cast.
#[allow(clippy::too_many_arguments)]
fn leaf<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    vis: &V,
    poly: u32,
    corners: &[Vec3],
    nrm: Vec3,
    g: u32,
    seed: u32,
    em: &Emitters,
    out: &mut [f64],
) -> u32 {
    let nb = st.bands;
    let n = g * g;
    let mj = mean_jacobian(corners);
    let stride = coprime_stride(n, hash3(seed, 1, 0x57));
    let mut weight = 0.0f64;
    let mut cast = 0u32;
    let mut shares = [Share::default(); MAX_DIRECT_EMITTERS];
    let total = if em.direct {
        emitter_shares(st, ws, poly, corners, nrm, em, &mut shares)
    } else {
        0.0
    };
    let cut = if em.tree {
        let centre = corners.iter().copied().sum::<Vec3>() / corners.len() as f32;
        Some(super::emitter_tree::cut(st, ws, centre, nrm, poly)).filter(|c| !c.is_empty())
    } else {
        None
    };
    for j in 0..n {
        let cell = ((j as u64 * stride as u64) % n as u64) as u32;
        let (ju, jv) = unit2(hash3(seed, j, 0xA3));
        let u = ((cell % g) as f32 + ju) / g as f32;
        let v = ((cell / g) as f32 + jv) / g as f32;
        let x = point_on(corners, u, v);
        let w = (jacobian(corners, u, v) / mj) as f64;
        weight += w;
        let (du, dv) = unit2(hash3(seed, j, 0xD7));
        let du = ((j % g) as f32 + du) / g as f32;
        let dv = ((j / g) as f32 + dv) / g as f32;
        let d = cosine_direction(nrm, du, dv);
        let mut c = [0.0f32; 8];
        cast += 1;
        let end = st.beyond(x, d);
        if let Some((hit, t)) = vis.first_hit(x, end, [poly, NONE])
            && hit < st.polygons
        {
            let y = x + (end - x) * t;
            let hp = st.polygon(ws, hit);
            let front = Vec3::from(hp.normal).dot(d) < 0.0;
            let hroot = Elem(hp.root);
            let hside = if front { 0 } else { 1 };
            if hside < State::sides(hroot) {
                let at = leaf_at(st, ws, hroot, y, Vec3::from(hp.normal));
                let m = st.material(ws, hp.material);
                if let Some(b) = st.b(ws, at, hside) {
                    for k in 0..nb {
                        let e = if em.apart() { m.emit[hside][k] } else { 0.0 };
                        c[k] = (b[k] - e).max(0.0);
                    }
                }
            }
        }
        if let Some(cut) = &cut {
            let h = hash3(seed, j, 0xE3);
            let pick = (j as f64 + unit2(h).0 as f64) / n as f64;
            let leaf = Receiver { poly, nrm, x };
            cast += super::emitter_tree::light(st, ws, vis, &leaf, cut, pick, h, &mut c[..nb]);
        } else if total > 0.0 {
            let h = hash3(seed, j, 0xE3);
            let pick = (j as f32 + unit2(h).0) / n as f32;
            let leaf = Receiver { poly, nrm, x };
            cast += emitted_light(
                st,
                ws,
                vis,
                &leaf,
                em,
                &shares,
                total,
                pick,
                h,
                &mut c[..nb],
            );
        }
        for k in 0..nb {
            out[k] += w * c[k] as f64;
        }
    }
    if weight > 0.0 {
        for o in out.iter_mut() {
            *o /= weight;
        }
    }
    cast
}

/// One emitting polygon as a leaf patch sees it: its importance (largest exitance x
/// estimated unoccluded form factor from the leaf), the side it shows, and whether its light
/// is integrated from the emitter's side (an emitter no larger than the leaf: reciprocity,
/// smooth where a point-by-point form factor would peak under a small lamp).
#[derive(Clone, Copy, Debug, Default)]
struct Share {
    weight: f32,
    side: usize,
    reciprocal: bool,
    /// For `reciprocal`: the emitter's form factor to the whole leaf times its area over the
    /// leaf's, over the emitter's quadrature points (the form factor to a leaf whose edge
    /// passes under a small lamp changes across the lamp). It does not depend on the
    /// sample point.
    f_leaf: f32,
}

/// A sample point of a receiving leaf patch of polygon `poly`, facing `nrm`.
pub(crate) struct Receiver {
    pub poly: u32,
    pub nrm: Vec3,
    pub x: Vec3,
}

/// Fills `shares` for a leaf patch (`corners`, receiving normal `nrm`); returns their sum.
fn emitter_shares(
    st: &State,
    ws: &[u8],
    poly: u32,
    corners: &[Vec3],
    nrm: Vec3,
    em: &Emitters,
    shares: &mut [Share; MAX_DIRECT_EMITTERS],
) -> f32 {
    let nb = st.bands;
    let centre = corners.iter().copied().sum::<Vec3>() / corners.len() as f32;
    let area = polygon_area(corners);
    let mut total = 0.0f32;
    for (s, &l) in shares.iter_mut().zip(&em.ids[..em.count]) {
        *s = Share::default();
        if l == poly {
            continue;
        }
        let lp = st.polygon(ws, l);
        let (lc, k) = patch_corners(st, ws, Elem(lp.root));
        let l_normal = Vec3::from(lp.normal);
        let Some(side) = facing_side(centre, lc[0], l_normal) else {
            continue;
        };
        let m = st.material(ws, lp.material);
        let e_max = m.emit[side][..nb].iter().copied().fold(0.0f32, f32::max);
        if e_max <= 0.0 {
            continue;
        }
        let l_area = polygon_area(&lc[..k]);
        let reciprocal = l_area <= area;
        let f = if reciprocal && area > 0.0 {
            let lcen = lc[..k].iter().copied().sum::<Vec3>() / k as f32;
            let ln = if side == 0 { l_normal } else { -l_normal };
            l_area * point_polygon(lcen, ln, corners) / area
        } else {
            point_polygon(centre, nrm, &lc[..k])
        };
        // Seen at the centre or not, a part of the emitter may show elsewhere on the leaf:
        // keep a floor so that it can still be drawn.
        let f = if f.is_finite() { f.max(1e-6) } else { 0.0 };
        let f_leaf = if reciprocal && area > 0.0 {
            let ln = if side == 0 { l_normal } else { -l_normal };
            let (mut pts, mut wts) = ([Vec3::ZERO; MAX_QUADRATURE], [0.0f32; MAX_QUADRATURE]);
            let q = quadrature(&lc[..k], &mut pts, &mut wts);
            let mut fq = 0.0f32;
            for (p, w) in pts[..q].iter().zip(&wts[..q]) {
                fq += w * point_polygon(*p, ln, corners);
            }
            l_area * fq / area
        } else {
            0.0
        };
        *s = Share {
            weight: e_max * f,
            side,
            reciprocal,
            f_leaf,
        };
        total += e_max * f;
    }
    total
}

/// The area of a planar triangle or quad (m^2).
fn polygon_area(c: &[Vec3]) -> f32 {
    let mut a = Vec3::ZERO;
    for i in 1..c.len() - 1 {
        a += (c[i] - c[0]).cross(c[i + 1] - c[0]);
    }
    0.5 * a.length()
}

/// Adds to `c` the irradiance at the leaf's sample from the emitting polygons: one emitter
/// drawn by its share (`pick` in [0, 1)), its light at the point (exact unoccluded form
/// factor from the point) or over the leaf (from a point of the emitter, by reciprocity),
/// times one visibility ray. Returns the rays cast.
#[allow(clippy::too_many_arguments)]
fn emitted_light<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    vis: &V,
    leaf: &Receiver,
    em: &Emitters,
    shares: &[Share; MAX_DIRECT_EMITTERS],
    total: f32,
    pick: f32,
    h: u32,
    c: &mut [f32],
) -> u32 {
    let nb = st.bands;
    let target = pick * total;
    let mut acc = 0.0f32;
    let mut chosen = NONE as usize;
    for (i, s) in shares[..em.count].iter().enumerate() {
        if s.weight > 0.0 {
            acc += s.weight;
            chosen = i;
            if target < acc {
                break;
            }
        }
    }
    if chosen == NONE as usize {
        return 0;
    }
    let share = shares[chosen];
    let l = em.ids[chosen];
    let lp = st.polygon(ws, l);
    let (lc, k) = patch_corners(st, ws, Elem(lp.root));
    let m = st.material(ws, lp.material);
    let (x, n) = (leaf.x, leaf.nrm);
    // A point of the emitter in front of x (a few draws: an emitter that straddles the
    // plane of x shows only part of itself).
    for attempt in 0..8u32 {
        let (u, v) = unit2(hash3(h, attempt, 0x9E));
        let y = point_on(&lc[..k], u, v);
        if n.dot(y - x) <= 0.0 {
            continue;
        }
        let f = if share.reciprocal {
            share.f_leaf
        } else {
            point_polygon(x, n, &lc[..k])
        };
        if !(f.is_finite() && f > 0.0) {
            return 1;
        }
        let t = vis.transmittance(x, y, [leaf.poly, l]);
        if t > 0.0 {
            let scale = t * f * total / share.weight;
            for (ck, e) in c.iter_mut().zip(&m.emit[share.side][..nb]) {
                *ck += scale * e;
            }
        }
        return 1;
    }
    0
}

/// A patch's corners and their count.
pub(crate) fn patch_corners(st: &State, ws: &[u8], e: Elem) -> ([Vec3; 4], usize) {
    let p = st.patch(ws, e);
    let mut corners = [Vec3::ZERO; 4];
    for (c, src) in corners.iter_mut().zip(p.corners) {
        *c = src.into();
    }
    (corners, p.corner_count())
}

/// The leaf patch of the quadtree under `root` that holds the point `y` of its plane (front
/// normal `n`): at each level the child that `y` lies deepest inside.
pub(crate) fn leaf_at(st: &State, ws: &[u8], root: Elem, y: Vec3, n: Vec3) -> Elem {
    let mut e = root;
    loop {
        let p = st.patch(ws, e);
        if p.first_child == NONE {
            return e;
        }
        let mut best = (f32::NEG_INFINITY, Elem::new(e.kind(), p.first_child));
        for j in 0..4 {
            let child = Elem::new(e.kind(), p.first_child + j);
            let (corners, k) = patch_corners(st, ws, child);
            // The child's own orientation (children keep their parent's, but a flipped input
            // corner order must not send the point to the wrong child).
            let own = (corners[1] - corners[0]).cross(corners[k - 1] - corners[0]);
            let n = if own.dot(n) < 0.0 { -n } else { n };
            let mut inside = f32::INFINITY;
            for i in 0..k {
                let (a, b) = (corners[i], corners[(i + 1) % k]);
                let edge = b - a;
                let len = edge.length();
                if len > 0.0 {
                    inside = inside.min(edge.cross(y - a).dot(n) / len);
                }
            }
            if inside > best.0 {
                best = (inside, child);
            }
        }
        e = best.1;
    }
}

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
/// (for [`super::Settings::AUTO`]) until one moves the leaving light by less than
/// [`SETTLED`] of what enters, at most [`super::MAX_FINAL_PASSES`] passes in all. Records
/// the passes (the polygons' own included), the last pass's move and the rays in the stats.
pub(crate) fn relight_passes<V: Visibility + ?Sized, E: Executor>(
    st: &mut State,
    ws: &mut [u8],
    vis: &Vis<'_, V>,
    ex: &mut Fallback<'_, E>,
    progress: &mut dyn Progress,
) {
    let asked = st.settings.final_passes;
    let auto = asked == super::Settings::AUTO;
    let passes = if auto { super::MAX_FINAL_PASSES } else { asked };
    if passes > 1 {
        st.take_corrections(ws);
        st.stats.peak_bytes = st.stats.peak_bytes.max(st.bytes_in_use() as u64);
    }
    let mut before = leaving_power(st, ws);
    for pass in 1..passes {
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
/// irradiance from its own rays into the solution (as [`polygon`] samples it), then the
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
/// its own: passes
/// that cast the same rays iterate one sampled transport to its fixed point, whose inverse
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
    let em = emitters(st, ws);
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
                    "final gather (patches)",
                    offset + (done * CHUNK).min(n) as u64,
                    all.max(offset + (total * CHUNK).min(n) as u64),
                )
            },
        );
        offset += n as u64;
    }
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
            "final gather (solving)"
        } else {
            what
        };
        self.0.report(what, done, total)
    }
}
