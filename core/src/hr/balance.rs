//! The power balance of a finished solve, per band: what enters (emitted by surfaces, direct
//! light of suns and sky that reaches a surface) against where it goes (absorbed by
//! surfaces, absorbed by the backs of one-sided polygons, escaping the scene).
//!
//! Absorption comes from the solution itself (`(1 - rho - tau) H` on every receiving side of
//! every exposed leaf). Where the light that leaves each leaf ends up is measured apart from
//! the links, by rays: from stratified points of every emitting leaf side, in stratified
//! cosine-distributed directions, a ray that meets nothing escapes, one that meets the back
//! of a one-sided polygon is absorbed there, any other is carried by the solution to a
//! receiver. So the imbalance `in - absorbed - escaped` is a real check of the transport: a
//! solution that hands out more light than its emitters send (close, badly integrated
//! links) shows a negative imbalance, one that loses light a positive one.

use super::exec::{Executor, Fallback, Progress, run_chunks};
use super::ids::{Elem, Kind};
use super::layout::CHUNK;
use super::records::Source;
use super::state::State;
use super::vis::{Ray, Vis, WsPolygons};
use crate::limits::{MAX_BANDS, NONE};
use crate::sampling::{hash3, point_on, unit2};
use crate::visibility::Visibility;
use glam::Vec3;

/// Power per band (W), with `bands` entries used.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Balance {
    /// Emitted by surfaces (exitance x area).
    pub emitted: [f64; MAX_BANDS],
    /// Direct light of suns and sky that reaches a surface (front, and back of two-sided
    /// polygons; the backs of one-sided polygons count under `absorbed_backs`).
    pub direct: [f64; MAX_BANDS],
    /// Absorbed by the receiving sides of surfaces.
    pub absorbed: [f64; MAX_BANDS],
    /// Absorbed by the backs of one-sided polygons (and by parts buried inside closed
    /// objects).
    pub absorbed_backs: [f64; MAX_BANDS],
    /// Leaving the scene.
    pub escaped: [f64; MAX_BANDS],
}

impl Balance {
    /// What enters minus what is absorbed or escapes, per band (W).
    pub fn imbalance(&self, band: usize) -> f64 {
        self.emitted[band] + self.direct[band]
            - self.absorbed[band]
            - self.absorbed_backs[band]
            - self.escaped[band]
    }

    /// The imbalance as a fraction of what enters (0 when nothing enters).
    pub fn relative_imbalance(&self, band: usize) -> f64 {
        let input = self.emitted[band] + self.direct[band];
        if input > 0.0 {
            self.imbalance(band) / input
        } else {
            0.0
        }
    }
}

impl Balance {
    /// Adds `other`'s powers to these, band by band.
    pub fn add(&mut self, other: &Balance) {
        for b in 0..MAX_BANDS {
            self.emitted[b] += other.emitted[b];
            self.direct[b] += other.direct[b];
            self.absorbed[b] += other.absorbed[b];
            self.absorbed_backs[b] += other.absorbed_backs[b];
            self.escaped[b] += other.escaped[b];
        }
    }
}

/// What a balance covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Scope {
    /// The whole scene in one level: its leaves and its closed instances (the light they
    /// scatter estimated from their tables), at least [`MIN_BUDGET`] rays.
    Scene,
    /// One level of hierarchical instantiation, its leaves only (each closed instance is
    /// counted by the level it opens into): a leaf's light escapes only if it leaves the
    /// scene through every level this one is open in; `rays` per leaf, no minimum, at most
    /// its leaves' share of [`MAX_BUDGET`] (the levels' sum is the solve's balance).
    Level,
}

struct Ctx<'a, 'v, V: ?Sized> {
    st: &'a State,
    ws: &'a [u8],
    vis: &'a Vis<'v, V>,
    out: Balance,
    scope: Scope,
}

