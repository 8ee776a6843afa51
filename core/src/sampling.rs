//! Deterministic sampling on triangles and quads: receiver quadrature points (the same for
//! every link of an element, so that form factors from an element close to 1), jittered
//! points from an integer hash (so results never depend on thread count or run), and the
//! 1-to-4 subdivision of patches.

use glam::Vec3;

/// A 32-bit integer hash of three words (murmur3 finaliser over a simple mix); the only source
/// of "randomness" in the solver.
pub fn hash3(a: u32, b: u32, c: u32) -> u32 {
    let mut h = a.wrapping_mul(0x9E37_79B1)
        ^ b.wrapping_mul(0x85EB_CA77).rotate_left(13)
        ^ c.wrapping_mul(0xC2B2_AE3D).rotate_left(26);
    h ^= h >> 16;
    h = h.wrapping_mul(0x85EB_CA6B);
    h ^= h >> 13;
    h = h.wrapping_mul(0xC2B2_AE35);
    h ^= h >> 16;
    h
}

/// Two numbers in [0, 1) from a hash.
pub fn unit2(h: u32) -> (f32, f32) {
    let h2 = hash3(h, 0x68E3_1DA4, 0x1B56_C4E9);
    (
        (h >> 8) as f32 * (1.0 / 16_777_216.0),
        (h2 >> 8) as f32 * (1.0 / 16_777_216.0),
    )
}

/// The point at parameters `(u, v)` in [0, 1]^2: bilinear on a quad `a b c d`; on a triangle
/// `a b c` the square is folded onto the triangle (area-preserving).
pub fn point_on(corners: &[Vec3], u: f32, v: f32) -> Vec3 {
    if corners.len() == 4 {
        let (a, b, c, d) = (corners[0], corners[1], corners[2], corners[3]);
        a * ((1.0 - u) * (1.0 - v)) + b * (u * (1.0 - v)) + c * (u * v) + d * ((1.0 - u) * v)
    } else {
        let (a, b, c) = (corners[0], corners[1], corners[2]);
        let (u, v) = if u + v > 1.0 {
            (1.0 - u, 1.0 - v)
        } else {
            (u, v)
        };
        a + (b - a) * u + (c - a) * v
    }
}

/// Most quadrature points of any rule below.
pub const MAX_QUADRATURE: usize = 4;

/// Receiver quadrature: points and weights (summing to 1) that integrate a smooth function's
/// area average over the polygon: the 2 x 2 Gauss rule on a quad (weights from the bilinear
/// map's Jacobian), the 3-point degree-2 rule on a triangle. Returns the point count.
pub fn quadrature(
    corners: &[Vec3],
    points: &mut [Vec3; MAX_QUADRATURE],
    weights: &mut [f32; MAX_QUADRATURE],
) -> usize {
    if corners.len() == 4 {
        const G: [f32; 2] = [0.211_324_87, 0.788_675_1];
        let (a, b, c, d) = (corners[0], corners[1], corners[2], corners[3]);
        let mut total = 0.0;
        for (k, (u, v)) in [(G[0], G[0]), (G[1], G[0]), (G[1], G[1]), (G[0], G[1])]
            .into_iter()
            .enumerate()
        {
            points[k] = point_on(corners, u, v);
            let du = (b - a) * (1.0 - v) + (c - d) * v;
            let dv = (d - a) * (1.0 - u) + (c - b) * u;
            weights[k] = du.cross(dv).length();
            total += weights[k];
        }
        for w in weights.iter_mut() {
            *w /= total;
        }
        4
    } else {
        let (a, b, c) = (corners[0], corners[1], corners[2]);
        points[0] = a * (2.0 / 3.0) + b * (1.0 / 6.0) + c * (1.0 / 6.0);
        points[1] = a * (1.0 / 6.0) + b * (2.0 / 3.0) + c * (1.0 / 6.0);
        points[2] = a * (1.0 / 6.0) + b * (1.0 / 6.0) + c * (2.0 / 3.0);
        *weights = [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0, 0.0];
        3
    }
}

