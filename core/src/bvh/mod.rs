//! The core's own bounding volume hierarchy over the polygons of one level, built into storage
//! the caller provides, and the occlusion test the solver asks of it.
//!
//! The module follows parry's split of concerns:
//! * [`build()`](build::build): binned SAH with a median-split fallback, an explicit fixed-size
//!   stack, no allocation, deterministic output;
//! * [`query`]: segment traversal ([`Bvh::any_hit`], [`Bvh::closest_hit`]);
//! * [`refit()`](refit::refit): new boxes for an unchanged tree after its primitives moved;
//! * [`polygon`]: the watertight segment/triangle and segment/quad test and the
//!   [`PolygonSet`] trait the visibility reads polygons through;
//! * [`visibility`]: [`BvhVisibility`], the [`crate::visibility::Visibility`] of the core.
//!
//! # Storage
//! Like smoltcp's sockets, the hierarchy owns no memory: the caller hands in a node slice of at
//! least [`nodes_needed`]`(n)` entries and an order slice of at least `n` entries, and gets back
//! a [`Bvh`] view that borrows them. [`bytes_needed`] gives a planner the exact byte count.
//!
//! # Layout
//! Nodes are stored in one array, the root at index 0. An inner node's two children sit next
//! to each other (`first` and `first + 1`), always at larger indices than their parent; a leaf
//! names the range `order[first..first + count]` of primitive ids. A tree of `n >= 1`
//! primitives therefore uses `2 * leaves - 1 <= 2n - 1` nodes.
//!
//! # Numbers
//! Nothing here uses an absolute tolerance: box tests are padded by a relative amount of the
//! segment parameter (Ize 2013, "Robust BVH ray traversal"), surface-area costs are evaluated
//! in f64 so that no finite f32 box overflows them, and the polygon test is the watertight one
//! of Woop, Benthin and Wald (2013). A scene in millimetres and the same scene in kilometres
//! give the same answers.

pub mod build;
pub mod polygon;
pub mod query;
pub mod refit;
pub mod visibility;

pub use build::build;
pub use polygon::{PolygonSet, SegmentTest, SlicePolygons, segment_polygon};
pub use refit::refit;
pub use visibility::{BvhVisibility, SEGMENT_MARGIN};

use crate::geometry::Aabb;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// Most primitives in one leaf made by [`build()`](build::build).
pub const MAX_LEAF: u32 = 4;

/// Most levels of a hierarchy, the root counting as level 1. [`build()`](build::build) stays
/// below it by construction (see [`SAH_LEVELS`]) and [`Bvh::from_parts`] refuses deeper trees,
/// so the fixed traversal stacks (`MAX_DEPTH` entries of 4 to 8 bytes) can never overflow.
pub const MAX_DEPTH: usize = 64;

/// Levels on which [`build()`](build::build) may choose a surface-area split (the root is level
/// 1). Deeper nodes are split at their median, which halves the primitive count, so that a
/// node of at most [`MAX_PRIMITIVES`] = 2^30 primitives on level 33 ends in leaves of at most
/// [`MAX_LEAF`] = 4 primitives after at most 28 more levels: at most 61 levels in all, below
/// [`MAX_DEPTH`].
pub const SAH_LEVELS: u32 = 32;

/// Most primitives one hierarchy may hold (node indices must fit in `u32`).
pub const MAX_PRIMITIVES: u32 = 1 << 30;

/// One node of the hierarchy: 32 bytes, plain old data, so that a tree can be stored in and
/// read back from a byte image.
///
/// The box is stored as two corners interleaved with the two index words, so that each half
/// of the node is 16 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhNode {
    /// Lower corner of the box (m).
    pub min: [f32; 3],
    /// Leaf: index of the first primitive in the order array. Inner node: index of the left
    /// child; the right child is at `first + 1`.
    pub first: u32,
    /// Upper corner of the box (m).
    pub max: [f32; 3],
    /// Leaf: number of primitives (at least 1). Inner node: 0.
    pub count: u32,
}

