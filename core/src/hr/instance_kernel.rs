//! Links with a closed instance on one side (DESIGN.md "Instances inside a level").
//!
//! * **As an emitter** a closed instance sends the intensity its original's tables give for
//!   the light it received, `I(o)` (W/sr) towards the unit direction `o`. Links keep the
//!   isotropic kernel of a volume whose mean cross-section is a quarter of its reference
//!   area `A` (`A = 4` x the mean cross-section `(1 - tau) A_box` over the sphere):
//!   `A cos / (4 pi r^2 + A)`, and carry the radiosity `4 pi I(o) / A`
//!   ([`carried_radiosity`]), so that a receiver far away gets `I(o) cos / r^2`.
//! * **As a receiver** it takes the fluence at its centre (W/m^2: the flux density across
//!   each direction the emitter covers, summed, which for a small emitter is the
//!   irradiance on a plane facing it), which it keeps as beams of its received light (see
//!   `tables::closed`) spread over the cone of directions the emitter covers (the link's
//!   direction is the light's mean direction, as long as it is collimated; see
//!   `instance_light::cone_directions`): what it intercepts is each beam's flux density
//!   times its cross-section that way.
//!
//! Visibility is the mean transmittance of rays between points of the two elements, drawn
//! in the instance's placed box; the instance itself does not block its own rays (its
//! contents' shadows are in its tables), other closed instances do by their `tau`.

use super::blockers::SKIP_INSTANCE;
use super::cluster_kernel::{Plane, gathered};
use super::eval::Coefficients;
use super::ids::{Elem, Kind};
use super::state::{Shape, State};
use crate::formfactor::facing_side;
use crate::limits::NONE;
use crate::sampling::{MAX_QUADRATURE, hash3, point_on, quadrature, unit2};
use crate::visibility::Visibility;
use core::f32::consts::PI;
use glam::Vec3;

/// A point of closed instance `i`'s placed box, from a hash.
pub(crate) fn point_of(st: &State, ws: &[u8], i: u32, h: u32) -> Vec3 {
    let placed = st.placed(ws, i);
    let (lo, hi) = placed.tables().bounds();
    let f = |x: u32| (x & 0x3FF) as f32 / 1024.0 + 0.5 / 1024.0;
    let u = Vec3::new(f(h), f(h >> 10), f(h >> 20));
    placed.place().point(lo + (hi - lo) * u)
}

/// Points of its own polygons a closed instance receives at (see `into_instance`).
const RECEIVING_POINTS: u32 = 4;

/// Point `j` of `m` on closed instance `i`'s own polygons (world), drawn by area from the
/// hash `h`, stratified over the `m`; its box's centre when it has none.
fn surface_point(st: &State, ws: &[u8], i: u32, h: u32, j: u32, m: u32) -> Vec3 {
    let leaf = st.instance(ws, i);
    let Some(g) = st.original_geometry(ws, leaf.slot) else {
        return centre_of(st, ws, i);
    };
    let (a0, _) = unit2(hash3(h, 1, 0xC1));
    let (u, v) = unit2(hash3(h, 2, 0xC2));
    let a = ((j as f32 + a0) / m.max(1) as f32).min(1.0 - f32::EPSILON);
    match g.sample(a, u, v) {
        Some(sp) => {
            let place = leaf.place();
            place.point(sp.point)
        }
        None => centre_of(st, ws, i),
    }
}

/// The centre of closed instance `i`'s placed box (m).
pub(crate) fn centre_of(st: &State, ws: &[u8], i: u32) -> Vec3 {
    let placed = st.placed(ws, i);
    let (lo, hi) = placed.tables().bounds();
    placed.place().point((lo + hi) * 0.5)
}

