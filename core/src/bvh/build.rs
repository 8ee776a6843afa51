//! Building a hierarchy into caller storage: binned surface-area heuristic (SAH) with a median
//! split as fallback, an explicit fixed-size stack, no allocation, deterministic output.
//!
//! # Algorithm
//! Each node's primitives are binned by box centre into [`BINS`] bins (fewer for nodes of
//! fewer primitives) on every axis along which the centres spread; the split between bins with the lowest surface-area cost wins
//! (costs in f64, relative to one polygon test, so that no finite f32 box overflows them).
//! Nodes of more than [`MAX_LEAF`] primitives are always split; smaller ones only when the
//! split is cheaper than testing every primitive. When the centres do not spread (all equal,
//! or too close for f32 binning), or below level [`SAH_LEVELS`], the node is split at the
//! median centre along its widest axis, which bounds the depth (see [`SAH_LEVELS`]).
//!
//! # Cost
//! The `bounds` callback is called about twice per primitive and level (binning, then
//! partitioning, which also yields the children's boxes), plus `O(n log n)` times in median
//! splits. Pass precomputed boxes when computing one is expensive.
//!
//! # Determinism
//! Every decision depends only on the set of primitives in a node (box unions are exact,
//! ties go to the first axis and bin, median splits order by centre then id), and leaf ranges
//! are sorted, so the same input gives identical nodes and order regardless of how the
//! standard library's selection orders equal halves.
//!
//! Stack use: about 4 KiB (the deferred-sibling stack of [`MAX_DEPTH`] entries and the bins).

use super::{
    Bvh, BvhError, BvhNode, MAX_DEPTH, MAX_LEAF, MAX_PRIMITIVES, SAH_LEVELS, nodes_needed,
};
use crate::geometry::Aabb;
use glam::Vec3;

/// Bins per axis of the SAH sweep (nodes of fewer primitives use one bin per primitive,
/// at least 4).
pub const BINS: usize = 16;

/// Cost of visiting a node relative to one polygon test, in the SAH.
const TRAVERSAL_COST: f64 = 1.0;

/// A node waiting to be split: its primitive range and the bounds of their box centres.
#[derive(Clone, Copy)]
struct Task {
    node: u32,
    start: u32,
    end: u32,
    level: u32,
    cmin: Vec3,
    cmax: Vec3,
}

impl Task {
    const NONE: Task = Task {
        node: 0,
        start: 0,
        end: 0,
        level: 0,
        cmin: Vec3::ZERO,
        cmax: Vec3::ZERO,
    };
}

/// Box and centre bounds of one side of a split, grown primitive by primitive.
#[derive(Clone, Copy)]
struct Side {
    b: Aabb,
    cmin: Vec3,
    cmax: Vec3,
}

impl Side {
    const EMPTY: Side = Side {
        b: Aabb::EMPTY,
        cmin: Vec3::splat(f32::INFINITY),
        cmax: Vec3::splat(f32::NEG_INFINITY),
    };

    #[inline]
    fn grow(&mut self, b: Aabb) {
        let c = centre(b);
        self.b.min = self.b.min.min(b.min);
        self.b.max = self.b.max.max(b.max);
        self.cmin = self.cmin.min(c);
        self.cmax = self.cmax.max(c);
    }
}

/// A chosen split: primitives `[..mid]` go left.
struct Split {
    mid: usize,
    left: Side,
    right: Side,
}

/// Centre of a box, computed without overflow for any finite box.
#[inline]
fn centre(b: Aabb) -> Vec3 {
    b.min * 0.5 + b.max * 0.5
}

/// Half the surface area of a box in f64, which no finite f32 box overflows; 0 when empty.
fn half_area(b: &Aabb) -> f64 {
    if b.is_empty() {
        return 0.0;
    }
    let d = [
        b.max.x as f64 - b.min.x as f64,
        b.max.y as f64 - b.min.y as f64,
        b.max.z as f64 - b.min.z as f64,
    ];
    d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
}

