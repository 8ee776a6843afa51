//! The two geometric functions of an original's directional table (paper section 3.1): the
//! projected area `A(dir)` of its bounding box (m^2, analytic) and its uncollided
//! transmittance `tau(dir)` (dimensionless, 0..=1): the fraction of parallel rays along
//! `dir` across the box's projection that cross the box without meeting a polygon.

use super::grid::DirectionGrid;
use crate::limits::NONE;
use crate::sampling::{hash3, unit2};
use crate::visibility::Visibility;
use glam::Vec3;

/// The area (m^2) of the shadow of the box `[lo, hi]` on a plane perpendicular to the unit
/// direction `d`: the faces' areas weighted by their cosines, `|dx| Sy Sz + |dy| Sx Sz +
/// |dz| Sx Sy` (`S` the box's sizes).
pub fn projected_area(lo: Vec3, hi: Vec3, d: Vec3) -> f32 {
    let s = (hi - lo).max(Vec3::ZERO);
    let a = d.abs();
    a.x * s.y * s.z + a.y * s.x * s.z + a.z * s.x * s.y
}

/// `tau` towards `d` from its values at the cell centres of `grid`, for the box `[lo, hi]`.
///
/// What is interpolated is the cross-section `(1 - tau) A` (m^2), the area of the contents'
/// own shadow, not `tau`: `A` folds wherever the direction crosses the plane of a face of the
/// box (its cosine weights change sign), and `tau = 1 - cross-section / A` folds with it,
/// which interpolation would only follow to first order.
pub fn interpolate_tau(grid: &DirectionGrid, values: &[f32], lo: Vec3, hi: Vec3, d: Vec3) -> f32 {
    let area = projected_area(lo, hi, d);
    if area <= 0.0 {
        return 1.0;
    }
    let shadow: f32 = grid
        .weights_directions(d)
        .iter()
        .map(|&(c, w, dc)| {
            let t = values.get(c as usize).copied().unwrap_or(1.0);
            w * (1.0 - t) * projected_area(lo, hi, dc)
        })
        .sum();
    (1.0 - shadow / area).clamp(0.0, 1.0)
}

/// The power a box's contents scatter out for a sun of 1 W/m^2 towards `d` (m^2), or a
/// part of it: the scattered cross-section `albedo (1 - tau) A` interpolated from its values
/// at the cell centres of `grid` (`tau` per cell; `albedo[cell * stride + at]`, the share of
/// the intercepted power that the part scatters out), as a whole for the reason
/// [`interpolate_tau`] interpolates the cross-section.
#[allow(clippy::too_many_arguments)]
pub fn interpolate_scattered(
    grid: &DirectionGrid,
    tau: &[f32],
    albedo: &[f32],
    stride: usize,
    at: usize,
    lo: Vec3,
    hi: Vec3,
    d: Vec3,
) -> f32 {
    grid.weights_directions(d)
        .iter()
        .map(|&(c, w, dc)| {
            let i = c as usize;
            let t = tau.get(i).copied().unwrap_or(1.0);
            let a = albedo.get(i * stride + at).copied().unwrap_or(0.0);
            w * a * (1.0 - t) * projected_area(lo, hi, dc)
        })
        .sum::<f32>()
        .max(0.0)
}

/// One estimate of `tau` along a direction.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TauEstimate {
    /// Uncollided transmittance: rays that crossed unblocked over rays that crossed the box.
    pub tau: f32,
    /// Rays that crossed the box (those of the grid inside its projection).
    pub rays: u32,
    /// The box's projected area measured by the same grid (m^2): a check of the sampling
    /// against [`projected_area`].
    pub area: f32,
}

