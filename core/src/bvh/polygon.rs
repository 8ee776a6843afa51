//! Where a segment crosses a triangle or a planar convex quad, and the trait through which the
//! visibility reads polygons.
//!
//! The test is the watertight one of Woop, Benthin and Wald (2013, "Watertight ray/triangle
//! intersection"): the corners are moved to the segment's origin and sheared so that the
//! segment runs along the z axis; the 2D edge functions then decide inside/outside. Two
//! triangles that share an edge (same corner coordinates) compute exactly opposite values for
//! that edge, so a segment through the edge crosses at least one of them: no light leaks
//! through a mesh. Points on an edge count as inside (closed polygons). A segment lying in the
//! polygon's plane never crosses it. There is no tolerance at all, so the test is scale-free
//! as long as products of two coordinate differences stay normal f32 numbers: lengths from
//! about 1e-15 to 1e15 in whatever unit the scene uses.
//!
//! A quad `a b c d` is the two triangles `a b c` and `a c d` sharing the diagonal `a c`; the
//! diagonal's edge function is computed once and used with both signs, so the quad is
//! watertight along it.

use crate::geometry::Aabb;
use glam::Vec3;

/// A segment `from + t dir`, prepared for polygon tests.
#[derive(Clone, Copy, Debug)]
pub struct SegmentTest {
    origin: [f32; 3],
    /// Axes of the sheared frame; `kz` is where `dir` is largest in magnitude.
    kx: usize,
    ky: usize,
    kz: usize,
    /// Shear `dir[kx] / dir[kz]`, `dir[ky] / dir[kz]` and scale `1 / dir[kz]`.
    sx: f32,
    sy: f32,
    sz: f32,
}

/// A polygon's corners in the sheared frame of a [`SegmentTest`].
#[derive(Clone, Copy)]
struct Sheared {
    x: f32,
    y: f32,
    z: f32,
}

impl SegmentTest {
    /// Prepares the segment `from + t dir`, t in (0, 1). `None` when `from` or `dir` is not
    /// finite or `dir` is zero (such a segment crosses nothing).
    pub fn new(from: Vec3, dir: Vec3) -> Option<Self> {
        if !(from.is_finite() && dir.is_finite()) || dir == Vec3::ZERO {
            return None;
        }
        let a = dir.abs().to_array();
        let kz = if a[0] >= a[1] && a[0] >= a[2] {
            0
        } else if a[1] >= a[2] {
            1
        } else {
            2
        };
        let kx = (kz + 1) % 3;
        let ky = (kx + 1) % 3;
        let d = dir.to_array();
        Some(SegmentTest {
            origin: from.to_array(),
            kx,
            ky,
            kz,
            sx: d[kx] / d[kz],
            sy: d[ky] / d[kz],
            sz: 1.0 / d[kz],
        })
    }

    #[inline]
    fn shear(&self, v: Vec3) -> Sheared {
        let v = v.to_array();
        let a = [
            v[0] - self.origin[0],
            v[1] - self.origin[1],
            v[2] - self.origin[2],
        ];
        let z = a[self.kz];
        Sheared {
            x: a[self.kx] - self.sx * z,
            y: a[self.ky] - self.sy * z,
            z: self.sz * z,
        }
    }

    /// The parameter t in (0, 1) at which the segment crosses the triangle (3 corners) or
    /// quad (4 corners), or `None` if it does not. Any other corner count crosses nothing.
    /// Either side of the polygon counts.
    pub fn polygon(&self, corners: &[Vec3]) -> Option<f32> {
        match *corners {
            [a, b, c] => {
                let (a, b, c) = (self.shear(a), self.shear(b), self.shear(c));
                let u = edge(b, c);
                let v = edge(c, a);
                let w = edge(a, b);
                crossing(a, b, c, u, v, w)
            }
            [a, b, c, d] => {
                let (a, b, c, d) = (self.shear(a), self.shear(b), self.shear(c), self.shear(d));
                let diagonal = edge(c, a);
                let first = crossing(a, b, c, edge(b, c), diagonal, edge(a, b));
                if first.is_some() {
                    return first;
                }
                // Triangle a c d: edge(a, c) is exactly -edge(c, a) in floating point.
                crossing(a, c, d, edge(c, d), edge(d, a), -diagonal)
            }
            _ => None,
        }
    }
}