/// Builds a hierarchy over primitives `0..count` whose boxes `bounds(id)` returns, into the
/// caller's `nodes` (at least [`nodes_needed`]`(count)` entries) and `order` (at least `count`
/// entries). The returned view borrows the used prefixes of both.
///
/// `bounds` must return the same box for the same id every time (it is called several times
/// per primitive); if it does not, the tree may answer queries wrongly but nothing panics.
///
/// Errors: [`BvhError::TooManyPrimitives`] above [`MAX_PRIMITIVES`],
/// [`BvhError::StorageTooSmall`], [`BvhError::InvalidBounds`] for the first primitive whose
/// box is empty or not finite. Never panics, never allocates, never recurses.
pub fn build<'a>(
    count: u32,
    mut bounds: impl FnMut(u32) -> Aabb,
    nodes: &'a mut [BvhNode],
    order: &'a mut [u32],
) -> Result<Bvh<'a>, BvhError> {
    if count > MAX_PRIMITIVES {
        return Err(BvhError::TooManyPrimitives);
    }
    let n = count as usize;
    let need = nodes_needed(count);
    if nodes.len() < need || order.len() < n {
        return Err(BvhError::StorageTooSmall {
            nodes: need,
            order: n,
        });
    }
    if n == 0 {
        return Ok(Bvh::new_unchecked(&nodes[..0], &order[..0]));
    }
    let order = &mut order[..n];
    let mut root = Side::EMPTY;
    for (id, slot) in (0..count).zip(order.iter_mut()) {
        let b = bounds(id);
        if !b.is_finite_nonempty() {
            return Err(BvhError::InvalidBounds { primitive: id });
        }
        root.grow(b);
        *slot = id;
    }
    nodes[0] = BvhNode::with_box(root.b);
    let mut used = 1usize;

    // Deferred right siblings. The current task is on level L and the stack holds at most one
    // entry per level above it, so it never holds more than MAX_DEPTH - 1 entries.
    let mut stack = [Task::NONE; MAX_DEPTH];
    let mut sp = 0usize;
    let mut task = Task {
        node: 0,
        start: 0,
        end: count,
        level: 1,
        cmin: root.cmin,
        cmax: root.cmax,
    };
    loop {
        let prims = &mut order[task.start as usize..task.end as usize];
        let node_box = nodes[task.node as usize].aabb();
        match split(&mut bounds, prims, &node_box, &task) {
            Some(s) => {
                debug_assert!(task.level < MAX_DEPTH as u32 && sp + 1 < MAX_DEPTH);
                // At most 2 * leaves - 1 <= 2n - 1 nodes are ever used.
                let left = used;
                used += 2;
                let parent = &mut nodes[task.node as usize];
                parent.first = left as u32;
                parent.count = 0;
                nodes[left] = BvhNode::with_box(s.left.b);
                nodes[left + 1] = BvhNode::with_box(s.right.b);
                let mid = task.start + s.mid as u32;
                stack[sp] = Task {
                    node: left as u32 + 1,
                    start: mid,
                    end: task.end,
                    level: task.level + 1,
                    cmin: s.right.cmin,
                    cmax: s.right.cmax,
                };
                sp += 1;
                task = Task {
                    node: left as u32,
                    start: task.start,
                    end: mid,
                    level: task.level + 1,
                    cmin: s.left.cmin,
                    cmax: s.left.cmax,
                };
            }
            None => {
                prims.sort_unstable();
                let leaf = &mut nodes[task.node as usize];
                leaf.first = task.start;
                leaf.count = task.end - task.start;
                if sp == 0 {
                    break;
                }
                sp -= 1;
                task = stack[sp];
            }
        }
    }
    Ok(Bvh::new_unchecked(&nodes[..used], order))
}

/// Chooses and performs the split of one node, or `None` to make it a leaf.
fn split(
    bounds: &mut impl FnMut(u32) -> Aabb,
    prims: &mut [u32],
    node_box: &Aabb,
    task: &Task,
) -> Option<Split> {
    let n = prims.len();
    if n <= 1 {
        return None;
    }
    if task.level <= SAH_LEVELS {
        match sah(bounds, prims, node_box, task) {
            Sah::Leaf => return None,
            Sah::Split {
                axis,
                bin,
                bins,
                scale,
            } => {
                let lo = task.cmin[axis];
                let s = partition(bounds, prims, |c| bin_of(c[axis], lo, scale, bins) <= bin);
                if s.mid > 0 && s.mid < n {
                    return Some(s);
                }
                // Only reachable if `bounds` answers differently from one call to the next.
            }
            Sah::NoSpread => {}
        }
    }
    if n <= MAX_LEAF as usize {
        return None;
    }
    Some(median(bounds, prims, task))
}

