//! Segment queries: which leaves does the segment `from..to` cross?
//!
//! Traversal visits the nearer child first and defers the other on a fixed stack of
//! [`MAX_DEPTH`] entries, which every tree of this module fits (see [`super::SAH_LEVELS`]).
//!
//! # The box test
//! The slab test works on the segment parameter t in [0, 1]. It is conservative: whenever the
//! exact segment touches a (closed) box, the test says so.
//! * The far slab distance is enlarged by the relative factor `1 + 4 * f32::EPSILON`, which
//!   covers the rounding of `(bound - origin) / direction` (Ize 2013, "Robust BVH ray
//!   traversal", uses `1 + 2 * gamma(3)`). Relative to t, so it is scale-free.
//! * A zero direction component gives an infinite inverse; a segment lying exactly in a slab's
//!   boundary plane then gives `0 * inf = NaN`, which the bound updates ignore (a comparison
//!   with NaN is false), so the segment counts as inside that slab (the box is closed) rather
//!   than being lost.
//! * Near and far bounds are chosen from the sign of the direction (including the sign of
//!   zero), not by comparing the two distances, so NaN never picks the wrong side.

use super::{Bvh, BvhNode, MAX_DEPTH};
use glam::Vec3;

/// Relative enlargement of the far slab distance (Ize 2013): >= 1 + 2 gamma(3).
const FAR_PAD: f32 = 1.0 + 4.0 * f32::EPSILON;

/// A segment prepared for slab tests against node boxes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SlabSegment {
    origin: [f32; 3],
    inv: [f32; 3],
    /// Per axis, where the near and far bound sit in a node seen as 8 words
    /// (`min` at 0..3, `max` at 4..7): chosen once from the direction's sign.
    near: [usize; 3],
    far: [usize; 3],
    /// Boxes the segment leaves before this parameter are not met (0 for the whole segment).
    t_min: f32,
}

impl SlabSegment {
    /// The segment `from + t (to - from)`, t in [0, 1]; `None` unless both ends are finite
    /// and the difference is finite too.
    pub(crate) fn new(from: Vec3, to: Vec3) -> Option<Self> {
        let d = to - from;
        if !(from.is_finite() && to.is_finite() && d.is_finite()) {
            return None;
        }
        let d = d.to_array();
        let mut near = [0, 1, 2];
        let mut far = [4, 5, 6];
        for axis in 0..3 {
            // The sign bit, so that -0.0 (inverse -inf) takes the bounds of a negative step.
            if d[axis].is_sign_negative() {
                core::mem::swap(&mut near[axis], &mut far[axis]);
            }
        }
        Some(SlabSegment {
            origin: from.to_array(),
            inv: [1.0 / d[0], 1.0 / d[1], 1.0 / d[2]],
            near,
            far,
            t_min: 0.0,
        })
    }

    /// The parameter where the segment enters the node's box, if it meets the box for some t
    /// in [0, t_max].
    #[inline(always)]
    pub(crate) fn enter(&self, node: &BvhNode, t_max: f32) -> Option<f32> {
        let w: &[f32; 8] = bytemuck::cast_ref(node);
        let mut near = self.t_min;
        let mut far = t_max;
        for axis in 0..3 {
            let t0 = (w[self.near[axis]] - self.origin[axis]) * self.inv[axis];
            let t1 = (w[self.far[axis]] - self.origin[axis]) * self.inv[axis] * FAR_PAD;
            // Written as comparisons so that a NaN distance leaves the bound unchanged (and
            // compiles to one max/min instruction).
            if t0 > near {
                near = t0;
            }
            if t1 < far {
                far = t1;
            }
        }
        if near <= far { Some(near) } else { None }
    }
}