/// Measures the balance of the current solution: `rays` per leaf on average, between
/// [`MIN_BUDGET`] and [`MAX_BUDGET`] in all, shared by the power that leaves each leaf (up to
/// [`MAX_RAYS`]), at least one per leaf side that sends light. The budget is capped because
/// the noise of the escaping total depends on the rays, not on the leaves: 262,144 rays
/// shared by power measure it within about 0.1% of the light, and 16 per leaf of a
/// 100,000-leaf tree cost seconds for nothing.
pub(crate) fn measure<V: Visibility + ?Sized, E: Executor>(
    st: &State,
    ws: &[u8],
    vis: &Vis<'_, V>,
    ex: &mut Fallback<'_, E>,
    rays: u32,
    scope: Scope,
    progress: &mut dyn Progress,
) -> Balance {
    let nb = st.bands;
    // The power leaving each leaf side sets its share of the rays.
    let mut total = 0.0f64;
    let mut leaves = 0u64;
    for kind in [Kind::Patch1, Kind::Patch2] {
        for i in 0..st.pool(kind).len {
            let e = Elem::new(kind, i);
            let p = st.patch(ws, e);
            if p.first_child == NONE {
                leaves += 1;
                total += leaving(st, ws, e, &p) as f64;
            }
        }
    }
    let budget = match scope {
        Scope::Scene => (rays as f64 * leaves as f64).clamp(MIN_BUDGET, MAX_BUDGET),
        // Its leaves' share of the scene's budget: the levels together cast about what hr
        // casts on the expanded scene (every level at 4 x rays per leaf cast ten times as
        // many on the paper poplar, 5% of its solve).
        Scope::Level => {
            let share = if st.scene_sides > 0 {
                (leaves as f64 / st.scene_sides as f64).min(1.0)
            } else {
                1.0
            };
            (rays as f64 * leaves as f64).min(MAX_BUDGET * share)
        }
    };
    let per_watt = if total > 0.0 { budget / total } else { 0.0 };
    let mut ctx = Ctx {
        st,
        ws,
        vis,
        out: Balance::default(),
        scope,
    };
    // Per leaf: escaping and back-absorbed fractions per side, and the back direct light of
    // one-sided polygons per band.
    let per = 4 + 2 * nb;
    // Both pools under one phase: the count runs on over them.
    let all = st.pool(Kind::Patch1).len as u64 + st.pool(Kind::Patch2).len as u64;
    let mut offset = 0u64;
    for kind in [Kind::Patch1, Kind::Patch2] {
        let n = st.pool(kind).len as usize;
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
                    if p.first_child != NONE || p.area * p.exposed <= 0.0 {
                        continue;
                    }
                    let o = &mut buf[slot * per..(slot + 1) * per];
                    let share = (per_watt * leaving(c.st, c.ws, e, &p) as f64) as u32;
                    let beyond = c.scope == Scope::Level;
                    fates(c.st, c.ws, e, share.clamp(1, MAX_RAYS), &ray, beyond, o);
                }
            },
            |c: &mut Ctx<'_, '_, V>, chunk, buf| {
                for (slot, i) in (chunk * CHUNK..((chunk + 1) * CHUNK).min(n)).enumerate() {
                    let e = Elem::new(kind, i as u32);
                    add_leaf(
                        c.st,
                        c.ws,
                        e,
                        &buf[slot * per..(slot + 1) * per],
                        &mut c.out,
                    );
                }
            },
            &mut |done, total| {
                progress.report(
                    "power balance (patches)",
                    offset + (done * CHUNK).min(n) as u64,
                    all.max(offset + (total * CHUNK).min(n) as u64),
                )
            },
        );
        offset += n as u64;
    }
    if st.instances > 0 && scope == Scope::Scene {
        let ray = Ray {
            vis,
            polys: WsPolygons { st, ws },
        };
        for i in 0..st.instances {
            add_instance(st, ws, i, rays.max(1) * INSTANCE_RAYS, &ray, &mut ctx.out);
        }
    }
    ctx.out
}

/// Rays per closed instance for its scattered light's fate, per ray of a leaf.
const INSTANCE_RAYS: u32 = 16;

/// Adds closed instance `i`'s part of the balance: the direct light it intercepts, what it
/// absorbs (intercepted less scattered out, all of it), and of what it scatters out, the
/// part that escapes: `rays` directions spread evenly over the sphere from points of its
/// box, each weighted by its intensity there, through the other closed instances' `tau`.
fn add_instance<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    i: u32,
    rays: u32,
    vis: &V,
    out: &mut Balance,
) {
    use crate::tables::closed::Received;
    let nb = st.bands;
    let placed = st.placed(ws, i);
    let Ok(all) = Received::over(&placed, st.received(ws, i)) else {
        return;
    };
    for b in 0..nb {
        // The intercepted power is the light's first value per band.
        out.direct[b] += st.direct_value(ws, i, b) as f64;
        out.absorbed[b] += all.absorbed(b) as f64;
    }
    let seed = hash3(i, 0xBA1, 0x1A);
    let mut escaped = [0.0f64; MAX_BANDS];
    let mut sent = [0.0f64; MAX_BANDS];
    for j in 0..rays {
        let (u, v) = unit2(hash3(seed, j, 0x22));
        let z = 1.0 - 2.0 * u;
        let r = libm::sqrtf((1.0 - z * z).max(0.0));
        let phi = core::f32::consts::TAU * v;
        let d = Vec3::new(r * libm::cosf(phi), r * libm::sinf(phi), z);
        let x = super::instance_kernel::point_of(st, ws, i, hash3(seed, j, 0x23));
        let end = st.beyond(x, d);
        let skip = [super::blockers::SKIP_INSTANCE | i, NONE];
        let t = if vis.first_hit(x, end, skip).is_none() {
            vis.transmittance(x, end, skip) as f64
        } else {
            0.0
        };
        let mut i_d = [0.0f32; MAX_BANDS];
        all.intensity_all(&placed, d, &mut i_d[..nb]);
        for b in 0..nb {
            let w = i_d[b] as f64;
            sent[b] += w;
            escaped[b] += w * t;
        }
    }
    for b in 0..nb {
        if sent[b] > 0.0 {
            out.escaped[b] += all.scattered(b) as f64 * escaped[b] / sent[b];
        }
    }
}