/// The radiosity (W/m^2 per band) a link from closed instance `i` carries towards the
/// point `towards`: `4 pi I(o) / A` (see the module documentation).
pub(crate) fn carried_radiosity(st: &State, ws: &[u8], i: u32, towards: Vec3, out: &mut [f32]) {
    out.fill(0.0);
    let leaf = st.instance(ws, i);
    if leaf.area_ref <= 0.0 {
        return;
    }
    let o = (towards - centre_of(st, ws, i)).normalize_or_zero();
    let placed = st.placed(ws, i);
    let Ok(r) = crate::tables::closed::Received::over(&placed, st.received(ws, i)) else {
        return;
    };
    let s = 4.0 * PI / leaf.area_ref;
    r.intensity_all(&placed, o, out);
    for o_b in out.iter_mut() {
        *o_b *= s;
    }
}

/// The radiosity closed instance `i`'s links carry on average (W/m^2, the largest band):
/// the power it scatters out over its reference area.
pub(crate) fn mean_radiosity(st: &State, ws: &[u8], i: u32) -> f32 {
    let leaf = st.instance(ws, i);
    if leaf.area_ref <= 0.0 {
        return 0.0;
    }
    let placed = st.placed(ws, i);
    let Ok(r) = crate::tables::closed::Received::over(&placed, st.received(ws, i)) else {
        return 0.0;
    };
    (0..st.bands).map(|b| r.scattered(b)).fold(0.0f32, f32::max) / leaf.area_ref
}

/// The isotropic kernel of an instance of reference area `a` seen at distance squared `r2`
/// under cosine `cos` (clamped so that it never exceeds 1).
fn kernel(a: f32, r2: f32, cos: f32) -> f32 {
    if cos <= 0.0 || a <= 0.0 {
        return 0.0;
    }
    a * cos / (4.0 * PI * r2 + a)
}

/// Mean transmittance of `rays` rays from `x` to points drawn by `target(j)`.
fn visible<V: Visibility + ?Sized>(
    vis: &V,
    x: Vec3,
    rays: u32,
    skip: [u32; 2],
    mut target: impl FnMut(u32) -> Vec3,
) -> f32 {
    let n = rays.max(1);
    let mut seen = 0.0f32;
    for j in 0..n {
        seen += vis.transmittance(x, target(j), skip);
    }
    seen / n as f32
}

/// The coefficients of link `recv <- emit` where either is a closed instance, and what
/// refinement decides by from an estimate of their own (as every link's, see
/// `eval::evaluate`).
pub(crate) fn evaluate<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    recv: Elem,
    emit: Elem,
    vis: &V,
    seed: u32,
    rays: u32,
) -> Coefficients {
    let mut out = estimate(st, ws, recv, emit, vis, seed, rays);
    let d = estimate(
        st,
        ws,
        recv,
        emit,
        vis,
        hash3(seed, 0xDEC1DE, 0x5EE),
        rays.div_ceil(4),
    );
    out.open = d.open;
    out.partial = d.partial;
    out.spread = d.spread;
    out.seen = d.seen;
    out.rays += d.rays;
    out
}

/// One estimate of the coefficients of link `recv <- emit` from `seed` with `rays` rays per
/// point.
#[allow(clippy::too_many_arguments)]
fn estimate<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    recv: Elem,
    emit: Elem,
    vis: &V,
    seed: u32,
    rays: u32,
) -> Coefficients {
    let mut out = Coefficients {
        witness: [NONE; 2],
        ..Coefficients::default()
    };
    match (recv.kind(), emit.kind()) {
        (_, Kind::Instance) => from_instance(st, ws, recv, emit.index(), vis, seed, rays, &mut out),
        (Kind::Instance, _) => into_instance(st, ws, recv.index(), emit, vis, seed, rays, &mut out),
        _ => {}
    }
    out.seen = out.k.iter().flatten().sum();
    out
}

