//! New boxes for an unchanged tree after its primitives moved.
//!
//! The topology stays: refitting is cheap (one pass, one `bounds` call per primitive) but the
//! tree's quality degrades as primitives move relative to each other; rebuild with
//! [`build()`](super::build::build) when they have moved far.

use super::{Bvh, BvhError, BvhNode, check_structure};
use crate::geometry::Aabb;

/// Recomputes every box of the tree stored in `nodes` and `order` (the arrays of a previous
/// [`build()`](super::build::build) or any arrays [`Bvh::from_parts`] accepts, boxes aside)
/// from the primitives' new boxes `bounds(id)`, and returns the view of the refitted tree.
///
/// Children always lie after their parent, so one pass from the last node to the first sees
/// every child before its parent. Errors: [`BvhError::Malformed`] if the arrays are not a
/// tree, [`BvhError::InvalidBounds`] for a primitive whose new box is empty or not finite (the
/// boxes are then partly updated and the arrays must be refitted again before use).
pub fn refit<'a>(
    nodes: &'a mut [BvhNode],
    order: &'a [u32],
    mut bounds: impl FnMut(u32) -> Aabb,
) -> Result<Bvh<'a>, BvhError> {
    check_structure(nodes, order, false)?;
    for i in (0..nodes.len()).rev() {
        let n = nodes[i];
        let b = if n.is_leaf() {
            let mut b = Aabb::EMPTY;
            for &id in &order[n.first as usize..(n.first + n.count) as usize] {
                let p = bounds(id);
                if !p.is_finite_nonempty() {
                    return Err(BvhError::InvalidBounds { primitive: id });
                }
                b = b.union(p);
            }
            b
        } else {
            let l = n.first as usize;
            nodes[l].aabb().union(nodes[l + 1].aabb())
        };
        nodes[i].min = b.min.to_array();
        nodes[i].max = b.max.to_array();
    }
    Ok(Bvh::new_unchecked(nodes, order))
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::bvh::{build, nodes_needed};
    use crate::sampling::{hash3, unit2};
    use glam::Vec3;
    use std::vec;
    use std::vec::Vec;

    fn boxes(n: u32, shift: f32) -> Vec<Aabb> {
        (0..n)
            .map(|i| {
                let u = |k| unit2(hash3(i, 3, k)).0;
                let c = Vec3::new(u(1), u(2), u(3)) + Vec3::new(shift * u(4), 0.0, 0.0);
                Aabb::new(c - 0.01, c + 0.01)
            })
            .collect()
    }

    #[test]
    fn refit_gives_tight_boxes_and_same_answers() {
        let n = 1000;
        let before = boxes(n, 0.0);
        let after = boxes(n, 0.3);
        let mut nodes = vec![BvhNode::default(); nodes_needed(n)];
        let mut order = vec![0u32; n as usize];
        let used = build(n, |i| before[i as usize], &mut nodes, &mut order)
            .unwrap()
            .nodes()
            .len();
        let bvh = refit(&mut nodes[..used], &order, |i| after[i as usize]).unwrap();
        // Same structure, boxes valid for the new positions.
        let checked = Bvh::from_parts(bvh.nodes(), bvh.order()).unwrap();
        assert_eq!(
            checked.bounds(),
            after.iter().fold(Aabb::EMPTY, |a, b| a.union(*b))
        );
        for q in 0..300u32 {
            let p = |k| Vec3::new(unit2(hash3(q, k, 1)).0, unit2(hash3(q, k, 2)).0, 0.5) * 1.3;
            let (from, to) = (p(5), p(6));
            let mut got = Vec::new();
            bvh.any_hit(from, to, |id| {
                got.push(id);
                false
            });
            // Every box the segment meets is among the visited leaves' primitives.
            for (i, b) in after.iter().enumerate() {
                let meets = crate::bvh::query::SlabSegment::new(from, to)
                    .unwrap()
                    .enter(&BvhNode::with_box(*b), 1.0)
                    .is_some();
                if meets {
                    assert!(got.contains(&(i as u32)), "query {q} missed {i}");
                }
            }
        }
    }

    #[test]
    fn refit_refuses_bad_input() {
        let b = boxes(10, 0.0);
        let mut nodes = vec![BvhNode::default(); nodes_needed(10)];
        let mut order = vec![0u32; 10];
        let used = build(10, |i| b[i as usize], &mut nodes, &mut order)
            .unwrap()
            .nodes()
            .len();
        let r = refit(&mut nodes[..used], &order, |i| {
            if i == 3 { Aabb::EMPTY } else { b[i as usize] }
        });
        assert_eq!(r.unwrap_err(), BvhError::InvalidBounds { primitive: 3 });
        let mut broken = nodes.clone();
        broken[0].first = 0;
        broken[0].count = 0;
        assert!(matches!(
            refit(&mut broken[..used], &order, |i| b[i as usize]),
            Err(BvhError::Malformed { .. })
        ));
    }
}