/// Most rays for one leaf side.
const MAX_RAYS: u32 = 16_384;
/// Rays for the whole scene at least, and at most (besides one per leaf side).
const MIN_BUDGET: f64 = 16_384.0;
const MAX_BUDGET: f64 = 262_144.0;

/// The largest band's power leaving a leaf (W, its sides together).
fn leaving(st: &State, ws: &[u8], e: Elem, p: &super::records::Patch) -> f32 {
    let mut w = 0.0f32;
    for side in 0..State::sides(e) {
        if let Some(b) = st.b(ws, e, side) {
            w += b.iter().copied().fold(0.0f32, f32::max);
        }
    }
    w * p.area * p.exposed
}

/// Adds one leaf's part of the balance. The direct light that came through the links of
/// the levels around (an opened level's binned beams, see `State::linked`) is light from
/// other surfaces, not what enters the scene: left out of `direct`.
fn add_leaf(st: &State, ws: &[u8], e: Elem, fate: &[f32], out: &mut Balance) {
    let nb = st.bands;
    let p = st.patch(ws, e);
    if p.first_child != NONE {
        return;
    }
    let m = st.material(ws, st.polygon(ws, p.poly).material);
    let area = p.area as f64;
    let seen = area * p.exposed as f64;
    for b in 0..nb {
        for side in 0..2 {
            let emit = m.emit[side][b] as f64;
            out.emitted[b] += area * emit;
            // Emission from buried parts goes straight into the object around them.
            out.absorbed_backs[b] += (area - seen) * emit;
        }
    }
    let mut h = [0.0f32; 8];
    for side in 0..State::sides(e) {
        super::closure::leaf_irradiance(st, ws, e, side, &mut h[..nb]);
        let bside = st.b(ws, e, side).unwrap_or(&[]);
        let direct = st.direct(ws, e, side);
        let linked = st.linked(ws, e, side);
        for b in 0..nb {
            let absorb = 1.0 - m.rho[side][b] as f64 - m.tau[b] as f64;
            out.absorbed[b] += seen * absorb * h[b] as f64;
            if let Some(d) = direct {
                let through_links = linked.map_or(0.0, |l| l[b]);
                out.direct[b] += seen * (d[b] - through_links) as f64;
            }
            let leaving = seen * bside.get(b).copied().unwrap_or(0.0) as f64;
            out.escaped[b] += leaving * fate[2 * side] as f64;
            out.absorbed_backs[b] += leaving * fate[2 * side + 1] as f64;
        }
    }
    // The direct light on the back of a one-sided polygon is absorbed there.
    if State::sides(e) == 1 {
        for b in 0..nb {
            let d = seen * fate[4 + b] as f64;
            // Light of other surfaces through links on it, absorbed there too.
            out.absorbed_backs[b] += seen * fate[4 + nb + b] as f64;
            out.direct[b] += d;
            out.absorbed_backs[b] += d;
        }
    }
}