/// Most points of [`clipped_quadrature`]: a quad clipped by a plane is at most a pentagon,
/// three triangles of three points.
pub const MAX_CLIPPED_QUADRATURE: usize = 9;

/// Quadrature over the part of a convex polygon in front of a plane (through `on_plane`,
/// normal `normal`): the clipped polygon fanned into triangles, each with the triangle rule.
/// The weights are fractions of the whole polygon's area (they sum to the part in front).
/// For an emitter straddling a receiver's plane, where its own few points would count a
/// third of it (or none) instead of the part that shows. Returns the point count.
pub fn clipped_quadrature(
    corners: &[Vec3],
    on_plane: Vec3,
    normal: Vec3,
    points: &mut [Vec3; MAX_CLIPPED_QUADRATURE],
    weights: &mut [f32; MAX_CLIPPED_QUADRATURE],
) -> usize {
    let m = corners.len().min(4);
    let mut clipped = [Vec3::ZERO; 5];
    let k = clip_front(corners, on_plane, normal, &mut clipped);
    let whole = polygon_area(&corners[..m]);
    if k < 3 || whole <= 0.0 {
        return 0;
    }
    let mut n = 0;
    for t in 1..k - 1 {
        let (a, b, c) = (clipped[0], clipped[t], clipped[t + 1]);
        let w = 0.5 * (b - a).cross(c - a).length() / whole / 3.0;
        for (pa, pb, pc) in [(a, b, c), (b, c, a), (c, a, b)] {
            points[n] = pa * (2.0 / 3.0) + pb * (1.0 / 6.0) + pc * (1.0 / 6.0);
            weights[n] = w;
            n += 1;
        }
    }
    n
}

/// Clips a convex triangle or quad to the half-space `normal . (y - on_plane) > 0`; returns
/// the corner count written to `out` (below 3 when nothing is in front).
fn clip_front(corners: &[Vec3], on_plane: Vec3, normal: Vec3, out: &mut [Vec3; 5]) -> usize {
    let m = corners.len().min(4);
    let mut k = 0;
    for i in 0..m {
        let (a, b) = (corners[i], corners[(i + 1) % m]);
        let (da, db) = (normal.dot(a - on_plane), normal.dot(b - on_plane));
        if da > 0.0 && k < 5 {
            out[k] = a;
            k += 1;
        }
        if (da > 0.0) != (db > 0.0) && k < 5 {
            let t = da / (da - db);
            if t.is_finite() {
                out[k] = a + (b - a) * t;
                k += 1;
            }
        }
    }
    k
}

/// A point drawn uniformly by area over the part of a convex triangle or quad in front of a
/// plane (through `on_plane`, normal `normal`), from three numbers in [0, 1): `pick` chooses
/// a triangle of the clipped polygon's fan by area, `u`, `v` a point in it. `None` when
/// nothing is in front. Unlike drawing over the whole polygon until a point lands in front,
/// it never gives up on a polygon that shows only a sliver.
pub fn point_in_front(
    corners: &[Vec3],
    on_plane: Vec3,
    normal: Vec3,
    pick: f32,
    u: f32,
    v: f32,
) -> Option<Vec3> {
    let mut clipped = [Vec3::ZERO; 5];
    let k = clip_front(corners, on_plane, normal, &mut clipped);
    if k < 3 {
        return None;
    }
    let tri = |t: usize| {
        let (a, b, c) = (clipped[0], clipped[t], clipped[t + 1]);
        (b - a).cross(c - a).length()
    };
    let total: f32 = (1..k - 1).map(tri).sum();
    if total.is_nan() || total <= 0.0 {
        return None;
    }
    let mut target = pick * total;
    let mut t = k - 2;
    for i in 1..k - 1 {
        let a = tri(i);
        if target < a {
            t = i;
            break;
        }
        target -= a;
    }
    let (u, v) = if u + v > 1.0 {
        (1.0 - u, 1.0 - v)
    } else {
        (u, v)
    };
    let (a, b, c) = (clipped[0], clipped[t], clipped[t + 1]);
    Some(a + (b - a) * u + (c - a) * v)
}