/// The 2D edge function of the edge `p -> q` at the sheared origin (twice the signed area of
/// the triangle origin, p, q). `edge(q, p)` is exactly `-edge(p, q)`.
#[inline]
fn edge(p: Sheared, q: Sheared) -> f32 {
    q.x * p.y - q.y * p.x
}

/// Crossing of triangle `a b c` whose edge functions opposite `a`, `b`, `c` are `u`, `v`, `w`.
#[inline]
fn crossing(a: Sheared, b: Sheared, c: Sheared, u: f32, v: f32, w: f32) -> Option<f32> {
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 {
        return None;
    }
    let t = (u * a.z + v * b.z + w * c.z) / det;
    // NaN and infinities (overflowing coordinates) fail both comparisons.
    if t > 0.0 && t < 1.0 { Some(t) } else { None }
}

/// The parameter t in (0, 1) at which the segment `from + t dir` crosses the triangle or
/// planar convex quad `corners` (3 or 4 corners, counter-clockwise seen from the front; either
/// side counts), or `None`. Prepare a [`SegmentTest`] instead when testing one segment
/// against many polygons.
pub fn segment_polygon(from: Vec3, dir: Vec3, corners: &[Vec3]) -> Option<f32> {
    SegmentTest::new(from, dir)?.polygon(corners)
}

/// Polygons the visibility tests segments against, by id `0..count()`.
///
/// Must be `Sync`: the solver asks for visibility from several threads.
pub trait PolygonSet: Sync {
    /// Number of polygons.
    fn count(&self) -> u32;

    /// Writes the corners of polygon `id` to `out` and returns how many there are: 3 for a
    /// triangle, 4 for a quad. Any other value (for instance 0 for an id out of range) means
    /// "no polygon": it blocks nothing, and building a hierarchy over it fails with
    /// [`super::BvhError::InvalidBounds`].
    fn corners(&self, id: u32, out: &mut [Vec3; 4]) -> usize;

    /// Bounding box of polygon `id` ([`Aabb::EMPTY`] if it has no valid corner count).
    fn bounds(&self, id: u32) -> Aabb {
        let mut c = [Vec3::ZERO; 4];
        let n = self.corners(id, &mut c);
        if n != 3 && n != 4 {
            return Aabb::EMPTY;
        }
        let mut b = Aabb::EMPTY;
        for p in &c[..n] {
            b.include(*p);
        }
        b
    }
}

impl<P: PolygonSet + ?Sized> PolygonSet for &P {
    fn count(&self) -> u32 {
        (**self).count()
    }
    fn corners(&self, id: u32, out: &mut [Vec3; 4]) -> usize {
        (**self).corners(id, out)
    }
    fn bounds(&self, id: u32) -> Aabb {
        (**self).bounds(id)
    }
}

/// A [`PolygonSet`] over caller slices: four corner slots per polygon and, optionally, the
/// number of corners used (3 or 4) per polygon; without counts every polygon is a quad.
#[derive(Clone, Copy, Debug)]
pub struct SlicePolygons<'a> {
    corners: &'a [[Vec3; 4]],
    counts: Option<&'a [u8]>,
}

impl<'a> SlicePolygons<'a> {
    /// Polygon `i` has corners `corners[i][..counts[i]]`. If the slices differ in length,
    /// only the polygons present in both exist.
    pub fn new(corners: &'a [[Vec3; 4]], counts: &'a [u8]) -> Self {
        let n = corners.len().min(counts.len());
        SlicePolygons {
            corners: &corners[..n],
            counts: Some(&counts[..n]),
        }
    }

    /// Every polygon is the quad `corners[i]`.
    pub fn quads(corners: &'a [[Vec3; 4]]) -> Self {
        SlicePolygons {
            corners,
            counts: None,
        }
    }
}

