//! [`BvhVisibility`]: the core's [`Visibility`], a hierarchy over opaque polygons.

use super::polygon::{PolygonSet, SegmentTest};
use super::{Bvh, BvhError, BvhNode, build};
use crate::visibility::Visibility;
use glam::Vec3;

/// Crossings at a segment parameter t within this margin of either end do not block
/// (`SEGMENT_MARGIN < t < 1 - SEGMENT_MARGIN` blocks). Relative to the segment's length, so a
/// ray leaving one surface is not blocked by a coplanar or touching neighbour at t ~ 0 in a
/// scene of any unit; an occluder closer to an end point than this fraction of the distance
/// is missed.
pub const SEGMENT_MARGIN: f32 = 1e-5;

/// Visibility between two points against a set of opaque polygons, through a [`Bvh`] over
/// them.
///
/// Every polygon blocks fully: a translucent leaf still blocks the direct ray, and the solver
/// accounts for the light it transmits separately.
#[derive(Clone, Copy, Debug)]
pub struct BvhVisibility<'a, P: PolygonSet> {
    bvh: Bvh<'a>,
    polygons: P,
}

impl<'a, P: PolygonSet> BvhVisibility<'a, P> {
    /// Visibility through an already built hierarchy whose primitive ids are the ids of
    /// `polygons`. Ids the set does not know block nothing.
    pub fn new(bvh: Bvh<'a>, polygons: P) -> Self {
        BvhVisibility { bvh, polygons }
    }

    /// Builds the hierarchy over all of `polygons` in the caller's storage
    /// ([`super::nodes_needed`]`(polygons.count())` nodes, `polygons.count()` order entries).
    /// Fails on too little storage, too many polygons, or a polygon whose corners are not
    /// finite or whose corner count is not 3 or 4 ([`BvhError::InvalidBounds`] names it).
    pub fn build(
        polygons: P,
        nodes: &'a mut [BvhNode],
        order: &'a mut [u32],
    ) -> Result<Self, BvhError> {
        let bvh = build(polygons.count(), |id| polygons.bounds(id), nodes, order)?;
        Ok(BvhVisibility { bvh, polygons })
    }

    /// The hierarchy.
    pub fn bvh(&self) -> Bvh<'a> {
        self.bvh
    }

    /// The polygons.
    pub fn polygons(&self) -> &P {
        &self.polygons
    }

    /// The parameter t at which the open segment crosses polygon `id`, if it blocks.
    #[inline]
    fn blocks(&self, seg: &SegmentTest, id: u32, skip: [u32; 2]) -> Option<f32> {
        if id == skip[0] || id == skip[1] {
            return None;
        }
        let mut c = [Vec3::ZERO; 4];
        let n = self.polygons.corners(id, &mut c).min(4);
        seg.polygon(&c[..n])
            .filter(|&t| t > SEGMENT_MARGIN && t < 1.0 - SEGMENT_MARGIN)
    }

    /// Some polygon (not in `skip`) that the segment `from..to` crosses at a parameter t with
    /// `SEGMENT_MARGIN < t < 1 - SEGMENT_MARGIN`, or `None` if nothing blocks. Which one is
    /// returned when several block depends on the tree, not on chance.
    pub fn blocker(&self, from: Vec3, to: Vec3, skip: [u32; 2]) -> Option<u32> {
        let seg = SegmentTest::new(from, to - from)?;
        let mut found = None;
        self.bvh
            .any_hit_within(from, to, 0.5 * SEGMENT_MARGIN, 1.0, |id| {
                let hit = self.blocks(&seg, id, skip).is_some();
                if hit {
                    found = Some(id);
                }
                hit
            });
        found
    }

    /// The blocking polygon nearest to `from` and its segment parameter t, with the same
    /// rules as [`BvhVisibility::blocker`]. Nearest up to the rounding of t: of polygons
    /// crossed at nearly the same t (coplanar ones), any may be returned.
    pub fn first_hit(&self, from: Vec3, to: Vec3, skip: [u32; 2]) -> Option<(u32, f32)> {
        self.first_hit_before(from, to, skip, 1.0)
    }

    /// [`BvhVisibility::first_hit`] among the crossings before the parameter `t_max` (a
    /// caller that knows something nearer blocks prunes what lies beyond it).
    pub fn first_hit_before(
        &self,
        from: Vec3,
        to: Vec3,
        skip: [u32; 2],
        t_max: f32,
    ) -> Option<(u32, f32)> {
        let seg = SegmentTest::new(from, to - from)?;
        self.bvh
            .closest_hit_within(from, to, 0.5 * SEGMENT_MARGIN, t_max, |id, t_max| {
                self.blocks(&seg, id, skip).filter(|&t| t < t_max)
            })
    }
}