/// Fills `out` for a leaf: per side, the fractions of its light that escape and that are
/// absorbed by one-sided backs; then (one-sided patches) the direct irradiance on its back.
fn fates<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    e: Elem,
    rays: u32,
    vis: &V,
    beyond: bool,
    out: &mut [f32],
) {
    let nb = st.bands;
    let p = st.patch(ws, e);
    let poly = st.polygon(ws, p.poly);
    let normal = Vec3::from(poly.normal);
    let n = p.corner_count();
    let mut corners = [Vec3::ZERO; 4];
    for (c, src) in corners.iter_mut().zip(p.corners) {
        *c = src.into();
    }
    let corners = &corners[..n];
    let rays = rays.max(1);
    let grid = libm::floorf(libm::sqrtf(rays as f32)).max(1.0) as u32;
    for side in 0..State::sides(e) {
        // Only sides that send light out matter.
        if !st
            .b(ws, e, side)
            .is_some_and(|b| b.iter().any(|&v| v > 0.0))
        {
            continue;
        }
        let nr = if side == 0 { normal } else { -normal };
        let seed = hash3(e.0, side as u32, 0xBA1);
        let (mut escaped, mut backs) = (0.0f32, 0u32);
        // Directions are stratified too, in an order shuffled against the points' (a stride
        // coprime with the cell count), so that neither pairs with the other.
        let cells = grid * grid;
        let stride = super::sample::coprime_stride(cells, hash3(seed, 0, 0x44));
        for j in 0..rays {
            let (pu, pv) = unit2(hash3(seed, j, 0x11));
            let cell = j % (grid * grid);
            let x = point_on(
                corners,
                ((cell % grid) as f32 + pu) / grid as f32,
                ((cell / grid) as f32 + pv) / grid as f32,
            );
            // Directions stratified in the other order, so points and directions do not pair.
            let dc = ((cell as u64 * stride as u64 + (j / cells) as u64) % cells as u64) as u32;
            let (du, dv) = unit2(hash3(seed, j, 0x22));
            let d = super::sample::cosine_direction(
                nr,
                ((dc % grid) as f32 + du) / grid as f32,
                ((dc / grid) as f32 + dv) / grid as f32,
            );
            let end = st.beyond(x, d);
            match vis.first_hit(x, end, [p.poly, NONE]) {
                // On out of the levels this one is open in, to the scene's edge.
                None if beyond => {
                    escaped += vis.transmittance_towards(x, end, d, [p.poly, NONE]);
                }
                // What closed instances on the way intercept, their links carry.
                None if st.instances > 0 => escaped += vis.transmittance(x, end, [p.poly, NONE]),
                None => escaped += 1.0,
                Some((hit, _)) if hit < st.polygons => {
                    let hp = st.polygon(ws, hit);
                    let one_sided = st.material(ws, hp.material).two_sided == 0;
                    if one_sided && Vec3::from(hp.normal).dot(d) > 0.0 {
                        backs += 1;
                    }
                }
                Some(_) => {}
            }
        }
        out[2 * side] = escaped / rays as f32;
        out[2 * side + 1] = backs as f32 / rays as f32;
    }
    if State::sides(e) == 1 && st.sources > 0 {
        back_direct(
            st,
            ws,
            e,
            corners,
            normal,
            p.poly,
            rays,
            vis,
            &mut out[4..4 + 2 * nb],
        );
    }
}

/// Direct irradiance on the back of a one-sided patch (W/m^2 per band), from `rays`
/// stratified points per source that faces it: into `out[..bands]` the suns' and sky's,
/// into `out[bands..]` the beams' that came through links of the levels around.
#[allow(clippy::too_many_arguments)]
fn back_direct<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    e: Elem,
    corners: &[Vec3],
    normal: Vec3,
    poly: u32,
    rays: u32,
    vis: &V,
    out: &mut [f32],
) {
    let grid = libm::floorf(libm::sqrtf(rays as f32)).max(1.0) as u32;
    for k in 0..st.sources {
        let src: Source = super::pool::read(ws, st.at(ws, Elem::new(Kind::Source, k)));
        let towards = Vec3::from(src.towards);
        let c = -normal.dot(towards);
        if c <= 0.0 || st.settings.sun_sides & 2 == 0 {
            continue;
        }
        let seed = hash3(e.0, k, 0xBAC);
        let mut lit = 0.0f32;
        for j in 0..grid * grid {
            let (u, v) = unit2(hash3(seed, j, 0x33));
            let x = point_on(
                corners,
                ((j % grid) as f32 + u) / grid as f32,
                ((j / grid) as f32 + v) / grid as f32,
            );
            let skip = st.source_skip(ws, k, poly);
            lit += vis.transmittance_towards(x, st.beyond(x, towards), towards, skip);
        }
        lit /= (grid * grid) as f32;
        let irr = st.b(ws, Elem::new(Kind::Source, k), 0).unwrap_or(&[]);
        // The suns' and sky's first, then what came through links (see `add_leaf`).
        let nb = irr.len().min(out.len() / 2);
        let part = if src.outer == NONE { 0 } else { nb };
        for (o, v) in out[part..part + nb].iter_mut().zip(irr) {
            *o += v * c * lit;
        }
    }
}
