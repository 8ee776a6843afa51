//! Exact, unoccluded form factors from a point to a polygon (Lambert's contour integral),
//! with the polygon clipped to the half-space the point can see.
//!
//! For a receiving point `p` with unit normal `n` and a planar polygon, the form factor is
//! `F = 1/(2 pi) * sum_i angle(r_i, r_i+1) * n . normalize(r_i x r_i+1)` with `r_i = v_i - p`,
//! taken over the part of the polygon in front of `p` (`n . (y - p) > 0`). It is exact for any
//! distance, so form factors from one point to the pieces of a closed surface sum to 1: this
//! is what keeps a closed furnace at `B = E / (1 - rho)`. Computed in f64.

use glam::{DVec3, Vec3};

/// Most corners a clipped triangle or quad can have.
const MAX_CLIPPED: usize = 5;

/// Form factor (dimensionless, 0..=1) from a differential area at `p` with unit normal `n` to
/// the convex planar polygon `poly` (3 or 4 corners, either orientation), counting only the
/// part in front of the tangent plane of `p`. Which side of the polygon faces `p` is the
/// caller's concern (see [`facing_side`]). Computed in f32 relative to `p` (sums over a closed
/// surface come to 1 within about 1e-6); [`point_polygon_f64`] is the slower exact one.
pub fn point_polygon(p: Vec3, n: Vec3, poly: &[Vec3]) -> f32 {
    let mut clipped = [Vec3::ZERO; MAX_CLIPPED];
    let mut k = 0;
    let m = poly.len().min(4);
    for i in 0..m {
        let a = poly[i] - p;
        let b = poly[(i + 1) % m] - p;
        let (da, db) = (n.dot(a), n.dot(b));
        if da > 0.0 && k < MAX_CLIPPED {
            clipped[k] = a;
            k += 1;
        }
        if (da > 0.0) != (db > 0.0) && k < MAX_CLIPPED {
            let t = da / (da - db);
            if t.is_finite() {
                clipped[k] = a + (b - a) * t;
                k += 1;
            }
        }
    }
    if k < 3 {
        return 0.0;
    }
    let mut sum = 0.0f32;
    for i in 0..k {
        let (a, b) = (clipped[i], clipped[(i + 1) % k]);
        let c = a.cross(b);
        let len = c.length();
        if len <= 0.0 || !len.is_finite() {
            continue;
        }
        sum += angle(len, a.dot(b)) * n.dot(c) / len;
    }
    (sum.abs() / (2.0 * core::f32::consts::PI)).min(1.0)
}

/// What a whole convex polygon sends to the point `p`, unclipped (the polygon must lie on
/// one side of every plane through `p` that matters to the caller): its solid angle (sr) and
/// its vector form factor `phi = (1/2 pi) sum_i angle(r_i, r_i+1) normalize(r_i x r_i+1)`,
/// oriented so that the irradiance on a plane of unit normal `n` facing all of the polygon
/// is `B n . phi` for a polygon of radiosity B. `pi |phi| <= solid angle`, with equality
/// only for a vanishing polygon: their ratio is how collimated its light is.
pub fn point_polygon_light(p: Vec3, poly: &[Vec3]) -> (f32, Vec3) {
    let m = poly.len().min(4);
    if m < 3 {
        return (0.0, Vec3::ZERO);
    }
    let mut phi = Vec3::ZERO;
    for i in 0..m {
        let (a, b) = (poly[i] - p, poly[(i + 1) % m] - p);
        let c = a.cross(b);
        let len = c.length();
        if len <= 0.0 || !len.is_finite() {
            continue;
        }
        phi += c * (angle(len, a.dot(b)) / len);
    }
    phi /= 2.0 * core::f32::consts::PI;
    // Solid angle: a fan of triangles (Van Oosterom and Strackee).
    let mut omega = 0.0f32;
    let a = poly[0] - p;
    for i in 1..m - 1 {
        let (b, c) = (poly[i] - p, poly[i + 1] - p);
        let (la, lb, lc) = (a.length(), b.length(), c.length());
        let num = a.dot(b.cross(c)).abs();
        let den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
        let t = 2.0 * libm::atan2f(num, den);
        if t.is_finite() {
            omega += t.abs();
        }
    }
    // The light arrives from the polygon: orient phi towards it.
    let centre = poly[..m].iter().copied().sum::<Vec3>() / m as f32 - p;
    if phi.dot(centre) < 0.0 {
        phi = -phi;
    }
    (omega, phi)
}

