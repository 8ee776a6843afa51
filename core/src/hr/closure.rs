//! Exact closure of the irradiance a sub-patch inherits.
//!
//! A link attached to a patch is evaluated at that patch's quadrature points, and its
//! irradiance is pushed unchanged to every sub-patch. At a given sub-patch the inherited form
//! factors therefore do not sum to what the sub-patch itself sees: in a closed scene the sum
//! is 1 only on average over the parent. With rho = 0.99 a sum of 1.01 somewhere is enough to
//! diverge. After each refinement round every leaf sub-patch re-evaluates, at its own
//! quadrature points and without occlusion, the exact form factors of the links its ancestor
//! patches receive from other patches (visibility kept as the link's fraction), and scales
//! the inherited irradiance by the ratio of that sum to the inherited one, per side. Sums at
//! every leaf are then exact (a closed furnace holds `B = E / (1 - rho)` to float precision)
//! at the cost of form-factor evaluations, no rays.

use super::exec::{Executor, Fallback, run_chunks};
use super::ids::{Elem, Kind};
use super::layout::CHUNK;
use super::state::{Shape, State};
use crate::formfactor::{facing_side, point_polygon};
use crate::limits::NONE;
use crate::sampling::{MAX_QUADRATURE, quadrature};
use glam::Vec3;

struct Ctx<'a> {
    st: &'a mut State,
    ws: &'a mut [u8],
}

/// Recomputes the closure factors of every sub-patch.
pub(crate) fn update<E: Executor>(
    st: &mut State,
    ws: &mut [u8],
    ex: &mut Fallback<'_, E>,
    progress: &mut dyn super::exec::Progress,
) {
    for kind in [Kind::Patch1, Kind::Patch2] {
        let n = st.pool(kind).len as usize;
        let mut ctx = Ctx {
            st: &mut *st,
            ws: &mut *ws,
        };
        run_chunks(
            ex,
            &mut ctx,
            n.div_ceil(CHUNK),
            CHUNK * 2,
            |c: &Ctx<'_>, chunk, buf| {
                for (slot, i) in (chunk * CHUNK..((chunk + 1) * CHUNK).min(n)).enumerate() {
                    let e = Elem::new(kind, i as u32);
                    // NaN marks "unchanged": only patches under changed links are redone.
                    let f = if needs_update(c.st, c.ws, e) {
                        factors(c.st, c.ws, e)
                    } else {
                        [f32::NAN; 2]
                    };
                    buf[2 * slot..2 * slot + 2].copy_from_slice(&f);
                }
            },
            |c: &mut Ctx<'_>, chunk, buf| {
                for (slot, i) in (chunk * CHUNK..((chunk + 1) * CHUNK).min(n)).enumerate() {
                    if buf[2 * slot].is_nan() {
                        continue;
                    }
                    let e = Elem::new(kind, i as u32);
                    let mut p = c.st.patch(c.ws, e);
                    p.closure = [buf[2 * slot], buf[2 * slot + 1]];
                    c.st.set_patch(c.ws, e, &p);
                }
            },
            &mut |done, total| {
                progress.report(
                    "closing (patches)",
                    (done * CHUNK).min(n) as u64,
                    (total * CHUNK).min(n) as u64,
                )
            },
        );
    }
    // Everything is up to date now.
    for kind in [Kind::Patch1, Kind::Patch2] {
        for i in 0..st.pool(kind).len {
            let e = Elem::new(kind, i);
            let mut p = st.patch(ws, e);
            if p.stale() {
                p.shape &= !super::records::STALE;
                st.set_patch(ws, e, &p);
            }
        }
    }
}

/// True if a leaf sub-patch or one of its ancestor patches had its links changed.
fn needs_update(st: &State, ws: &[u8], e: Elem) -> bool {
    let p = st.patch(ws, e);
    if p.first_child != NONE || Elem(p.parent).kind() == Kind::Cluster {
        return false;
    }
    let mut a = e;
    while a.is_patch() {
        let ap = st.patch(ws, a);
        if ap.stale() {
            return true;
        }
        a = Elem(ap.parent);
    }
    false
}

/// The irradiance of a leaf patch's side (W/m^2 per band): what it gathered and inherited
/// from ancestor patches, scaled by its closure factor, plus a quarter of the flux density of
/// its polygon's cluster (isotropic).
pub(crate) fn leaf_irradiance(st: &State, ws: &[u8], e: Elem, side: usize, out: &mut [f32]) {
    let p = st.patch(ws, e);
    let root = st.patch(ws, Elem(st.polygon(ws, p.poly).root));
    let cluster = st.h(ws, Elem(root.parent), 0);
    let c = p.closure[side.min(1)];
    for ((o, h), hc) in out.iter_mut().zip(st.h(ws, e, side)).zip(cluster) {
        *o = c * h + 0.25 * hc;
    }
}

/// The closure factors of one patch (1 for roots and for patches with children).
fn factors(st: &State, ws: &[u8], e: Elem) -> [f32; 2] {
    let p = st.patch(ws, e);
    if p.first_child != NONE || Elem(p.parent).kind() == Kind::Cluster {
        return [1.0; 2];
    }
    let Shape::Patch {
        corners,
        n,
        normal,
        two_sided,
        ..
    } = st.shape(ws, e)
    else {
        return [1.0; 2];
    };
    let (mut pts, mut wts) = ([Vec3::ZERO; MAX_QUADRATURE], [0.0f32; MAX_QUADRATURE]);
    let m = quadrature(&corners[..n], &mut pts, &mut wts);
    let sides = if two_sided { 2 } else { 1 };
    let kk = st.lay.strides.link_k;
    let (mut num, mut den) = ([0.0f64; 2], [0.0f64; 2]);
    // The patch's own links count as they are (they were evaluated at these very points), so
    // that the factor can scale its whole patch-gathered irradiance.
    let mut a = e;
    while a.is_patch() {
        let ap = st.patch(ws, a);
        let mut cur = ap.links;
        while cur != NONE {
            let l = st.link(ws, cur);
            let k = st.link_k(ws, cur);
            let emit = Elem(l.emit);
            let sum_k: f32 = k.iter().sum();
            let vis = if l.k_open > 0.0 {
                (sum_k / l.k_open).min(1.0)
            } else {
                0.0
            };
            // The patch's own links count as they are; only inherited ones are re-evaluated.
            let eshape = if a == e {
                None
            } else {
                Some(st.shape(ws, emit))
            };
            for r in 0..sides {
                let inherited: f32 = if kk == 1 {
                    k[0]
                } else {
                    k[r * 2] + k[r * 2 + 1]
                };
                den[r] += inherited as f64;
                let own = match eshape {
                    None => inherited,
                    Some(Shape::Patch {
                        corners: ec,
                        n: en,
                        normal: enormal,
                        two_sided: etwo,
                        ..
                    }) => {
                        let nr = if r == 0 { normal } else { -normal };
                        let mut f = 0.0f32;
                        for q in 0..m {
                            let Some(s) = facing_side(pts[q], ec[0], enormal) else {
                                continue;
                            };
                            if s == 1 && (!etwo || kk == 1) {
                                continue;
                            }
                            f += wts[q] * point_polygon(pts[q], nr, &ec[..en]);
                        }
                        f * vis
                    }
                    // Cluster and source kernels are kept as inherited.
                    _ => inherited,
                };
                num[r] += own as f64;
            }
            cur = l.next;
        }
        a = Elem(ap.parent);
    }
    let mut out = [1.0f32; 2];
    for r in 0..sides {
        if den[r] > 0.0 {
            out[r] = (num[r] / den[r]) as f32;
        }
    }
    out
}