impl PolygonSet for SlicePolygons<'_> {
    fn count(&self) -> u32 {
        u32::try_from(self.corners.len()).unwrap_or(u32::MAX)
    }

    fn corners(&self, id: u32, out: &mut [Vec3; 4]) -> usize {
        let i = id as usize;
        let Some(c) = self.corners.get(i) else {
            return 0;
        };
        *out = *c;
        match self.counts {
            None => 4,
            Some(counts) => counts.get(i).map_or(0, |&n| n as usize),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{hash3, unit2};

    fn v(x: f32, y: f32, z: f32) -> Vec3 {
        Vec3::new(x, y, z)
    }

    fn rnd(h: u32) -> Vec3 {
        let (a, b) = unit2(h);
        let (c, _) = unit2(hash3(h, 77, 78));
        v(a, b, c)
    }

    #[test]
    fn triangle_hits_and_misses() {
        let tri = [v(0., 0., 0.), v(1., 0., 0.), v(0., 1., 0.)];
        let t = segment_polygon(v(0.2, 0.2, 1.0), v(0., 0., -4.0), &tri).unwrap();
        assert_eq!(t, 0.25);
        // Either side, either winding.
        assert_eq!(
            segment_polygon(v(0.2, 0.2, -1.0), v(0., 0., 2.0), &tri),
            Some(0.5)
        );
        let back = [tri[0], tri[2], tri[1]];
        assert_eq!(
            segment_polygon(v(0.2, 0.2, 1.0), v(0., 0., -2.0), &back),
            Some(0.5)
        );
        // Outside, too short, pointing away, starting or ending on the plane.
        assert_eq!(
            segment_polygon(v(0.6, 0.6, 1.0), v(0., 0., -2.0), &tri),
            None
        );
        assert_eq!(
            segment_polygon(v(0.2, 0.2, 1.0), v(0., 0., -0.5), &tri),
            None
        );
        assert_eq!(
            segment_polygon(v(0.2, 0.2, 1.0), v(0., 0., 2.0), &tri),
            None
        );
        assert_eq!(
            segment_polygon(v(0.2, 0.2, 0.0), v(0., 0., 2.0), &tri),
            None
        );
        assert_eq!(
            segment_polygon(v(0.2, 0.2, 1.0), v(0., 0., -1.0), &tri),
            None
        );
        // In the plane: never crosses.
        assert_eq!(segment_polygon(v(-1., 0.2, 0.), v(3., 0., 0.), &tri), None);
        // Zero or non-finite direction, wrong corner counts, degenerate triangles.
        assert_eq!(segment_polygon(v(0.2, 0.2, 1.0), Vec3::ZERO, &tri), None);
        assert_eq!(
            segment_polygon(v(0.2, 0.2, 1.0), v(0., 0., f32::NAN), &tri),
            None
        );
        assert_eq!(
            segment_polygon(v(0.2, 0.2, 1.0), v(0., 0., -2.), &tri[..2]),
            None
        );
        let line = [v(0., 0., 0.), v(1., 1., 0.), v(2., 2., 0.)];
        assert_eq!(
            segment_polygon(v(0.5, 0.5, 1.0), v(0., 0., -2.), &line),
            None
        );
        // Oblique segment.
        let t = segment_polygon(v(-1.0, -1.0, 1.0), v(2.5, 2.5, -2.0), &tri).unwrap();
        assert!((t - 0.5).abs() < 1e-6);
    }

    #[test]
    fn edges_and_corners_are_inside() {
        let tri = [v(0., 0., 0.), v(1., 0., 0.), v(0., 1., 0.)];
        for p in [
            v(0., 0., 0.),
            v(0.5, 0., 0.),
            v(0., 0.5, 0.),
            v(0.5, 0.5, 0.),
        ] {
            let from = p + v(0., 0., 1.);
            assert_eq!(
                segment_polygon(from, v(0., 0., -2.), &tri),
                Some(0.5),
                "{p}"
            );
        }
    }

    #[test]
    fn quad_is_watertight_along_its_diagonal() {
        // A planar convex quad in the tilted plane z = 0.1 x + 0.05 y.
        let quad = [
            v(0., 0., 0.),
            v(2., 0., 0.),
            v(2.5, 1.7, 0.),
            v(-0.3, 1.1, 0.),
        ]
        .map(|p| p.with_z(0.1 * p.x + 0.05 * p.y));
        let normal = v(-0.1, -0.05, 1.0).normalize();
        for i in 0..20_000u32 {
            // Points on the diagonal 0-2, as close as f32 gets, from random directions.
            let s = unit2(hash3(i, 1, 2)).0;
            let p = quad[0].lerp(quad[2], s);
            let dir = (rnd(hash3(i, 3, 4)) - Vec3::splat(0.5)) * 4.0 + v(0., 0., 0.5);
            let from = p - dir * 0.5;
            if dir.dot(normal).abs() > 1e-3 * dir.length() {
                assert!(segment_polygon(from, dir, &quad).is_some(), "leak at {i}");
            }
        }
    }

    #[test]
    fn shared_edges_of_separate_triangles_do_not_leak() {
        // Two triangles with the same corner coordinates along a shared, skewed edge.
        let (a, b) = (v(0.1, 0.2, 0.3), v(1.3, 0.9, -0.4));
        let (c, d) = (v(0.2, 1.5, 0.1), v(1.1, -0.6, 0.2));
        let t1 = [a, b, c];
        let t2 = [b, a, d];
        for i in 0..20_000u32 {
            let s = unit2(hash3(i, 5, 6)).0;
            let p = a.lerp(b, s);
            let dir = (rnd(hash3(i, 7, 8)) - Vec3::splat(0.5)) * 3.0;
            let from = p - dir * 0.5;
            let hit = segment_polygon(from, dir, &t1).is_some()
                || segment_polygon(from, dir, &t2).is_some();
            // Seen along `dir`, both triangles must face the same way; otherwise the edge is
            // a silhouette and passing beside it is a genuine miss.
            let n1 = (b - a).cross(c - a);
            let n2 = (a - b).cross(d - b);
            if dir.dot(n1) * dir.dot(n2) > 0.0 {
                assert!(hit, "leak at {i}");
            }
        }
    }

    #[test]
    fn scale_free() {
        let quad = [v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)];
        for i in 0..2000u32 {
            let from = rnd(hash3(i, 9, 1)) * 2.0 - Vec3::splat(0.5);
            let to = rnd(hash3(i, 9, 2)) * 2.0 - Vec3::splat(0.5) - v(0., 0., 1.0);
            let base = segment_polygon(from, to - from, &quad);
            // Powers of two: exactly the same answer; other scales: the same side.
            for s in [1.0 / 1024.0, 1024.0, 2f32.powi(-40), 2f32.powi(40)] {
                let q = quad.map(|p| p * s);
                assert_eq!(segment_polygon(from * s, (to - from) * s, &q), base);
            }
            for s in [1e-3f32, 1e3, 1e-20, 1e15] {
                let q = quad.map(|p| p * s);
                let got = segment_polygon(from * s, (to - from) * s, &q);
                assert_eq!(got.is_some(), base.is_some(), "scale {s}, segment {i}");
            }
        }
    }

    #[test]
    fn slice_polygons() {
        let polys = [
            [
                v(0., 0., 0.),
                v(1., 0., 0.),
                v(0., 1., 0.),
                Vec3::splat(9.0),
            ],
            [v(0., 0., 1.), v(1., 0., 1.), v(1., 1., 1.), v(0., 1., 1.)],
        ];
        let set = SlicePolygons::new(&polys, &[3, 4, 3]);
        assert_eq!(set.count(), 2);
        let mut out = [Vec3::ZERO; 4];
        assert_eq!(set.corners(0, &mut out), 3);
        assert_eq!(set.bounds(0), Aabb::new(v(0., 0., 0.), v(1., 1., 0.)));
        assert_eq!(set.corners(1, &mut out), 4);
        assert_eq!(set.corners(2, &mut out), 0);
        assert!(set.bounds(2).is_empty());
        let quads = SlicePolygons::quads(&polys);
        assert_eq!(quads.corners(0, &mut out), 4);
        fn count_of<P: PolygonSet>(p: P) -> u32 {
            p.count()
        }
        assert_eq!(count_of::<&SlicePolygons>(&quads), 2);
    }
}