/// `tau` along the unit direction `d` through the box `[lo, hi]` of an original whose
/// polygons `vis` knows, from a stratified `g x g` grid of parallel rays (jittered by
/// `seed`) over the rectangle that bounds the box's projection. Each ray runs from where it
/// enters the box to where it leaves; a ray that misses the box is not counted.
pub fn tau<V: Visibility + ?Sized>(
    vis: &V,
    lo: Vec3,
    hi: Vec3,
    d: Vec3,
    g: u32,
    seed: u32,
) -> TauEstimate {
    let mut clear = 0u32;
    let (crossed, cell) = parallel_rays(lo, hi, d, g, seed, |from, to| {
        if vis.transmittance(from, to, [NONE, NONE]) > 0.5 {
            clear += 1;
        }
    });
    if g == 0 || d.normalize_or_zero() == Vec3::ZERO {
        return TauEstimate::default();
    }
    TauEstimate {
        tau: if crossed > 0 {
            clear as f32 / crossed as f32
        } else {
            1.0
        },
        rays: crossed,
        area: crossed as f32 * cell,
    }
}

/// Calls `f(from, to)` for each ray of a stratified `g x g` grid of rays parallel to the
/// unit direction `d` (jittered by `seed`) over the rectangle that bounds the projection of
/// the box `[lo, hi]`, with the part of the ray inside the box (`from` where it enters, `to`
/// where it leaves, `to - from` along `d`); rays that miss the box are skipped. Returns the
/// rays that crossed and the area each ray stands for (m^2): `crossed x area` estimates
/// [`projected_area`].
pub fn parallel_rays<F: FnMut(Vec3, Vec3)>(
    lo: Vec3,
    hi: Vec3,
    d: Vec3,
    g: u32,
    seed: u32,
    mut f: F,
) -> (u32, f32) {
    let d = d.normalize_or_zero();
    if d == Vec3::ZERO || g == 0 {
        return (0, 0.0);
    }
    let (e1, e2) = frame(d);
    let centre = (lo + hi) * 0.5;
    // The rectangle spanned by the projected corners, around the centre.
    let (mut s_max, mut t_max) = (0.0f32, 0.0f32);
    for k in 0..8 {
        let c = Vec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        ) - centre;
        s_max = s_max.max(c.dot(e1).abs());
        t_max = t_max.max(c.dot(e2).abs());
    }
    let reach = (hi - lo).length();
    // Rays run through the box grown by a hair, so that polygons on its faces (all of them,
    // for a flat original) are inside the segments rather than at their ends.
    let pad = Vec3::splat(1e-4 * reach + f32::MIN_POSITIVE);
    let (lo, hi) = (lo - pad, hi + pad);
    let cell = 4.0 * s_max * t_max / (g * g) as f32;
    let mut crossed = 0u32;
    for j in 0..g {
        for i in 0..g {
            let (ju, jv) = unit2(hash3(seed, j * g + i, 0x7A0));
            let s = ((i as f32 + ju) / g as f32 * 2.0 - 1.0) * s_max;
            let t = ((j as f32 + jv) / g as f32 * 2.0 - 1.0) * t_max;
            let on = centre + e1 * s + e2 * t;
            let Some((t0, t1)) = slab(on - d * reach, d, lo, hi) else {
                continue;
            };
            if t1 <= t0 {
                continue;
            }
            crossed += 1;
            f(on - d * reach + d * t0, on - d * reach + d * t1);
        }
    }
    (crossed, cell)
}

/// Two unit vectors that make a right-handed orthonormal frame with the unit `d`.
fn frame(d: Vec3) -> (Vec3, Vec3) {
    let t = if d.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let e1 = d.cross(t).normalize();
    (e1, d.cross(e1))
}

/// Where the ray `o + t d` enters and leaves the box `[lo, hi]` (its parameters), if it
/// meets it.
fn slab(o: Vec3, d: Vec3, lo: Vec3, hi: Vec3) -> Option<(f32, f32)> {
    let (mut t0, mut t1) = (f32::NEG_INFINITY, f32::INFINITY);
    for a in 0..3 {
        if d[a].abs() < 1e-12 {
            if o[a] < lo[a] || o[a] > hi[a] {
                return None;
            }
            continue;
        }
        let (mut n, mut f) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
        if n > f {
            core::mem::swap(&mut n, &mut f);
        }
        t0 = t0.max(n);
        t1 = t1.min(f);
    }
    (t0 <= t1).then_some((t0, t1))
}