/// Area (m^2) of the part of a convex triangle or quad in front of a plane (through
/// `on_plane`, normal `normal`): the measure [`point_in_front`] draws its points by.
pub fn area_in_front(corners: &[Vec3], on_plane: Vec3, normal: Vec3) -> f32 {
    let mut clipped = [Vec3::ZERO; 5];
    let k = clip_front(corners, on_plane, normal, &mut clipped);
    if k < 3 {
        0.0
    } else {
        polygon_area(&clipped[..k])
    }
}

/// Area of a planar convex polygon (m^2).
pub fn polygon_area(corners: &[Vec3]) -> f32 {
    let mut twice = Vec3::ZERO;
    for t in 1..corners.len().saturating_sub(1) {
        twice += (corners[t] - corners[0]).cross(corners[t + 1] - corners[0]);
    }
    0.5 * twice.length()
}

/// Splits a quad into 4 quads at its edge midpoints and centre, or a triangle into 4
/// triangles at its edge midpoints (the middle one keeps the orientation). Children keep the
/// parent's orientation and, for a planar convex parent, are planar and convex.
pub fn subdivide(corners: &[Vec3], out: &mut [[Vec3; 4]; 4]) -> usize {
    if corners.len() == 4 {
        let (a, b, c, d) = (corners[0], corners[1], corners[2], corners[3]);
        let (ab, bc, cd, da) = ((a + b) * 0.5, (b + c) * 0.5, (c + d) * 0.5, (d + a) * 0.5);
        let m = (a + b + c + d) * 0.25;
        *out = [
            [a, ab, m, da],
            [ab, b, bc, m],
            [m, bc, c, cd],
            [da, m, cd, d],
        ];
        4
    } else {
        let (a, b, c) = (corners[0], corners[1], corners[2]);
        let (ab, bc, ca) = ((a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5);
        *out = [
            [a, ab, ca, Vec3::ZERO],
            [ab, b, bc, Vec3::ZERO],
            [ca, bc, c, Vec3::ZERO],
            [ab, bc, ca, Vec3::ZERO],
        ];
        3
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::polygon_shape;

    #[test]
    fn clipped_quadrature_integrates_the_part_in_front() {
        let v = |x: f32, y: f32| Vec3::new(x, y, 0.0);
        let quad = [v(0., 0.), v(2., 0.), v(2., 1.), v(0., 1.)];
        let tri = [v(0., 0.), v(2., 0.), v(0., 2.)];
        let (mut p, mut w) = (
            [Vec3::ZERO; MAX_CLIPPED_QUADRATURE],
            [0.0; MAX_CLIPPED_QUADRATURE],
        );
        // Planes x = c (front towards -x or +x), and a slanted one: the weights sum to the
        // area fraction in front, and a linear function integrates exactly.
        for corners in [&quad[..], &tri[..]] {
            for (o, n) in [
                (v(0.5, 0.), Vec3::X),
                (v(0.5, 0.), -Vec3::X),
                (v(1.3, 0.4), Vec3::new(1., 1., 0.).normalize()),
            ] {
                let k = clipped_quadrature(corners, o, n, &mut p, &mut w);
                // Reference by a fine grid over the polygon.
                let (mut frac, mut fx) = (0.0f64, 0.0f64);
                let g = 400;
                for i in 0..g {
                    for j in 0..g {
                        let x = point_on(
                            corners,
                            (i as f32 + 0.5) / g as f32,
                            (j as f32 + 0.5) / g as f32,
                        );
                        if corners.len() == 3 && i + j >= g {
                            continue;
                        }
                        if n.dot(x - o) > 0.0 {
                            frac += 1.0;
                            fx += x.x as f64 + 2.0 * x.y as f64;
                        }
                    }
                }
                let cells = if corners.len() == 3 {
                    (g * (g + 1) / 2) as f64
                } else {
                    (g * g) as f64
                };
                let sum: f32 = w[..k].iter().sum();
                let integral: f32 = (0..k).map(|q| w[q] * (p[q].x + 2.0 * p[q].y)).sum();
                assert!(
                    (sum as f64 - frac / cells).abs() < 0.01,
                    "{sum} vs {}",
                    frac / cells
                );
                assert!(
                    (integral as f64 - fx / cells).abs() < 0.02,
                    "{integral} vs {}",
                    fx / cells
                );
            }
        }
        // Wholly behind: nothing.
        assert_eq!(
            clipped_quadrature(&quad, v(3., 0.), Vec3::X, &mut p, &mut w),
            0
        );
    }

    #[test]
    fn hash_is_spread_and_stable() {
        assert_eq!(hash3(1, 2, 3), hash3(1, 2, 3));
        assert_ne!(hash3(1, 2, 3), hash3(1, 2, 4));
        let mut mean = (0.0f64, 0.0f64);
        for i in 0..10_000 {
            let (u, v) = unit2(hash3(i, 7, 9));
            assert!((0.0..1.0).contains(&u) && (0.0..1.0).contains(&v));
            mean.0 += u as f64;
            mean.1 += v as f64;
        }
        assert!((mean.0 / 1e4 - 0.5).abs() < 0.01 && (mean.1 / 1e4 - 0.5).abs() < 0.01);
    }

    #[test]
    fn quadrature_integrates_linear_functions_exactly() {
        let quad = [
            Vec3::new(0., 0., 0.),
            Vec3::new(2., 0., 0.),
            Vec3::new(1.5, 1., 0.),
            Vec3::new(0., 1., 0.),
        ];
        let tri = [
            Vec3::new(0., 0., 0.),
            Vec3::new(2., 0., 0.),
            Vec3::new(0., 1., 0.),
        ];
        // Centroids by area: the quad's is (65/84... computed by splitting into triangles).
        for poly in [&quad[..], &tri[..]] {
            let (mut p, mut w) = ([Vec3::ZERO; 4], [0.0; 4]);
            let n = quadrature(poly, &mut p, &mut w);
            let q: Vec3 = (0..n).map(|k| p[k] * w[k]).sum();
            // Exact area centroid.
            let mut c = Vec3::ZERO;
            let mut area = 0.0;
            for k in 1..poly.len() - 1 {
                let a = polygon_shape(&[poly[0], poly[k], poly[k + 1]])
                    .unwrap()
                    .area;
                c += (poly[0] + poly[k] + poly[k + 1]) / 3.0 * a;
                area += a;
            }
            assert!((q - c / area).length() < 1e-5, "{q} vs {}", c / area);
        }
    }

    #[test]
    fn subdivision_tiles_the_parent() {
        let quad = [
            Vec3::new(0., 0., 0.),
            Vec3::new(2., 0., 0.),
            Vec3::new(1.5, 1., 0.),
            Vec3::new(0., 1., 0.),
        ];
        let tri = [
            Vec3::new(0., 0., 0.),
            Vec3::new(2., 0., 0.),
            Vec3::new(0., 1., 0.),
        ];
        for poly in [&quad[..], &tri[..]] {
            let parent = polygon_shape(poly).unwrap();
            let mut out = [[Vec3::ZERO; 4]; 4];
            let k = subdivide(poly, &mut out);
            let mut area = 0.0;
            for child in &out {
                let s = polygon_shape(&child[..k]).unwrap();
                assert!((s.normal - parent.normal).length() < 1e-6);
                area += s.area;
            }
            assert!((area - parent.area).abs() < 1e-6);
        }
    }
}