/// A patch, a cluster or another instance receiving from closed instance `i`.
#[allow(clippy::too_many_arguments)]
fn from_instance<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    recv: Elem,
    i: u32,
    vis: &V,
    seed: u32,
    rays: u32,
    out: &mut Coefficients,
) {
    let a = st.instance(ws, i).area_ref;
    let c = centre_of(st, ws, i);
    let to_emitter = |j: u32| point_of(st, ws, i, hash3(seed, j, 0x1E));
    match st.shape(ws, recv) {
        Shape::Patch {
            corners,
            n,
            normal,
            poly,
            two_sided,
            ..
        } => {
            let (mut pts, mut wts) = ([Vec3::ZERO; MAX_QUADRATURE], [0.0f32; MAX_QUADRATURE]);
            let m = super::eval::exposed_quadrature(
                &st.patch(ws, recv),
                &corners[..n],
                &mut pts,
                &mut wts,
            );
            let mut plain = [0.0f32; MAX_QUADRATURE];
            quadrature(&corners[..n], &mut [Vec3::ZERO; MAX_QUADRATURE], &mut plain);
            let (mut lo, mut hi) = (f32::INFINITY, 0.0f32);
            for q in 0..m {
                let x = pts[q];
                let d = c - x;
                let r2 = d.length_squared();
                let w = d.normalize_or_zero();
                for side in 0..if two_sided { 2 } else { 1 } {
                    let nr = if side == 0 { normal } else { -normal };
                    let open = kernel(a, r2, nr.dot(w));
                    if open <= 0.0 {
                        continue;
                    }
                    out.open += plain[q] * open;
                    if wts[q] == 0.0 {
                        out.partial = true;
                        continue;
                    }
                    let v = visible(vis, x, rays, [poly, SKIP_INSTANCE | i], |j| {
                        to_emitter(hash3(q as u32, side as u32, j))
                    });
                    out.rays += rays.max(1);
                    out.partial |= v < 1.0;
                    out.k[side][0] += wts[q] * open * v;
                    lo = lo.min(open * v);
                    hi = hi.max(open * v);
                }
            }
            if hi > 0.0 {
                out.spread = hi - lo.min(hi);
            }
        }
        Shape::Cluster { .. } => {
            // The flux density on a plane facing the instance, at points of the cluster's
            // surfaces.
            let n = rays.max(4);
            let mut sum = 0.0f32;
            let mut open = 0.0f32;
            for j in 0..n {
                let (x, poly) = super::sample::point_in(st, ws, recv, hash3(seed, j, 0xC7));
                let d = c - x;
                let k = kernel(a, d.length_squared(), 1.0);
                open += k;
                let y = to_emitter(j);
                sum += k * vis.transmittance(x, y, [poly, SKIP_INSTANCE | i]);
            }
            out.rays += n;
            out.k[0][0] = sum / n as f32;
            out.open = open / n as f32;
            out.partial = out.k[0][0] < out.open;
            out.dir = (c - super::oriented::centre(st, ws, recv)).normalize_or_zero();
        }
        Shape::Instance { index: r, .. } => {
            // Flux density at the receiver's centre, facing the emitter; rays between points
            // of both boxes.
            let x = centre_of(st, ws, r);
            let d = c - x;
            let open = kernel(a, d.length_squared(), 1.0);
            let n = rays.max(1);
            let mut seen = 0.0f32;
            for j in 0..n {
                let from = point_of(st, ws, r, hash3(seed, j, 0x2F));
                let skip = [SKIP_INSTANCE | r, SKIP_INSTANCE | i];
                seen += vis.transmittance(from, to_emitter(j), skip);
            }
            let v = seen / n as f32;
            out.rays += n;
            out.open = open;
            out.k[0][0] = open * v;
            out.partial = v < 1.0;
            out.dir = d.normalize_or_zero();
        }
        Shape::Source { .. } => {}
    }
}