impl Bvh<'_> {
    /// Visits, nearer boxes first, the primitives of every leaf whose box the segment
    /// `from..to` meets, and stops at the first primitive for which `hit` returns true.
    /// Returns whether one did.
    ///
    /// Every primitive the exact segment touches is offered to `hit` (the box test is
    /// conservative); others may be offered too, and `hit` decides. A non-finite end point
    /// meets nothing. A zero-length segment is a point: leaves whose box holds it are visited.
    pub fn any_hit(&self, from: Vec3, to: Vec3, hit: impl FnMut(u32) -> bool) -> bool {
        self.any_hit_within(from, to, 0.0, 1.0, hit)
    }

    /// [`Bvh::any_hit`] for the part `t_min..=t_max` of the segment: leaves whose box it
    /// meets only outside that range are not visited (a segment that starts inside a stack
    /// of thousands of coincident polygons does not visit them when their crossings fall
    /// within the caller's end margin).
    pub fn any_hit_within(
        &self,
        from: Vec3,
        to: Vec3,
        t_min: f32,
        t_max: f32,
        mut hit: impl FnMut(u32) -> bool,
    ) -> bool {
        let Some(root) = self.nodes.first() else {
            return false;
        };
        let Some(mut seg) = SlabSegment::new(from, to) else {
            return false;
        };
        seg.t_min = t_min.max(0.0);
        let t_max = t_max.min(1.0);
        if seg.enter(root, t_max).is_none() {
            return false;
        }
        let mut stack = [0u32; MAX_DEPTH];
        let mut sp = 0usize;
        let mut node = root;
        loop {
            if node.is_leaf() {
                let ids = &self.order[node.first as usize..(node.first + node.count) as usize];
                for &id in ids {
                    if hit(id) {
                        return true;
                    }
                }
            } else {
                let l = node.first as usize;
                let (left, right) = (&self.nodes[l], &self.nodes[l + 1]);
                match (seg.enter(left, t_max), seg.enter(right, t_max)) {
                    (Some(tl), Some(tr)) => {
                        // Depth bound of the tree: the stack holds one entry per level above.
                        if tl <= tr {
                            stack[sp] = l as u32 + 1;
                            node = left;
                        } else {
                            stack[sp] = l as u32;
                            node = right;
                        }
                        sp += 1;
                        continue;
                    }
                    (Some(_), None) => {
                        node = left;
                        continue;
                    }
                    (None, Some(_)) => {
                        node = right;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            if sp == 0 {
                return false;
            }
            sp -= 1;
            node = &self.nodes[stack[sp] as usize];
        }
    }

    /// The nearest primitive along the segment `from..to`: `hit(id, t_max)` returns the
    /// parameter t in [0, t_max) at which the segment crosses primitive `id`, or `None`.
    /// Returns the id and t of the smallest t found (the first in traversal order on ties),
    /// or `None` if nothing is crossed. Boxes entered beyond the best t so far are skipped,
    /// so a primitive whose own t rounds below the best while its box's entry rounds above
    /// it (coplanar primitives) may be passed over: the result is nearest up to rounding.
    pub fn closest_hit(
        &self,
        from: Vec3,
        to: Vec3,
        hit: impl FnMut(u32, f32) -> Option<f32>,
    ) -> Option<(u32, f32)> {
        self.closest_hit_within(from, to, 0.0, 1.0, hit)
    }

    /// [`Bvh::closest_hit`] for the part `t_min..=t_max` of the segment (see
    /// [`Bvh::any_hit_within`]).
    pub fn closest_hit_within(
        &self,
        from: Vec3,
        to: Vec3,
        t_min: f32,
        t_max: f32,
        mut hit: impl FnMut(u32, f32) -> Option<f32>,
    ) -> Option<(u32, f32)> {
        let root = self.nodes.first()?;
        let mut seg = SlabSegment::new(from, to)?;
        seg.t_min = t_min.max(0.0);
        let mut t_max = t_max.min(1.0);
        seg.enter(root, t_max)?;
        let mut best: Option<(u32, f32)> = None;
        let mut stack = [(0u32, 0.0f32); MAX_DEPTH];
        let mut sp = 0usize;
        let mut node = root;
        loop {
            if node.is_leaf() {
                let ids = &self.order[node.first as usize..(node.first + node.count) as usize];
                for &id in ids {
                    if let Some(t) = hit(id, t_max)
                        && t < t_max
                    {
                        t_max = t;
                        best = Some((id, t));
                    }
                }
            } else {
                let l = node.first as usize;
                let (left, right) = (&self.nodes[l], &self.nodes[l + 1]);
                match (seg.enter(left, t_max), seg.enter(right, t_max)) {
                    (Some(tl), Some(tr)) => {
                        if tl <= tr {
                            stack[sp] = (l as u32 + 1, tr);
                            node = left;
                        } else {
                            stack[sp] = (l as u32, tl);
                            node = right;
                        }
                        sp += 1;
                        continue;
                    }
                    (Some(_), None) => {
                        node = left;
                        continue;
                    }
                    (None, Some(_)) => {
                        node = right;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop, skipping boxes entered beyond the best hit found since they were pushed.
            loop {
                if sp == 0 {
                    return best;
                }
                sp -= 1;
                let (next, t_enter) = stack[sp];
                if t_enter <= t_max {
                    node = &self.nodes[next as usize];
                    break;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::bvh::{build, nodes_needed};
    use crate::geometry::Aabb;
    use crate::sampling::{hash3, unit2};
    use std::vec;
    use std::vec::Vec;

    fn node(min: [f32; 3], max: [f32; 3]) -> BvhNode {
        BvhNode {
            min,
            first: 0,
            max,
            count: 1,
        }
    }

    fn meets(from: [f32; 3], to: [f32; 3], b: &BvhNode) -> bool {
        SlabSegment::new(Vec3::from_array(from), Vec3::from_array(to))
            .unwrap()
            .enter(b, 1.0)
            .is_some()
    }

    #[test]
    fn slab_basics() {
        let b = node([0.0; 3], [1.0; 3]);
        assert!(meets([-1.0, 0.5, 0.5], [2.0, 0.5, 0.5], &b));
        assert!(meets([0.5; 3], [0.6; 3], &b), "inside");
        assert!(
            meets([-1.0, 0.5, 0.5], [0.0, 0.5, 0.5], &b),
            "ends on the face"
        );
        assert!(
            !meets([-1.0, 0.5, 0.5], [-0.1, 0.5, 0.5], &b),
            "stops short"
        );
        assert!(!meets([2.0, 0.5, 0.5], [3.0, 0.5, 0.5], &b), "beyond");
        assert!(
            !meets([-1.0, 2.0, 0.5], [2.0, 2.0, 0.5], &b),
            "passes above"
        );
        // Reversed direction.
        assert!(meets([2.0, 0.5, 0.5], [-1.0, 0.5, 0.5], &b));
        assert!(!meets([3.0, 0.5, 0.5], [2.0, 0.5, 0.5], &b));
        // Diagonal that misses a corner, and one that passes through it.
        assert!(!meets([1.5, -0.5, 0.5], [2.5, 0.5, 0.5], &b));
        assert!(meets([2.0, -1.0, 0.5], [0.0, 1.0, 0.5], &b));
    }

    #[test]
    fn axis_parallel_segments_on_faces_and_edges() {
        let b = node([0.0; 3], [1.0; 3]);
        // Lying in a face plane (0 * inf = NaN in that slab), inside and outside the face.
        assert!(meets([-1.0, 0.0, 0.5], [2.0, 0.0, 0.5], &b));
        assert!(meets([-1.0, 1.0, 0.5], [2.0, 1.0, 0.5], &b));
        assert!(
            meets([-1.0, 0.0, 0.0], [2.0, 0.0, 0.0], &b),
            "along an edge"
        );
        assert!(meets([-1.0, 1.0, 1.0], [2.0, 1.0, 1.0], &b));
        assert!(!meets([-1.0, 0.0, 1.5], [2.0, 0.0, 1.5], &b));
        assert!(!meets([-1.0, -0.0, 2.0], [2.0, -0.0, 2.0], &b));
        // Negative zero components behave as positive ones.
        assert!(meets([2.0, -0.0, 0.5], [-1.0, 0.0, 0.5], &b));
        assert!(meets([0.5, 0.5, 2.0], [0.5, 0.5, -2.0], &b));
        // Flat boxes (a polygon in an axis plane) are met by segments crossing the plane.
        let flat = node([0.0, 0.0, 0.3], [1.0, 1.0, 0.3]);
        assert!(meets([0.5, 0.5, 1.0], [0.5, 0.5, -1.0], &flat));
        assert!(meets([0.2, 0.3, 1.0], [0.6, 0.7, -1.0], &flat));
        assert!(!meets([0.2, 0.3, 1.0], [0.6, 0.7, 0.31], &flat));
        // A degenerate point box.
        let point = node([0.25; 3], [0.25; 3]);
        assert!(meets([0.0; 3], [0.5; 3], &point));
        assert!(meets([0.25, 0.25, 0.0], [0.25, 0.25, 1.0], &point));
        assert!(!meets([0.25, 0.26, 0.0], [0.25, 0.26, 1.0], &point));
        // Zero-length segment: a point test.
        assert!(meets([0.5; 3], [0.5; 3], &b));
        assert!(!meets([1.5; 3], [1.5; 3], &b));
        assert!(SlabSegment::new(Vec3::NAN, Vec3::ONE).is_none());
        assert!(SlabSegment::new(Vec3::splat(-3e38), Vec3::splat(3e38)).is_none());
    }

    #[test]
    fn scale_free_box_test() {
        // The same grazing configuration at very different scales.
        for s in [1e-30f32, 1e-3, 1.0, 1e3, 1e30] {
            let b = node([0.0, 0.0, 0.0], [s, s, s]);
            let f = |v: [f32; 3]| [v[0] * s, v[1] * s, v[2] * s];
            assert!(meets(f([-1.0, 1.0, 0.5]), f([1.0, -1.0, 0.5]), &b));
            assert!(!meets(f([-1.0, 0.99, 0.5]), f([0.99, -1.0, 0.5]), &b));
            assert!(meets(f([-1.0, 0.0, 0.5]), f([2.0, 0.0, 0.5]), &b));
        }
    }

    /// Random small boxes and random segments: the traversal visits exactly the boxes a
    /// brute-force slab test accepts (for the primitive boxes themselves).
    #[test]
    fn traversal_matches_brute_force_on_boxes() {
        let n = 2000u32;
        let unit = |h| unit2(h).0;
        let boxes: Vec<Aabb> = (0..n)
            .map(|i| {
                let c = Vec3::new(
                    unit(hash3(i, 1, 1)),
                    unit(hash3(i, 1, 2)),
                    unit(hash3(i, 1, 3)),
                );
                Aabb::new(c - 0.01, c + 0.01)
            })
            .collect();
        let mut nodes = vec![BvhNode::default(); nodes_needed(n)];
        let mut order = vec![0u32; n as usize];
        let bvh = build(n, |i| boxes[i as usize], &mut nodes, &mut order).unwrap();
        for q in 0..500u32 {
            let p = |k| {
                Vec3::new(
                    unit(hash3(q, k, 1)),
                    unit(hash3(q, k, 2)),
                    unit(hash3(q, k, 3)),
                )
            };
            let (from, to) = (p(10), p(20));
            let seg = SlabSegment::new(from, to).unwrap();
            let mut expected: Vec<u32> = (0..n)
                .filter(|&i| {
                    seg.enter(&BvhNode::with_box(boxes[i as usize]), 1.0)
                        .is_some()
                })
                .collect();
            let mut got = Vec::new();
            let stopped = bvh.any_hit(from, to, |id| {
                if seg
                    .enter(&BvhNode::with_box(boxes[id as usize]), 1.0)
                    .is_some()
                {
                    got.push(id);
                }
                false
            });
            assert!(!stopped);
            got.sort_unstable();
            expected.sort_unstable();
            assert_eq!(got, expected);
            // The closest box entry agrees with the brute-force minimum.
            let entry = |id: u32| seg.enter(&BvhNode::with_box(boxes[id as usize]), 1.0);
            let brute = expected
                .iter()
                .map(|&i| (i, entry(i).unwrap()))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            let closest = bvh.closest_hit(from, to, |id, t_max| entry(id).filter(|&t| t < t_max));
            assert_eq!(closest.map(|c| c.1), brute.map(|b| b.1));
        }
    }

    #[test]
    fn any_hit_stops_early_and_empty_tree_misses() {
        let boxes = [Aabb::new(Vec3::ZERO, Vec3::ONE); 10];
        let mut nodes = [BvhNode::default(); 19];
        let mut order = [0u32; 10];
        let bvh = build(10, |i| boxes[i as usize], &mut nodes, &mut order).unwrap();
        let mut calls = 0;
        assert!(bvh.any_hit(Vec3::splat(-1.0), Vec3::splat(2.0), |_| {
            calls += 1;
            true
        }));
        assert_eq!(calls, 1);
        assert!(!Bvh::EMPTY.any_hit(Vec3::ZERO, Vec3::ONE, |_| true));
        assert!(
            Bvh::EMPTY
                .closest_hit(Vec3::ZERO, Vec3::ONE, |_, _| Some(0.5))
                .is_none()
        );
        assert!(!bvh.any_hit(Vec3::NAN, Vec3::ONE, |_| true));
        assert!(!bvh.any_hit(Vec3::splat(2.0), Vec3::splat(3.0), |_| true));
    }
}