impl BvhNode {
    /// A node with the given box whose index words are not set yet.
    pub fn with_box(b: Aabb) -> Self {
        BvhNode {
            min: b.min.to_array(),
            first: 0,
            max: b.max.to_array(),
            count: 0,
        }
    }

    /// True for a leaf (a node that names primitives rather than children).
    #[inline]
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }

    /// The node's box.
    #[inline]
    pub fn aabb(&self) -> Aabb {
        Aabb::new(Vec3::from_array(self.min), Vec3::from_array(self.max))
    }
}

/// Why a hierarchy cannot be built or read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BvhError {
    /// The caller's storage is too small; the fields say how many entries are needed.
    StorageTooSmall {
        /// Nodes needed: [`nodes_needed`] of the primitive count.
        nodes: usize,
        /// Order entries needed: the primitive count.
        order: usize,
    },
    /// More than [`MAX_PRIMITIVES`] primitives.
    TooManyPrimitives,
    /// A primitive's box is empty or has a NaN or infinite corner.
    InvalidBounds {
        /// The primitive's id.
        primitive: u32,
    },
    /// Stored nodes that do not form a tree of this module (a child index out of range or not
    /// after its parent, a leaf range outside the order array, an order entry out of range, a
    /// bad box, or more than [`MAX_DEPTH`] levels).
    Malformed {
        /// The first offending node (or order entry, for an order entry out of range).
        index: u32,
    },
}

impl core::fmt::Display for BvhError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            BvhError::StorageTooSmall { nodes, order } => write!(
                f,
                "BVH storage too small: needs {nodes} nodes and {order} order entries"
            ),
            BvhError::TooManyPrimitives => {
                write!(f, "more than {MAX_PRIMITIVES} primitives in one BVH")
            }
            BvhError::InvalidBounds { primitive } => write!(
                f,
                "primitive {primitive} has an empty or non-finite bounding box"
            ),
            BvhError::Malformed { index } => write!(f, "malformed BVH at entry {index}"),
        }
    }
}

/// Nodes a hierarchy over `primitives` primitives may need: `2n - 1` (0 for none). This is
/// exact for the worst case (every leaf holding one primitive), so storage of this size is
/// always enough and [`build()`](build::build) refuses less. Saturates for counts that
/// [`build()`](build::build) refuses anyway.
pub const fn nodes_needed(primitives: u32) -> usize {
    if primitives == 0 {
        return 0;
    }
    let n = 2 * primitives as u64 - 1;
    if n > usize::MAX as u64 {
        usize::MAX
    } else {
        n as usize
    }
}

/// Bytes of caller storage a hierarchy over `primitives` primitives needs: the node array
/// plus the order array (4 bytes per primitive). Saturates on overflow.
pub const fn bytes_needed(primitives: u32) -> usize {
    let nodes = nodes_needed(primitives).saturating_mul(core::mem::size_of::<BvhNode>());
    nodes.saturating_add((primitives as usize).saturating_mul(4))
}

/// A built hierarchy: a read-only view of the caller's node and order arrays.
///
/// Obtained from [`build()`](build::build), [`refit()`](refit::refit) or
/// [`Bvh::from_parts`], which all guarantee the layout described in the module documentation;
/// the queries rely on it.
#[derive(Clone, Copy, Debug)]
pub struct Bvh<'a> {
    nodes: &'a [BvhNode],
    order: &'a [u32],
}