enum Sah {
    /// Testing every primitive is cheaper than any split.
    Leaf,
    /// Primitives whose centre falls in bins `0..=bin` (of `bins`) of `axis` go left.
    Split {
        axis: usize,
        bin: usize,
        bins: usize,
        scale: f32,
    },
    /// The centres do not spread along any axis by enough to bin them.
    NoSpread,
}

/// Bin of a centre coordinate `c` for `bins` bins starting at `lo`, `scale = bins / extent`.
/// Saturating conversion: NaN and negative values land in bin 0, so this never panics.
#[inline]
fn bin_of(c: f32, lo: f32, scale: f32, bins: usize) -> usize {
    (((c - lo) * scale) as usize).min(bins - 1)
}

/// The binned SAH decision for one node.
fn sah(bounds: &mut impl FnMut(u32) -> Aabb, prims: &[u32], node_box: &Aabb, task: &Task) -> Sah {
    // An axis can be binned when its centre extent and bins / extent are positive and finite.
    // Then the lowest centre falls in bin 0 and the highest in the last bin (the extent maps
    // to at least bins - 1 after rounding), so every split plane has primitives on both sides.
    let bins = prims.len().clamp(4, BINS);
    let mut scale = [0.0f32; 3];
    let mut any = false;
    for (axis, s) in scale.iter_mut().enumerate() {
        let extent = task.cmax[axis] - task.cmin[axis];
        let k = bins as f32 / extent;
        if extent > 0.0 && extent.is_finite() && k.is_finite() && k > 0.0 {
            *s = k;
            any = true;
        }
    }
    if !any {
        return Sah::NoSpread;
    }
    let mut boxes = [[Aabb::EMPTY; BINS]; 3];
    let mut counts = [[0u32; BINS]; 3];
    for &id in prims {
        let b = bounds(id);
        let c = centre(b);
        for axis in 0..3 {
            if scale[axis] > 0.0 {
                let k = bin_of(c[axis], task.cmin[axis], scale[axis], bins);
                let bin = &mut boxes[axis][k];
                bin.min = bin.min.min(b.min);
                bin.max = bin.max.max(b.max);
                counts[axis][k] += 1;
            }
        }
    }
    // Cost of a split in units of "polygon tests times half area": count * half_area summed
    // over both sides. The traversal and the leaf alternative are compared after the sweep.
    let mut best: Option<(f64, usize, usize)> = None;
    for axis in 0..3 {
        if scale[axis] <= 0.0 {
            continue;
        }
        let (bx, cn) = (&boxes[axis], &counts[axis]);
        // Plain min/max unions: the empty box is their identity, and a box is only measured
        // once it holds a primitive.
        let mut right_cost = [0.0f64; BINS];
        let mut acc = Aabb::EMPTY;
        let mut m = 0u32;
        for k in (1..bins).rev() {
            acc = Aabb::new(acc.min.min(bx[k].min), acc.max.max(bx[k].max));
            m += cn[k];
            right_cost[k - 1] = if m == 0 {
                f64::INFINITY
            } else {
                m as f64 * half_area(&acc)
            };
        }
        let mut acc = Aabb::EMPTY;
        let mut m = 0u32;
        for k in 0..bins - 1 {
            acc = Aabb::new(acc.min.min(bx[k].min), acc.max.max(bx[k].max));
            m += cn[k];
            if m == 0 {
                continue;
            }
            let cost = m as f64 * half_area(&acc) + right_cost[k];
            if best.is_none_or(|(b, _, _)| cost < b) {
                best = Some((cost, axis, k));
            }
        }
    }
    let Some((cost, axis, bin)) = best else {
        return Sah::NoSpread;
    };
    let n = prims.len();
    if n <= MAX_LEAF as usize {
        let area = half_area(node_box);
        if TRAVERSAL_COST * area + cost >= n as f64 * area {
            return Sah::Leaf;
        }
    }
    Sah::Split {
        axis,
        bin,
        bins,
        scale: scale[axis],
    }
}