/// The angle (0..=pi) whose sine and cosine are proportional to `y >= 0` and `x`: Cephes'
/// single-precision arctangent (about 1e-7 relative) with its octant reductions, inline and
/// branch-light. The solver's hottest function spends most of its time here.
#[inline]
fn angle(y: f32, x: f32) -> f32 {
    use core::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};
    let ax = x.abs();
    let (num, den, swapped) = if y > ax {
        (ax, y, true)
    } else {
        (y, ax, false)
    };
    if den <= 0.0 {
        return 0.0;
    }
    // t in [0, 1]; reduce to [-tan(pi/8), tan(pi/8)].
    let t = num / den;
    let (z, base) = if t > 0.414_213_57 {
        ((t - 1.0) / (t + 1.0), FRAC_PI_4)
    } else {
        (t, 0.0)
    };
    let z2 = z * z;
    let p = (((8.053_744_5e-2 * z2 - 1.387_768_6e-1) * z2 + 1.997_771_1e-1) * z2 - 3.333_295e-1)
        * z2
        * z
        + z;
    let mut r = base + p;
    if swapped {
        r = FRAC_PI_2 - r;
    }
    if x < 0.0 { PI - r } else { r }
}

/// [`point_polygon`] in f64, for sums that must close to 1 within 1e-9.
pub fn point_polygon_f64(p: DVec3, n: DVec3, poly: &[Vec3]) -> f64 {
    let mut clipped = [DVec3::ZERO; MAX_CLIPPED];
    let k = clip_front(p, n, poly, &mut clipped);
    if k < 3 {
        return 0.0;
    }
    let mut sum = 0.0f64;
    for i in 0..k {
        let a = clipped[i] - p;
        let b = clipped[(i + 1) % k] - p;
        let c = a.cross(b);
        let len = c.length();
        if len <= 1e-300 || !len.is_finite() {
            continue;
        }
        let angle = libm::atan2(len, a.dot(b));
        sum += angle * n.dot(c) / len;
    }
    (sum.abs() / (2.0 * core::f64::consts::PI)).min(1.0)
}

/// Clips `poly` to the half-space `n . (y - p) > 0`; returns the corner count written to
/// `out` (0 when nothing is in front).
fn clip_front(p: DVec3, n: DVec3, poly: &[Vec3], out: &mut [DVec3; MAX_CLIPPED]) -> usize {
    let m = poly.len().min(4);
    let mut k = 0;
    for i in 0..m {
        let a = poly[i].as_dvec3();
        let b = poly[(i + 1) % m].as_dvec3();
        let da = n.dot(a - p);
        let db = n.dot(b - p);
        if da > 0.0 && k < MAX_CLIPPED {
            out[k] = a;
            k += 1;
        }
        if (da > 0.0) != (db > 0.0) && k < MAX_CLIPPED {
            let t = da / (da - db);
            if t.is_finite() {
                out[k] = a + (b - a) * t;
                k += 1;
            }
        }
    }
    k
}