impl<'a> Bvh<'a> {
    /// The hierarchy over no primitives: every query misses.
    pub const EMPTY: Bvh<'static> = Bvh {
        nodes: &[],
        order: &[],
    };

    /// Checks stored arrays (for instance read from a scene image) and views them as a tree.
    ///
    /// Refuses, with [`BvhError::Malformed`]: a node count that does not fit in `u32`, a box
    /// that is empty or not finite, an inner node whose children are not after it inside the
    /// array, a leaf whose range leaves the order array, an order entry that is not a valid
    /// primitive id (`< order.len()`), a tree deeper than [`MAX_DEPTH`] levels or one that
    /// reaches more nodes than it stores (shared subtrees). Empty nodes with empty order is
    /// the empty tree. More than [`MAX_PRIMITIVES`] order entries is
    /// [`BvhError::TooManyPrimitives`]. Runs in time linear in the array sizes, without
    /// allocating.
    pub fn from_parts(nodes: &'a [BvhNode], order: &'a [u32]) -> Result<Self, BvhError> {
        check_structure(nodes, order, true)?;
        Ok(Bvh { nodes, order })
    }

    /// Used by build and refit, which produce valid trees.
    pub(crate) fn new_unchecked(nodes: &'a [BvhNode], order: &'a [u32]) -> Self {
        Bvh { nodes, order }
    }

    /// The nodes, root first.
    pub fn nodes(&self) -> &'a [BvhNode] {
        self.nodes
    }

    /// The primitive ids in leaf order.
    pub fn order(&self) -> &'a [u32] {
        self.order
    }

    /// Number of primitives.
    pub fn len(&self) -> usize {
        self.order.len()
    }

    /// True for the hierarchy over no primitives.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Box of all primitives ([`Aabb::EMPTY`] for none).
    pub fn bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, BvhNode::aabb)
    }

    /// Number of levels (root alone = 1, empty = 0).
    pub fn depth(&self) -> usize {
        let mut deepest = 0;
        walk(self.nodes, |_, level| deepest = deepest.max(level));
        deepest
    }
}

/// Depth-first walk calling `visit(node, level)` on every node reachable from the root, with a
/// fixed stack. Only for trees that passed [`check_structure`].
fn walk(nodes: &[BvhNode], mut visit: impl FnMut(usize, usize)) {
    if nodes.is_empty() {
        return;
    }
    let mut stack = [(0u32, 0u32); MAX_DEPTH];
    let mut sp = 0;
    let (mut node, mut level) = (0usize, 1usize);
    loop {
        visit(node, level);
        let n = &nodes[node];
        if !n.is_leaf() {
            stack[sp] = (n.first + 1, level as u32 + 1);
            sp += 1;
            node = n.first as usize;
            level += 1;
            continue;
        }
        if sp == 0 {
            return;
        }
        sp -= 1;
        node = stack[sp].0 as usize;
        level = stack[sp].1 as usize;
    }
}