impl<P: PolygonSet> Visibility for BvhVisibility<'_, P> {
    /// 0.0 if a polygon other than those in `skip` crosses the open segment `from..to` at a
    /// parameter t with `SEGMENT_MARGIN < t < 1 - SEGMENT_MARGIN`, else 1.0. Segments with a
    /// non-finite end point or of zero length are not blocked.
    fn transmittance(&self, from: Vec3, to: Vec3, skip: [u32; 2]) -> f32 {
        if self.blocker(from, to, skip).is_some() {
            0.0
        } else {
            1.0
        }
    }

    fn first_hit(&self, from: Vec3, to: Vec3, skip: [u32; 2]) -> Option<(u32, f32)> {
        BvhVisibility::first_hit(self, from, to, skip)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::bvh::{SlicePolygons, nodes_needed, segment_polygon};
    use crate::limits::NONE;
    use crate::sampling::{hash3, point_on, unit2};
    use std::vec;
    use std::vec::Vec;

    fn unit(h: u32) -> f32 {
        unit2(h).0
    }

    fn rnd3(a: u32, b: u32) -> Vec3 {
        Vec3::new(
            unit(hash3(a, b, 1)),
            unit(hash3(a, b, 2)),
            unit(hash3(a, b, 3)),
        )
    }

    /// A random polygon around `centre`: a triangle (3) or a planar convex quad (4) of size
    /// about `size`. Corners lie in cyclic order on a circle (a convex polygon), stretched
    /// differently along two axes of a random plane (an affine map keeps it convex).
    fn polygon(i: u32, seed: u32, centre: Vec3, size: f32) -> ([Vec3; 4], u8) {
        let n = (rnd3(i, seed ^ 0x51) - 0.5).normalize_or(Vec3::Z);
        let u = n.any_orthonormal_vector() * size * (0.5 + unit(hash3(i, seed, 7)));
        let v = n.cross(n.any_orthonormal_vector()) * size * (0.5 + unit(hash3(i, seed, 8)));
        let k = if hash3(i, seed, 9).is_multiple_of(2) {
            3
        } else {
            4
        };
        let mut c = [Vec3::ZERO; 4];
        let step = core::f32::consts::TAU / k as f32;
        for (j, p) in c.iter_mut().enumerate().take(k) {
            let a = step * (j as f32 + 0.8 * unit(hash3(i, seed, 20 + j as u32)));
            *p = centre + u * libm::cosf(a) + v * libm::sinf(a);
        }
        (c, k as u8)
    }

    struct Scene {
        corners: Vec<[Vec3; 4]>,
        counts: Vec<u8>,
    }

    impl Scene {
        fn random(n: u32, seed: u32, size: f32) -> Scene {
            let (corners, counts): (Vec<_>, Vec<_>) = (0..n)
                .map(|i| polygon(i, seed, rnd3(i, seed), size))
                .unzip();
            for (c, &k) in corners.iter().zip(&counts) {
                assert!(crate::geometry::polygon_shape(&c[..k as usize]).is_ok());
            }
            Scene { corners, counts }
        }

        fn scaled(&self, s: f32) -> Scene {
            Scene {
                corners: self.corners.iter().map(|c| c.map(|p| p * s)).collect(),
                counts: self.counts.clone(),
            }
        }

        fn poly(&self, i: usize) -> &[Vec3] {
            &self.corners[i][..self.counts[i] as usize]
        }

        /// Testing every polygon: the reference.
        fn brute(&self, from: Vec3, to: Vec3, skip: [u32; 2]) -> f32 {
            for i in 0..self.corners.len() {
                if skip.contains(&(i as u32)) {
                    continue;
                }
                if let Some(t) = segment_polygon(from, to - from, self.poly(i))
                    && t > SEGMENT_MARGIN
                    && t < 1.0 - SEGMENT_MARGIN
                {
                    return 0.0;
                }
            }
            1.0
        }

        /// Compares the BVH with brute force on the given segments; returns the blocked
        /// fraction so callers can check the test exercised both answers.
        fn compare(&self, segments: &[(Vec3, Vec3, [u32; 2])]) -> f32 {
            let n = self.corners.len() as u32;
            let mut nodes = vec![BvhNode::default(); nodes_needed(n)];
            let mut order = vec![0u32; n as usize];
            let set = SlicePolygons::new(&self.corners, &self.counts);
            let vis = BvhVisibility::build(set, &mut nodes, &mut order).unwrap();
            let mut blocked = 0;
            for (k, &(from, to, skip)) in segments.iter().enumerate() {
                let want = self.brute(from, to, skip);
                let got = vis.transmittance(from, to, skip);
                assert_eq!(got, want, "segment {k}: {from} -> {to} skip {skip:?}");
                // The nearest blocker is a blocker, and no brute-force crossing is nearer (up
                // to rounding: coplanar polygons cross at "the same" t, computed differently).
                let first = vis.first_hit(from, to, skip);
                assert_eq!(first.is_some(), got == 0.0);
                if let Some((id, t)) = first {
                    assert_eq!(
                        segment_polygon(from, to - from, self.poly(id as usize)),
                        Some(t)
                    );
                    for i in 0..self.corners.len() {
                        if skip.contains(&(i as u32)) {
                            continue;
                        }
                        if let Some(u) = segment_polygon(from, to - from, self.poly(i)) {
                            assert!(u <= SEGMENT_MARGIN || u >= t * (1.0 - 1e-5), "nearer {i}");
                        }
                    }
                    blocked += 1;
                }
            }
            blocked as f32 / segments.len() as f32
        }
    }

    fn random_segments(n: u32, seed: u32, scale: f32) -> Vec<(Vec3, Vec3, [u32; 2])> {
        (0..n)
            .map(|q| {
                let from = (rnd3(q, seed) * 1.2 - 0.1) * scale;
                let to = (rnd3(q, seed + 1) * 1.2 - 0.1) * scale;
                (from, to, [NONE, NONE])
            })
            .collect()
    }

    #[test]
    fn agrees_with_brute_force_at_every_scale() {
        let base = Scene::random(1500, 1, 0.03);
        for s in [1.0f32, 1e-3, 1e3] {
            let scene = base.scaled(s);
            let f = scene.compare(&random_segments(800, 7, s));
            assert!(f > 0.2 && f < 0.95, "blocked fraction {f} at scale {s}");
        }
    }

    #[test]
    fn agrees_on_axis_aligned_segments() {
        let scene = Scene::random(1500, 2, 0.03);
        let mut segs = Vec::new();
        for q in 0..900u32 {
            let from = rnd3(q, 40);
            let mut to = from;
            let axis = (q % 3) as usize;
            to[axis] = if q % 2 == 0 { -0.1 } else { 1.1 };
            segs.push((from, to, [NONE, NONE]));
            // Through polygon corners and centres along an axis.
            let p = scene.corners[(q % 1500) as usize][0];
            let (mut a, mut b) = (p, p);
            a[axis] -= 0.5;
            b[axis] += 0.5;
            segs.push((a, b, [NONE, NONE]));
        }
        let f = scene.compare(&segs);
        assert!(f > 0.2 && f < 0.95, "blocked fraction {f}");
    }

    #[test]
    fn agrees_when_all_polygons_lie_in_one_plane() {
        let mut scene = Scene::random(1200, 3, 0.03);
        for c in scene.corners.iter_mut() {
            for p in c.iter_mut() {
                p.z = 0.5;
            }
        }
        // Projection keeps the quads planar and convex (some become slivers or segments).
        let mut segs = random_segments(600, 11, 1.0);
        for q in 0..300u32 {
            // In the plane: never blocked.
            let (mut a, mut b) = (rnd3(q, 50), rnd3(q, 51));
            a.z = 0.5;
            b.z = 0.5;
            segs.push((a, b, [NONE, NONE]));
            // Straight down through the plane.
            let c = rnd3(q, 52);
            segs.push((c.with_z(1.0), c.with_z(0.0), [NONE, NONE]));
        }
        let f = scene.compare(&segs);
        assert!(f > 0.1 && f < 0.95, "blocked fraction {f}");
    }

    #[test]
    fn agrees_when_all_centroids_coincide() {
        let (corners, counts): (Vec<_>, Vec<_>) = (0..800)
            .map(|i| polygon(i, 4, Vec3::splat(0.5), 0.2 + 0.2 * unit(hash3(i, 4, 99))))
            .unzip();
        let scene = Scene { corners, counts };
        let f = scene.compare(&random_segments(700, 13, 1.0));
        assert!(f > 0.2 && f < 1.0, "blocked fraction {f}");
    }

    #[test]
    fn a_stack_of_coincident_polygons_agrees_with_brute_force_from_inside_and_through() {
        // 600 identical 1 um triangles and a quad above: segments that start on the stack
        // (whose crossings of it fall within the end margin: the traversal skips it) and
        // segments through it agree with brute force.
        let tri = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1e-6, 0.0, 0.0),
            Vec3::new(0.0, 1e-6, 0.0),
            Vec3::new(0.0, 1e-6, 0.0),
        ];
        let mut corners = vec![tri; 600];
        let mut counts = vec![3u8; 600];
        corners.push([
            Vec3::new(-1.0, -1.0, 1.0),
            Vec3::new(1.0, -1.0, 1.0),
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(-1.0, 1.0, 1.0),
        ]);
        counts.push(4);
        let scene = Scene { corners, counts };
        let mut segs = Vec::new();
        for q in 0..200u32 {
            let (u, v) = unit2(hash3(q, 70, 0));
            let x = point_on(&tri[..3], u, v);
            let d = rnd3(q, 71) * 2.0 - Vec3::ONE;
            segs.push((x, x + d, [q % 600, NONE]));
            segs.push((x - d, x + d, [NONE, NONE]));
        }
        let f = scene.compare(&segs);
        assert!(f > 0.2 && f < 1.0, "blocked fraction {f}");
    }

    #[test]
    fn surface_to_surface_segments_skip_their_own_polygons() {
        let scene = Scene::random(1000, 5, 0.05);
        let mut segs = Vec::new();
        for q in 0..800u32 {
            let i = hash3(q, 60, 0) % 1000;
            let j = hash3(q, 61, 0) % 1000;
            let (u, v) = unit2(hash3(q, 62, 0));
            let (s, t) = unit2(hash3(q, 63, 0));
            let a = point_on(scene.poly(i as usize), u, v);
            let b = point_on(scene.poly(j as usize), s, t);
            segs.push((a, b, [i, j]));
        }
        scene.compare(&segs);
        // Ending on a polygon without skipping it does not block either (t near 1 is
        // within the margin), and neither does a coplanar neighbour.
        let floor = [
            [
                Vec3::new(0., 0., 0.),
                Vec3::new(1., 0., 0.),
                Vec3::new(1., 1., 0.),
                Vec3::new(0., 1., 0.),
            ],
            [
                Vec3::new(1., 0., 0.),
                Vec3::new(2., 0., 0.),
                Vec3::new(2., 1., 0.),
                Vec3::new(1., 1., 0.),
            ],
        ];
        let set = SlicePolygons::quads(&floor);
        let mut nodes = [BvhNode::default(); 3];
        let mut order = [0u32; 2];
        let vis = BvhVisibility::build(set, &mut nodes, &mut order).unwrap();
        let on_edge = Vec3::new(1.0, 0.5, 0.0);
        assert_eq!(
            vis.transmittance(on_edge, Vec3::new(1.5, 0.5, 1.0), [0, NONE]),
            1.0
        );
        assert_eq!(
            vis.transmittance(Vec3::new(0.5, 0.5, 1.0), on_edge, [NONE, NONE]),
            1.0
        );
        assert_eq!(
            vis.transmittance(
                Vec3::new(0.5, 0.5, 1.0),
                Vec3::new(0.5, 0.5, -1.0),
                [NONE; 2]
            ),
            0.0
        );
        assert_eq!(
            vis.transmittance(
                Vec3::new(0.5, 0.5, 1.0),
                Vec3::new(0.5, 0.5, -1.0),
                [0, NONE]
            ),
            1.0
        );
        assert_eq!(vis.transmittance(Vec3::NAN, Vec3::ONE, [NONE; 2]), 1.0);
        assert_eq!(vis.transmittance(Vec3::ONE, Vec3::ONE, [NONE; 2]), 1.0);
        // Usable as a trait object shared between threads.
        let dynamic: &(dyn Visibility + Sync) = &vis;
        assert_eq!(
            dynamic.transmittance(Vec3::new(1.5, 0.5, 1.0), Vec3::new(1.5, 0.5, -1.0), [0, 1]),
            1.0
        );
    }

    #[test]
    fn build_refuses_bad_polygons() {
        let mut polys = [[Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ZERO]; 4];
        let counts = [3u8, 3, 2, 3];
        let mut nodes = [BvhNode::default(); 7];
        let mut order = [0u32; 4];
        let set = SlicePolygons::new(&polys, &counts);
        assert_eq!(
            BvhVisibility::build(set, &mut nodes, &mut order).unwrap_err(),
            BvhError::InvalidBounds { primitive: 2 }
        );
        polys[1][1].x = f32::INFINITY;
        let set = SlicePolygons::new(&polys, &[3, 3, 3, 3]);
        assert_eq!(
            BvhVisibility::build(set, &mut nodes, &mut order).unwrap_err(),
            BvhError::InvalidBounds { primitive: 1 }
        );
        let set = SlicePolygons::new(&polys, &[3, 3, 3, 3]);
        assert!(matches!(
            BvhVisibility::build(set, &mut nodes[..6], &mut order),
            Err(BvhError::StorageTooSmall { .. })
        ));
    }
}
