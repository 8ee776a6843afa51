//! Which links geometry alone proves dark: nothing an emitter sends can reach a receiver
//! that lies behind or in its plane, and a patch gathers only from what lies in front of it.
//! Refinement never makes such links (see `refine::link_pair`).

use super::ids::Elem;
use super::state::{Shape, State};
use glam::Vec3;

/// True when a receiving cluster's box lies wholly behind a one-sided emitting patch's
/// plane, where nothing it sends can arrive.
pub(crate) fn hidden_behind(rs: &Shape, es: &Shape) -> bool {
    let (
        Shape::Cluster { min, max, .. },
        Shape::Patch {
            corners,
            normal,
            two_sided: false,
            ..
        },
    ) = (*rs, *es)
    else {
        return false;
    };
    (0..8).all(|k| {
        let c = Vec3::new(
            if k & 1 == 0 { min.x } else { max.x },
            if k & 2 == 0 { min.y } else { max.y },
            if k & 4 == 0 { min.z } else { max.z },
        );
        normal.dot(c - corners[0]) <= 0.0
    })
}

/// True when nothing `emit` sends can reach `recv` through a link, from where they lie
/// alone: a receiving patch whose plane has the emitter wholly behind it or in it (a
/// one-sided patch gathers on its front only, a two-sided one on both, and nothing arrives
/// along its plane), or a receiver wholly behind a one-sided emitting patch. Such links would
/// carry exactly nothing; a flat ground's own clusters are the common case (at the top level
/// of a canopy they were three quarters of its links).
pub(crate) fn unreachable(st: &State, ws: &[u8], recv: Elem, emit: Elem) -> bool {
    let (rs, es) = (st.shape(ws, recv), st.shape(ws, emit));
    if hidden_behind(&rs, &es) {
        return true;
    }
    let Shape::Patch {
        corners,
        normal,
        two_sided,
        ..
    } = rs
    else {
        return false;
    };
    let p0 = corners[0];
    let mut pts = [Vec3::ZERO; 8];
    let n = corners_of(&es, &mut pts);
    if n == 0 {
        return false;
    }
    pts[..n].iter().all(|&c| {
        let d = normal.dot(c - p0);
        // Within a millionth of a radian of the plane counts as in it (rounding).
        let tol = PLANE_TOLERANCE * (c - p0).length();
        if two_sided { d.abs() <= tol } else { d <= tol }
    })
}

/// Angle (radians) within which a point counts as lying in a receiving patch's plane.
const PLANE_TOLERANCE: f32 = 1e-6;

/// The corners of an emitter's extent into `out` (a box's 8, a patch's own), and how many;
/// 0 for a source, which lies nowhere.
fn corners_of(shape: &Shape, out: &mut [Vec3; 8]) -> usize {
    match *shape {
        Shape::Cluster { min, max, .. } | Shape::Instance { min, max, .. } => {
            for (k, o) in out.iter_mut().enumerate() {
                *o = Vec3::new(
                    if k & 1 == 0 { min.x } else { max.x },
                    if k & 2 == 0 { min.y } else { max.y },
                    if k & 4 == 0 { min.z } else { max.z },
                );
            }
            8
        }
        Shape::Patch { corners, n, .. } => {
            out[..n].copy_from_slice(&corners[..n]);
            n
        }
        Shape::Source { .. } => 0,
    }
}