/// The checks of [`Bvh::from_parts`]; `boxes` also checks every box.
pub(crate) fn check_structure(
    nodes: &[BvhNode],
    order: &[u32],
    boxes: bool,
) -> Result<(), BvhError> {
    if order.len() > MAX_PRIMITIVES as usize {
        return Err(BvhError::TooManyPrimitives);
    }
    if nodes.is_empty() {
        return if order.is_empty() {
            Ok(())
        } else {
            Err(BvhError::Malformed { index: 0 })
        };
    }
    if nodes.len() > u32::MAX as usize {
        return Err(BvhError::Malformed { index: u32::MAX });
    }
    for (i, n) in nodes.iter().enumerate() {
        let bad = BvhError::Malformed { index: i as u32 };
        if boxes && !n.aabb().is_finite_nonempty() {
            return Err(bad);
        }
        if n.is_leaf() {
            if n.first as u64 + n.count as u64 > order.len() as u64 {
                return Err(bad);
            }
        } else if n.first as usize <= i || n.first as u64 + 1 >= nodes.len() as u64 {
            return Err(bad);
        }
    }
    for (i, &id) in order.iter().enumerate() {
        if id as usize >= order.len() {
            return Err(BvhError::Malformed { index: i as u32 });
        }
    }
    // Children always lie after their parent, so the walk ends; it must not reach more nodes
    // than are stored (shared subtrees would make queries slower than the size suggests) nor
    // go deeper than the traversal stacks.
    let mut stack = [(0u32, 0u32); MAX_DEPTH];
    let mut sp = 0;
    let (mut node, mut level) = (0usize, 1usize);
    let mut visited = 0usize;
    loop {
        visited += 1;
        let n = &nodes[node];
        if visited > nodes.len() || (!n.is_leaf() && level >= MAX_DEPTH) {
            return Err(BvhError::Malformed { index: node as u32 });
        }
        if !n.is_leaf() {
            stack[sp] = (n.first + 1, level as u32 + 1);
            sp += 1;
            node = n.first as usize;
            level += 1;
            continue;
        }
        if sp == 0 {
            return Ok(());
        }
        sp -= 1;
        node = stack[sp].0 as usize;
        level = stack[sp].1 as usize;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn node_is_32_bytes_and_pod() {
        assert_eq!(core::mem::size_of::<BvhNode>(), 32);
        let n = BvhNode {
            min: [1.0, 2.0, 3.0],
            first: 7,
            max: [4.0, 5.0, 6.0],
            count: 2,
        };
        let bytes = bytemuck::bytes_of(&n);
        assert_eq!(&bytes[12..16], &7u32.to_le_bytes());
        assert_eq!(*bytemuck::from_bytes::<BvhNode>(bytes), n);
    }

    #[test]
    fn sizes() {
        assert_eq!(nodes_needed(0), 0);
        assert_eq!(nodes_needed(1), 1);
        assert_eq!(nodes_needed(1000), 1999);
        assert_eq!(nodes_needed(MAX_PRIMITIVES), (1usize << 31) - 1);
        assert_eq!(bytes_needed(10), 19 * 32 + 40);
        assert_eq!(bytes_needed(0), 0);
        // Saturates instead of overflowing.
        let _ = bytes_needed(u32::MAX);
    }

    fn leaf(first: u32, count: u32) -> BvhNode {
        BvhNode {
            min: [0.0; 3],
            first,
            max: [1.0; 3],
            count,
        }
    }

    fn inner(first: u32) -> BvhNode {
        BvhNode {
            min: [0.0; 3],
            first,
            max: [1.0; 3],
            count: 0,
        }
    }

    #[test]
    fn from_parts_checks() {
        let order = [1u32, 0];
        let good = [inner(1), leaf(0, 1), leaf(1, 1)];
        let bvh = Bvh::from_parts(&good, &order).unwrap();
        assert_eq!(bvh.depth(), 2);
        assert_eq!(bvh.len(), 2);
        assert!(Bvh::from_parts(&[], &[]).unwrap().is_empty());
        assert!(Bvh::from_parts(&[], &[0]).is_err());
        let malformed = |nodes: &[BvhNode], order: &[u32]| {
            matches!(
                Bvh::from_parts(nodes, order),
                Err(BvhError::Malformed { .. })
            )
        };
        // Child before its parent (a cycle) or out of range.
        assert!(malformed(&[inner(0), leaf(0, 1), leaf(1, 1)], &order));
        assert!(malformed(&[inner(2), leaf(0, 1), leaf(1, 1)], &order));
        // Leaf range outside the order array, order entry out of range.
        assert!(malformed(&[inner(1), leaf(0, 1), leaf(1, 2)], &order));
        assert!(malformed(&good, &[0, 2]));
        // A bad box.
        let mut nan = good;
        nan[2].max[1] = f32::NAN;
        assert!(malformed(&nan, &order));
        let mut inverted = good;
        inverted[1].min[0] = 2.0;
        assert!(malformed(&inverted, &order));
        // Shared subtrees: both inner nodes point at the same pair.
        let shared = [inner(1), inner(3), inner(3), leaf(0, 1), leaf(1, 1)];
        assert!(malformed(&shared, &order));
    }

    #[test]
    fn from_parts_refuses_deep_chains() {
        // A chain: node 2k is inner with children 2k+1 (leaf) and 2k+2.
        const LEVELS: usize = MAX_DEPTH + 1;
        let mut nodes = [leaf(0, 1); 2 * LEVELS - 1];
        for k in 0..LEVELS - 1 {
            nodes[2 * k] = inner(2 * k as u32 + 1);
        }
        let order = [0u32];
        assert!(Bvh::from_parts(&nodes, &order).is_err());
        // The same chain one level shorter is accepted.
        let mut shallow = [leaf(0, 1); 2 * MAX_DEPTH - 1];
        for k in 0..MAX_DEPTH - 1 {
            shallow[2 * k] = inner(2 * k as u32 + 1);
        }
        let bvh = Bvh::from_parts(&shallow, &order).unwrap();
        assert_eq!(bvh.depth(), MAX_DEPTH);
    }
}
