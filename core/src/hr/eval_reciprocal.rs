//! A patch's coefficients from a smaller patch, integrated at the emitter's points and
//! scaled by reciprocity (areas), so that a patch never receives more than its emitter sends.

use super::eval::{Coefficients, emits, exposed_quadrature, recv_sides};
use super::ids::Elem;
use super::state::{Shape, State};
use crate::formfactor::{facing_side, point_polygon};
use crate::sampling::{
    MAX_CLIPPED_QUADRATURE, MAX_QUADRATURE, clipped_quadrature, hash3, point_on, quadrature, unit2,
};
use crate::visibility::Visibility;
use glam::Vec3;

/// A patch's coefficients from a smaller patch, by reciprocity: the emitter's form factors
/// to the receiver, integrated at the emitter's own quadrature points (where they vary
/// little: the emitter is the smaller), times emitter area over receiver area. Integrating at
/// the larger receiver's points instead can land a point right beside a small bright
/// emitter and credit the whole receiver with its peak (a 1 mm lamp over a 1000 m floor
/// gave the floor 1000 times the lamp's power); this way a patch never receives more than
/// its emitter sends. The spread over the receiver comes from the open form factors at the
/// receiver's points.
#[allow(clippy::too_many_arguments)]
pub(super) fn reciprocal<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    recv: Elem,
    r: &Shape,
    emit: Elem,
    e: &Shape,
    seed: u32,
    rays: u32,
    vis: &V,
    out: &mut Coefficients,
) {
    let (
        Shape::Patch {
            corners: rc,
            n: rn,
            normal: r_normal,
            poly: r_poly,
            area: r_area,
            ..
        },
        Shape::Patch {
            corners: ec,
            n: en,
            normal: e_normal,
            poly: e_poly,
            area: e_area,
            two_sided: e_two,
        },
    ) = (*r, *e)
    else {
        return;
    };
    let (rc, ec) = (&rc[..rn], &ec[..en]);
    let rp = st.patch(ws, recv);
    let ep = st.patch(ws, emit);
    let r_sides = recv_sides(r);
    // Per unit of the receiver's exposed area, from the emitter's exposed points.
    let (mut pts, mut wts) = ([Vec3::ZERO; MAX_QUADRATURE], [0.0f32; MAX_QUADRATURE]);
    let m = exposed_quadrature(&ep, ec, &mut pts, &mut wts);
    let seen_r = r_area * rp.exposed;
    let (dist, scale) = (
        |c: Vec3| r_normal.dot(c - rc[0]),
        ec.iter().fold(0.0f32, |a, &c| a.max((c - rc[0]).length())),
    );
    let straddles =
        ec.iter().any(|&c| dist(c) > 1e-6 * scale) && ec.iter().any(|&c| dist(c) < -1e-6 * scale);
    // A straddling emitter is integrated over its whole area in front (a buried part there
    // is dark to the rays), so its exposure is not counted again.
    let e_seen = if straddles {
        e_area
    } else {
        e_area * ep.exposed
    };
    let ratio_open = e_seen / r_area;
    let ratio = if seen_r > 0.0 { e_seen / seen_r } else { 0.0 };
    // The emitter's points, each with the receiving side it faces. An emitter straddling
    // the receiver's plane is integrated over the part on each side.
    const N: usize = 2 * MAX_CLIPPED_QUADRATURE;
    let (mut ys, mut yw, mut ysd) = ([Vec3::ZERO; N], [0.0f32; N], [0usize; N]);
    let mut count = 0;
    if straddles {
        for side in 0..r_sides {
            let nr = if side == 0 { r_normal } else { -r_normal };
            let (mut cp, mut cw) = (
                [Vec3::ZERO; MAX_CLIPPED_QUADRATURE],
                [0.0f32; MAX_CLIPPED_QUADRATURE],
            );
            let k = clipped_quadrature(ec, rc[0], nr, &mut cp, &mut cw);
            for i in 0..k {
                (ys[count], yw[count], ysd[count]) = (cp[i], cw[i], side);
                count += 1;
            }
        }
    } else {
        for q in 0..m {
            let Some(side) = facing_side(pts[q], rc[0], r_normal) else {
                continue;
            };
            if wts[q] > 0.0 && side < r_sides {
                (ys[count], yw[count], ysd[count]) = (pts[q], wts[q], side);
                count += 1;
            }
        }
    }
    for q in 0..count {
        let (y, w, r_side) = (ys[q], yw[q], ysd[q]);
        for s in 0..if e_two { 2 } else { 1 } {
            let ns = if s == 0 { e_normal } else { -e_normal };
            let f = point_polygon(y, ns, rc);
            if f <= 0.0 {
                continue;
            }
            let qs = hash3(seed, q as u32, 0x5E + s as u32);
            let (mut seen, mut cast) = (0.0f32, 0u32);
            for j in 0..2 * rays {
                if cast == rays {
                    break;
                }
                let (u, v) = unit2(hash3(qs, j, 0xA6));
                let x = point_on(rc, u, v);
                if ns.dot(x - y) <= 0.0 {
                    continue;
                }
                seen += vis.transmittance(y, x, [e_poly, r_poly]);
                cast += 1;
            }
            out.rays += cast;
            let v = if cast == 0 { 1.0 } else { seen / cast as f32 };
            out.partial |= v < 1.0;
            out.k[r_side][s] += ratio * w * f * v;
            out.open += ratio_open * w * f;
        }
    }
    out.partial |= (0..4).any(|q| rp.buried(q));
    // How the open coefficient varies over the receiver.
    let (mut rpts, mut rwts) = ([Vec3::ZERO; MAX_QUADRATURE], [0.0f32; MAX_QUADRATURE]);
    let rm = quadrature(rc, &mut rpts, &mut rwts);
    for side in 0..r_sides {
        let nr = if side == 0 { r_normal } else { -r_normal };
        let (mut lo, mut hi) = (f32::INFINITY, 0.0f32);
        for &x in &rpts[..rm] {
            let Some(s_side) = facing_side(x, ec[0], e_normal) else {
                continue;
            };
            let f = if emits(e, s_side) {
                point_polygon(x, nr, ec)
            } else {
                0.0
            };
            lo = lo.min(f);
            hi = hi.max(f);
        }
        if hi > 0.0 {
            out.spread = out.spread.max(hi - lo.min(hi));
        }
    }
}