/// Closed instance `i` receiving from a patch or a cluster (instances are `from_instance`).
#[allow(clippy::too_many_arguments)]
fn into_instance<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    i: u32,
    emit: Elem,
    vis: &V,
    seed: u32,
    rays: u32,
    out: &mut Coefficients,
) {
    // Where it receives: points of its own polygons where it has them (the fluence at its
    // box's centre, inside a canopy's densest layer, missed what its lowest leaves get from
    // the soil), else its box's centre.
    let geometry = st.original_geometry(ws, st.instance(ws, i).slot).is_some();
    let m = if geometry { RECEIVING_POINTS } else { 1 };
    let at = |j: u32| {
        if geometry {
            surface_point(st, ws, i, hash3(seed, j, 0x3D), j, m)
        } else {
            centre_of(st, ws, i)
        }
    };
    let from = |j: u32| point_of(st, ws, i, hash3(seed, j, 0x3E));
    match st.shape(ws, emit) {
        Shape::Patch {
            corners,
            n,
            normal,
            poly,
            two_sided,
            ..
        } => {
            let corners = &corners[..n];
            let per = rays.max(1).div_ceil(m);
            let (mut sum, mut open, mut dir) = ([0.0f32; 2], 0.0f32, Vec3::ZERO);
            let mut partial = false;
            for q in 0..m {
                let c = at(q);
                let Some(s) = facing_side(c, corners[0], normal) else {
                    continue;
                };
                if s == 1 && !two_sided {
                    continue;
                }
                // The fluence there per unit radiosity (its solid angle over pi): what the
                // instance intercepts from every direction the patch covers, not only the
                // cosine-weighted part on a plane facing it.
                let (omega, phi) = crate::formfactor::point_polygon_light(c, corners);
                let f = omega / PI;
                if f <= 0.0 {
                    continue;
                }
                let mut seen = 0.0f32;
                for j in 0..per {
                    let (u, v) = unit2(hash3(seed, q * per + j, 0x3F));
                    let x = if geometry { c } else { from(j) };
                    seen +=
                        vis.transmittance(x, point_on(corners, u, v), [SKIP_INSTANCE | i, poly]);
                }
                let v = seen / per as f32;
                out.rays += per;
                open += f;
                sum[s] += f * v;
                partial |= v < 1.0;
                // Towards the patch, as long as its light is collimated (see
                // `instance_light::cone_directions`).
                dir += phi * (PI * v / omega.max(f32::MIN_POSITIVE)) * f;
            }
            let total = sum[0] + sum[1];
            out.open = open / m as f32;
            out.k[0][0] = sum[0] / m as f32;
            out.k[0][1] = sum[1] / m as f32;
            out.partial = partial;
            out.dir = if total > 0.0 { dir / total } else { Vec3::ZERO };
        }
        Shape::Cluster { min, max, .. } => {
            let per = rays.max(4).div_ceil(m).max(2);
            let (mut k, mut open, mut towards) = (0.0f32, 0.0f32, Vec3::ZERO);
            let mut best = (0.0f32, super::cluster_kernel::Witnesses::EMPTY.pick);
            for q in 0..m {
                let c = at(q);
                // The fluence there: from every side (a cluster around or below the
                // instance is not cut in half by a plane facing its centre).
                let (kq, tq, oq, wit) = gathered(
                    st,
                    ws,
                    emit,
                    c,
                    Plane::Sphere,
                    SKIP_INSTANCE | i,
                    hash3(seed, 0x4E, 1 + q),
                    per,
                    true,
                    vis,
                );
                out.rays += per;
                k += kq;
                open += oq;
                towards += tq * kq;
                if kq > best.0 {
                    best = (kq, wit.pick);
                }
            }
            let c = centre_of(st, ws, i);
            let w = ((min + max) * 0.5 - c).normalize_or_zero();
            out.open = open / m as f32;
            out.k[0][0] = k / m as f32;
            out.partial = out.k[0][0] < out.open;
            out.exact = true;
            out.witness = best.1;
            // The light's mean direction, as long as it is collimated.
            out.dir = if k > 0.0 && towards.length_squared() > 0.0 {
                towards / k
            } else {
                w
            };
        }
        Shape::Instance { .. } | Shape::Source { .. } => {}
    }
}