/// Partitions `prims` in place so that those whose box centre satisfies `left` come first,
/// and measures both sides. One `bounds` call per primitive.
fn partition(
    bounds: &mut impl FnMut(u32) -> Aabb,
    prims: &mut [u32],
    left: impl Fn(Vec3) -> bool,
) -> Split {
    let (mut l, mut r) = (Side::EMPTY, Side::EMPTY);
    let (mut i, mut j) = (0usize, prims.len());
    while i < j {
        let b = bounds(prims[i]);
        if left(centre(b)) {
            l.grow(b);
            i += 1;
        } else {
            j -= 1;
            prims.swap(i, j);
            r.grow(b);
        }
    }
    Split {
        mid: i,
        left: l,
        right: r,
    }
}

/// Splits at the median centre along the widest axis of the centres (ties by id), so both
/// halves are non-empty and at most half (rounded up) the primitives.
fn median(bounds: &mut impl FnMut(u32) -> Aabb, prims: &mut [u32], task: &Task) -> Split {
    let mut axis = 0;
    let mut widest = -1.0f64;
    for a in 0..3 {
        let e = task.cmax[a] as f64 - task.cmin[a] as f64;
        if e > widest {
            widest = e;
            axis = a;
        }
    }
    let mid = prims.len() / 2;
    prims.select_nth_unstable_by(mid, |&a, &b| {
        let (ca, cb) = (centre(bounds(a))[axis], centre(bounds(b))[axis]);
        ca.total_cmp(&cb).then(a.cmp(&b))
    });
    let (mut l, mut r) = (Side::EMPTY, Side::EMPTY);
    for &id in &prims[..mid] {
        l.grow(bounds(id));
    }
    for &id in &prims[mid..] {
        r.grow(bounds(id));
    }
    Split {
        mid,
        left: l,
        right: r,
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::sampling::{hash3, unit2};
    use std::vec;
    use std::vec::Vec;

    fn unit(h: u32) -> f32 {
        unit2(h).0
    }

    /// Random boxes: centres in the unit cube times `scale`, sizes up to `size * scale`.
    fn random_boxes(n: u32, seed: u32, scale: f32, size: f32) -> Vec<Aabb> {
        (0..n)
            .map(|i| {
                let c = Vec3::new(
                    unit(hash3(i, seed, 1)),
                    unit(hash3(i, seed, 2)),
                    unit(hash3(i, seed, 3)),
                );
                let h = Vec3::new(
                    unit(hash3(i, seed, 4)),
                    unit(hash3(i, seed, 5)),
                    unit(hash3(i, seed, 6)),
                ) * size;
                Aabb::new((c - h) * scale, (c + h) * scale)
            })
            .collect()
    }

    /// Checks the tree invariants: every primitive in exactly one leaf, leaves of at most
    /// MAX_LEAF, children inside their parent, boxes tight around what they hold.
    fn check(bvh: &Bvh, boxes: &[Aabb]) {
        Bvh::from_parts(bvh.nodes(), bvh.order()).unwrap();
        assert!(bvh.nodes().len() <= nodes_needed(boxes.len() as u32));
        let mut seen = vec![false; boxes.len()];
        for (i, node) in bvh.nodes().iter().enumerate() {
            let b = node.aabb();
            if node.is_leaf() {
                assert!(node.count <= MAX_LEAF, "leaf {i} holds {}", node.count);
                let ids = &bvh.order()[node.first as usize..(node.first + node.count) as usize];
                assert!(ids.windows(2).all(|w| w[0] < w[1]), "leaf ids sorted");
                let mut tight = Aabb::EMPTY;
                for &id in ids {
                    assert!(!seen[id as usize]);
                    seen[id as usize] = true;
                    tight = tight.union(boxes[id as usize]);
                }
                assert_eq!(tight, b);
            } else {
                let (l, r) = (
                    bvh.nodes()[node.first as usize].aabb(),
                    bvh.nodes()[node.first as usize + 1].aabb(),
                );
                assert_eq!(l.union(r), b, "inner node {i} is the union of its children");
            }
        }
        assert!(seen.iter().all(|&s| s));
        assert!(bvh.depth() <= MAX_DEPTH);
    }

    fn build_vec(boxes: &[Aabb]) -> (Vec<BvhNode>, Vec<u32>, usize) {
        let n = boxes.len() as u32;
        let mut nodes = vec![BvhNode::default(); nodes_needed(n)];
        let mut order = vec![0u32; n as usize];
        let used = {
            let bvh = build(n, |i| boxes[i as usize], &mut nodes, &mut order).unwrap();
            check(&bvh, boxes);
            bvh.nodes().len()
        };
        (nodes, order, used)
    }

    #[test]
    fn small_counts() {
        for n in 0..40 {
            let boxes = random_boxes(n, 3, 1.0, 0.05);
            let (_, _, used) = build_vec(&boxes);
            assert!(used <= nodes_needed(n));
            if n == 0 {
                assert_eq!(used, 0);
            }
        }
    }

    #[test]
    fn random_trees_are_valid_and_shallow() {
        let boxes = random_boxes(5000, 11, 1.0, 0.01);
        let n = boxes.len() as u32;
        let mut nodes = vec![BvhNode::default(); nodes_needed(n)];
        let mut order = vec![0u32; n as usize];
        let bvh = build(n, |i| boxes[i as usize], &mut nodes, &mut order).unwrap();
        check(&bvh, &boxes);
        // A good tree over uniform boxes is near log2(n / leaf) deep.
        assert!(bvh.depth() < 30, "depth {}", bvh.depth());
    }

    #[test]
    fn deterministic_and_scale_free() {
        let boxes = random_boxes(3000, 5, 1.0, 0.02);
        let (a_nodes, a_order, a_used) = build_vec(&boxes);
        let (b_nodes, b_order, b_used) = build_vec(&boxes);
        assert_eq!(a_used, b_used);
        assert_eq!(a_nodes, b_nodes);
        assert_eq!(a_order, b_order);
        // Scaling by powers of two is exact, so the trees are the same up to the scale.
        for s in [
            1.0f32 / 1024.0,
            1024.0,
            1.0 / (1u64 << 40) as f32,
            (1u64 << 40) as f32,
        ] {
            let scaled: Vec<Aabb> = boxes
                .iter()
                .map(|b| Aabb::new(b.min * s, b.max * s))
                .collect();
            let (nodes, order, used) = build_vec(&scaled);
            assert_eq!(used, a_used);
            assert_eq!(order, a_order);
            for (x, y) in nodes.iter().zip(&a_nodes).take(used) {
                assert_eq!((x.first, x.count), (y.first, y.count));
                assert_eq!(x.aabb().min, y.aabb().min * s);
            }
        }
    }

    #[test]
    fn degenerate_inputs() {
        // All boxes equal: median splits by id.
        let same = vec![Aabb::new(Vec3::splat(1.0), Vec3::splat(2.0)); 1000];
        build_vec(&same);
        // Points (zero-size boxes), all in one plane, and at one place.
        let flat: Vec<Aabb> = random_boxes(1000, 7, 1.0, 0.0)
            .iter()
            .map(|b| {
                let mut p = b.min;
                p.z = 0.0;
                Aabb::new(p, p)
            })
            .collect();
        build_vec(&flat);
        let point = vec![Aabb::new(Vec3::ZERO, Vec3::ZERO); 257];
        build_vec(&point);
        // Equal centres, different sizes.
        let nested: Vec<Aabb> = (0..500)
            .map(|i| Aabb::new(Vec3::splat(-(i as f32)), Vec3::splat(i as f32)))
            .collect();
        build_vec(&nested);
        // Huge and tiny magnitudes side by side, and the extremes of f32.
        let mut wild = random_boxes(300, 9, 1e30, 0.1);
        wild.extend(random_boxes(300, 10, 1e-30, 0.1));
        wild.push(Aabb::new(Vec3::splat(-f32::MAX), Vec3::splat(f32::MAX)));
        wild.push(Aabb::new(Vec3::splat(f32::MAX), Vec3::splat(f32::MAX)));
        wild.push(Aabb::new(
            Vec3::splat(f32::MIN_POSITIVE * 1e-3),
            Vec3::splat(1e-40),
        ));
        build_vec(&wild);
    }

    #[test]
    fn depth_stays_bounded_on_adversarial_spreads() {
        // Exponentially spread centres make SAH peel one primitive per level; the forced
        // median splits below SAH_LEVELS keep the depth under MAX_DEPTH.
        let boxes: Vec<Aabb> = (0..3000)
            .map(|i| {
                let x = libm::powf(1.5, (i % 200) as f32) * if i % 2 == 0 { 1.0 } else { -1.0 };
                Aabb::new(Vec3::new(x, 0.0, 0.0), Vec3::new(x, 1.0, 1.0))
            })
            .collect();
        let n = boxes.len() as u32;
        let mut nodes = vec![BvhNode::default(); nodes_needed(n)];
        let mut order = vec![0u32; n as usize];
        let bvh = build(n, |i| boxes[i as usize], &mut nodes, &mut order).unwrap();
        check(&bvh, &boxes);
        assert!(bvh.depth() <= SAH_LEVELS as usize + 12);
    }

    #[test]
    fn refuses_bad_input_and_small_storage() {
        let boxes = random_boxes(100, 1, 1.0, 0.1);
        let mut nodes = vec![BvhNode::default(); nodes_needed(100)];
        let mut order = vec![0u32; 100];
        let small = build(100, |i| boxes[i as usize], &mut nodes[..198], &mut order);
        assert_eq!(
            small.unwrap_err(),
            BvhError::StorageTooSmall {
                nodes: 199,
                order: 100
            }
        );
        let small = build(100, |i| boxes[i as usize], &mut nodes, &mut order[..99]);
        assert!(matches!(small, Err(BvhError::StorageTooSmall { .. })));
        for bad in [
            Aabb::new(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::ONE),
            Aabb::new(Vec3::ZERO, Vec3::new(0.0, f32::INFINITY, 0.0)),
            Aabb::new(Vec3::ONE, Vec3::ZERO),
            Aabb::EMPTY,
        ] {
            let r = build(
                100,
                |i| if i == 42 { bad } else { boxes[i as usize] },
                &mut nodes,
                &mut order,
            );
            assert_eq!(r.unwrap_err(), BvhError::InvalidBounds { primitive: 42 });
        }
        let r = build(MAX_PRIMITIVES + 1, |_| Aabb::EMPTY, &mut nodes, &mut order);
        assert_eq!(r.unwrap_err(), BvhError::TooManyPrimitives);
        // Larger storage than needed is fine; only a prefix is used.
        let mut big = vec![BvhNode::default(); 1000];
        let mut big_order = vec![0u32; 1000];
        let bvh = build(100, |i| boxes[i as usize], &mut big, &mut big_order).unwrap();
        assert_eq!(bvh.len(), 100);
    }

    #[test]
    fn inconsistent_bounds_do_not_panic() {
        // A callback that answers differently on every call.
        let calls = core::cell::Cell::new(0u32);
        let mut nodes = vec![BvhNode::default(); nodes_needed(500)];
        let mut order = vec![0u32; 500];
        let r = build(
            500,
            |i| {
                let k = calls.get();
                calls.set(k + 1);
                let c = Vec3::new(
                    unit(hash3(i, k, 1)),
                    unit(hash3(i, k, 2)),
                    unit(hash3(i, k, 3)),
                );
                if k > 600 && k.is_multiple_of(7) {
                    Aabb::new(Vec3::splat(f32::NAN), Vec3::splat(f32::NAN))
                } else {
                    Aabb::new(c, c + 0.01)
                }
            },
            &mut nodes,
            &mut order,
        );
        let bvh = r.unwrap();
        let mut seen = vec![false; 500];
        for &id in bvh.order() {
            seen[id as usize] = true;
        }
        assert!(seen.iter().all(|&s| s));
    }
}