/// Which side of a polygon with front normal `normal` through `on_plane` faces the point
/// `p`: `Some(0)` front, `Some(1)` back, `None` when `p` lies in the polygon's plane
/// (relative to the distance, so the test is scale-free).
pub fn facing_side(p: Vec3, on_plane: Vec3, normal: Vec3) -> Option<usize> {
    let d = p - on_plane;
    let s = normal.dot(d);
    if s.abs() <= 1e-7 * d.length() {
        None
    } else if s > 0.0 {
        Some(0)
    } else {
        Some(1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f32, y: f32, z: f32) -> Vec3 {
        Vec3::new(x, y, z)
    }

    /// Area average over a receiver square [0,1]^2 at z = 0 (normal +z), midpoint rule.
    fn average(emitter: &[Vec3], n_pts: usize) -> f64 {
        let mut sum = 0.0;
        for i in 0..n_pts {
            for j in 0..n_pts {
                let p = DVec3::new(
                    (i as f64 + 0.5) / n_pts as f64,
                    (j as f64 + 0.5) / n_pts as f64,
                    0.0,
                );
                sum += point_polygon_f64(p, DVec3::Z, emitter);
            }
        }
        sum / (n_pts * n_pts) as f64
    }

    #[test]
    fn parallel_unit_squares() {
        let top = [v(0., 0., 1.), v(1., 0., 1.), v(1., 1., 1.), v(0., 1., 1.)];
        let f = average(&top, 64);
        assert!((f - 0.199825).abs() < 2e-5, "{f}");
    }

    #[test]
    fn perpendicular_squares_sharing_an_edge() {
        // Receiver [0,1]^2 in z = 0; emitter in the plane x = 0, y in [0,1], z in [0,1].
        let wall = [v(0., 0., 0.), v(0., 1., 0.), v(0., 1., 1.), v(0., 0., 1.)];
        let f = average(&wall, 128);
        assert!((f - 0.200044).abs() < 2e-4, "{f}");
    }

    #[test]
    fn a_closed_cube_sums_to_one() {
        // Faces of the unit cube; points on the floor see the five others.
        let faces = [
            [v(0., 0., 1.), v(1., 0., 1.), v(1., 1., 1.), v(0., 1., 1.)],
            [v(0., 0., 0.), v(0., 1., 0.), v(0., 1., 1.), v(0., 0., 1.)],
            [v(1., 0., 0.), v(1., 1., 0.), v(1., 1., 1.), v(1., 0., 1.)],
            [v(0., 0., 0.), v(1., 0., 0.), v(1., 0., 1.), v(0., 0., 1.)],
            [v(0., 1., 0.), v(1., 1., 0.), v(1., 1., 1.), v(0., 1., 1.)],
            [v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)],
        ];
        for p in [
            DVec3::new(0.5, 0.5, 0.0),
            DVec3::new(0.01, 0.99, 0.0),
            DVec3::new(0.3, 0.001, 0.0),
        ] {
            let sum: f64 = faces
                .iter()
                .map(|f| point_polygon_f64(p, DVec3::Z, f))
                .sum();
            assert!((sum - 1.0).abs() < 1e-9, "{p}: {sum}");
        }
        // Split the walls into triangles: still 1.
        let p = DVec3::new(0.2, 0.7, 0.0);
        let mut sum = 0.0;
        for f in &faces {
            sum += point_polygon_f64(p, DVec3::Z, &[f[0], f[1], f[2]]);
            sum += point_polygon_f64(p, DVec3::Z, &[f[0], f[2], f[3]]);
        }
        assert!((sum - 1.0).abs() < 1e-9, "{sum}");
    }

    #[test]
    fn clipped_and_behind() {
        let p = Vec3::ZERO;
        // Entirely behind the tangent plane.
        let below = [
            v(-1., -1., -1.),
            v(1., -1., -1.),
            v(1., 1., -1.),
            v(-1., 1., -1.),
        ];
        assert_eq!(point_polygon(p, Vec3::Z, &below), 0.0);
        // A huge vertical wall straddling the plane: half of it counts, and a far wall
        // tends to 1/2 of the hemisphere's projected area.
        let wall = [
            v(-1e4, 1., -1e4),
            v(1e4, 1., -1e4),
            v(1e4, 1., 1e4),
            v(-1e4, 1., 1e4),
        ];
        let f = point_polygon(p, Vec3::Z, &wall);
        assert!((f - 0.5).abs() < 1e-3, "{f}");
        // Scale-free: the same configuration in millimetres and kilometres.
        let sq = |s: f32| [v(0., 0., s), v(s, 0., s), v(s, s, s), v(0., s, s)];
        let a = point_polygon(v(0.3e-3, 0.2e-3, 0.), Vec3::Z, &sq(1e-3));
        let b = point_polygon(v(0.3e3, 0.2e3, 0.), Vec3::Z, &sq(1e3));
        assert!((a - b).abs() < 1e-6, "{a} {b}");
        // The f32 path closes a cube to 1e-6.
        let p = Vec3::new(0.2, 0.7, 0.0);
        let faces = [
            [v(0., 0., 1.), v(1., 0., 1.), v(1., 1., 1.), v(0., 1., 1.)],
            [v(0., 0., 0.), v(0., 1., 0.), v(0., 1., 1.), v(0., 0., 1.)],
            [v(1., 0., 0.), v(1., 1., 0.), v(1., 1., 1.), v(1., 0., 1.)],
            [v(0., 0., 0.), v(1., 0., 0.), v(1., 0., 1.), v(0., 0., 1.)],
            [v(0., 1., 0.), v(1., 1., 0.), v(1., 1., 1.), v(0., 1., 1.)],
        ];
        let sum: f32 = faces.iter().map(|f| point_polygon(p, Vec3::Z, f)).sum();
        assert!((sum - 1.0).abs() < 1e-6, "{sum}");
    }

    #[test]
    fn fast_angle_matches_atan2() {
        let mut worst = 0.0f64;
        for i in 0..20_000 {
            let t = i as f64 / 20_000.0 * core::f64::consts::PI;
            for r in [1e-3, 1.0, 7e4] {
                let (y, x) = ((t.sin() * r) as f32, (t.cos() * r) as f32);
                let exact = libm::atan2(y as f64, x as f64);
                worst = worst.max((angle(y, x) as f64 - exact).abs());
            }
        }
        assert!(worst < 4e-7, "{worst}");
        assert_eq!(angle(0.0, 0.0), 0.0);
    }

    #[test]
    fn light_of_a_polygon_closes_the_sphere_and_matches_the_form_factor() {
        // A point inside a cube sees its six faces: solid angles sum to 4 pi, and the vector
        // form factors cancel.
        let faces = [
            [v(0., 0., 1.), v(1., 0., 1.), v(1., 1., 1.), v(0., 1., 1.)],
            [v(0., 0., 0.), v(0., 1., 0.), v(0., 1., 1.), v(0., 0., 1.)],
            [v(1., 0., 0.), v(1., 1., 0.), v(1., 1., 1.), v(1., 0., 1.)],
            [v(0., 0., 0.), v(1., 0., 0.), v(1., 0., 1.), v(0., 0., 1.)],
            [v(0., 1., 0.), v(1., 1., 0.), v(1., 1., 1.), v(0., 1., 1.)],
            [v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)],
        ];
        let p = v(0.3, 0.6, 0.45);
        let (mut omega, mut phi) = (0.0, Vec3::ZERO);
        for f in &faces {
            let (o, ph) = point_polygon_light(p, f);
            omega += o;
            phi += ph;
            // The form factor of a plane facing the whole face is n . phi.
            let n = (f[0] + f[1] + f[2] + f[3]) / 4.0 - p;
            let n = if n.x.abs() > n.y.abs().max(n.z.abs()) {
                Vec3::new(n.x.signum(), 0., 0.)
            } else if n.y.abs() > n.z.abs() {
                Vec3::new(0., n.y.signum(), 0.)
            } else {
                Vec3::new(0., 0., n.z.signum())
            };
            let ff = point_polygon(p, n, f);
            assert!((ff - n.dot(ph)).abs() < 1e-5, "{ff} vs {}", n.dot(ph));
            assert!(core::f32::consts::PI * ph.length() <= o * (1.0 + 1e-5));
        }
        assert!(
            (omega - 4.0 * core::f32::consts::PI).abs() < 1e-4,
            "{omega}"
        );
        assert!(phi.length() < 1e-5, "{phi}");
        // A small far polygon is nearly collimated: pi |phi| / omega near 1.
        let tiny = [
            v(0., 0., 10.),
            v(0.01, 0., 10.),
            v(0.01, 0.01, 10.),
            v(0., 0.01, 10.),
        ];
        let (o, ph) = point_polygon_light(Vec3::ZERO, &tiny);
        assert!((core::f32::consts::PI * ph.length() / o - 1.0).abs() < 1e-3);
    }

    #[test]
    fn sides() {
        assert_eq!(facing_side(v(0., 0., 1.), Vec3::ZERO, Vec3::Z), Some(0));
        assert_eq!(facing_side(v(0., 0., -1.), Vec3::ZERO, Vec3::Z), Some(1));
        assert_eq!(facing_side(v(5., 0., 0.), Vec3::ZERO, Vec3::Z), None);
    }
}
