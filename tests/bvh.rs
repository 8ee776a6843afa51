//! The core's BVH on arbitrary input: building never panics on any finite boxes, refuses
//! too-small storage and bad boxes with an error, always fits in `nodes_needed(n)` nodes, and
//! `BvhVisibility` gives exactly the answer of testing every polygon.

use glam::Vec3;
use hirad_core::bvh::{
    Bvh, BvhError, BvhNode, BvhVisibility, MAX_DEPTH, MAX_LEAF, SEGMENT_MARGIN, SlicePolygons,
    build, nodes_needed, segment_polygon,
};
use hirad_core::geometry::Aabb;
use hirad_core::limits::NONE;
use hirad_core::visibility::Visibility;
use proptest::prelude::*;

/// Any finite f32 of any magnitude, with zeros, subnormals and the extremes likely.
fn finite() -> impl Strategy<Value = f32> + Clone {
    prop_oneof![
        4 => -1e3f32..1e3,
        2 => proptest::num::f32::NORMAL | proptest::num::f32::SUBNORMAL | proptest::num::f32::ZERO,
        1 => Just(f32::MAX),
        1 => Just(-f32::MAX),
        1 => (-4i8..4).prop_map(f32::from),
    ]
}

fn vec3(s: impl Strategy<Value = f32> + Clone) -> impl Strategy<Value = Vec3> {
    (s.clone(), s.clone(), s).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

/// A box from two arbitrary finite corners.
fn any_box() -> impl Strategy<Value = Aabb> {
    (vec3(finite()), vec3(finite())).prop_map(|(a, b)| Aabb::new(a.min(b), a.max(b)))
}

/// Checks every invariant of a built tree over `boxes`.
fn check_tree(bvh: &Bvh, boxes: &[Aabb]) -> Result<(), TestCaseError> {
    prop_assert!(Bvh::from_parts(bvh.nodes(), bvh.order()).is_ok());
    prop_assert!(bvh.nodes().len() <= nodes_needed(boxes.len() as u32));
    prop_assert!(bvh.depth() <= MAX_DEPTH);
    let mut seen = vec![false; boxes.len()];
    for node in bvh.nodes() {
        if node.is_leaf() {
            prop_assert!(node.count <= MAX_LEAF);
            let mut tight = Aabb::EMPTY;
            for &id in &bvh.order()[node.first as usize..(node.first + node.count) as usize] {
                prop_assert!(!seen[id as usize], "primitive {} twice", id);
                seen[id as usize] = true;
                tight = tight.union(boxes[id as usize]);
            }
            prop_assert_eq!(tight, node.aabb());
        } else {
            let l = &bvh.nodes()[node.first as usize];
            let r = &bvh.nodes()[node.first as usize + 1];
            prop_assert_eq!(l.aabb().union(r.aabb()), node.aabb());
        }
    }
    prop_assert!(seen.iter().all(|&s| s));
    Ok(())
}

/// A polygon from arbitrary parameters: a triangle of three arbitrary corners (possibly
/// degenerate), or a planar convex quad (cyclic points on a circle, affinely stretched).
#[derive(Clone, Debug)]
enum PolySpec {
    Triangle([Vec3; 3]),
    Quad {
        centre: Vec3,
        u: Vec3,
        v: Vec3,
        angles: [f32; 4],
    },
}

impl PolySpec {
    fn corners(&self, scale: f32) -> ([Vec3; 4], u8) {
        match self {
            PolySpec::Triangle(t) => ([t[0] * scale, t[1] * scale, t[2] * scale, Vec3::ZERO], 3),
            PolySpec::Quad {
                centre,
                u,
                v,
                angles,
            } => {
                let mut c = [Vec3::ZERO; 4];
                for (j, p) in c.iter_mut().enumerate() {
                    let a = std::f32::consts::FRAC_PI_2 * (j as f32 + angles[j]);
                    *p = (*centre + *u * a.cos() + *v * a.sin()) * scale;
                }
                (c, 4)
            }
        }
    }
}

fn coord() -> impl Strategy<Value = f32> + Clone {
    prop_oneof![3 => -1.0f32..1.0, 1 => (-4i8..=4).prop_map(|i| f32::from(i) * 0.25)]
}

fn poly() -> impl Strategy<Value = PolySpec> {
    prop_oneof![
        [vec3(coord()), vec3(coord()), vec3(coord())].prop_map(PolySpec::Triangle),
        (
            vec3(coord()),
            vec3(-1.0f32..1.0),
            vec3(-1.0f32..1.0),
            0.1f32..0.5,
            0.1f32..0.5,
            [0.0f32..0.8, 0.0f32..0.8, 0.0f32..0.8, 0.0f32..0.8],
        )
            .prop_filter_map("normal too short", |(centre, a, b, su, sv, angles)| {
                let n = a.cross(b).try_normalize()?;
                let u = n.any_orthonormal_vector();
                let v = n.cross(u);
                Some(PolySpec::Quad {
                    centre,
                    u: u * su,
                    v: v * sv,
                    angles,
                })
            }),
    ]
}

#[derive(Clone, Debug)]
struct Seg {
    from: Vec3,
    to: Vec3,
    skip: [u32; 2],
}

fn segment(polys: usize) -> impl Strategy<Value = Seg> {
    let skip = prop_oneof![
        2 => Just(NONE),
        1 => 0..polys as u32,
    ];
    (
        vec3(coord()),
        vec3(coord()),
        0usize..4,
        [skip.clone(), skip],
    )
        .prop_map(|(from, mut to, axis, skip)| {
            // A quarter of the segments are axis-parallel.
            if axis < 3 {
                for k in 0..3 {
                    if k != axis {
                        to[k] = from[k];
                    }
                }
            }
            Seg { from, to, skip }
        })
}

fn brute(polys: &[([Vec3; 4], u8)], from: Vec3, to: Vec3, skip: [u32; 2]) -> f32 {
    for (i, (c, k)) in polys.iter().enumerate() {
        if skip.contains(&(i as u32)) {
            continue;
        }
        let t = segment_polygon(from, to - from, &c[..*k as usize]);
        if t.is_some_and(|t| t > SEGMENT_MARGIN && t < 1.0 - SEGMENT_MARGIN) {
            return 0.0;
        }
    }
    1.0
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    /// Any finite boxes build into a valid tree; storage below `nodes_needed(n)` nodes or `n`
    /// order entries is refused, more is fine.
    #[test]
    fn build_never_panics_and_storage_is_exact(
        boxes in proptest::collection::vec(any_box(), 0..300),
        spare in 0usize..3,
        short_nodes in any::<bool>(),
        short_order in any::<bool>(),
    ) {
        let n = boxes.len() as u32;
        let need = nodes_needed(n);
        let mut nodes = vec![BvhNode::default(); need + spare];
        let mut order = vec![0u32; n as usize + spare];
        let node_len = if short_nodes && need > 0 { need - 1 } else { need + spare };
        let order_len = if short_order && n > 0 { n as usize - 1 } else { n as usize + spare };
        let r = build(n, |i| boxes[i as usize], &mut nodes[..node_len], &mut order[..order_len]);
        if (short_nodes && need > 0) || (short_order && n > 0) {
            prop_assert_eq!(r.unwrap_err(), BvhError::StorageTooSmall { nodes: need, order: n as usize });
        } else {
            let bvh = r.unwrap();
            check_tree(&bvh, &boxes)?;
        }
    }

    /// Degenerate distributions: many copies of few boxes (equal centroids), points.
    #[test]
    fn build_handles_repeated_boxes(
        few in proptest::collection::vec(any_box(), 1..4),
        n in 1usize..400,
    ) {
        let boxes: Vec<Aabb> = (0..n).map(|i| few[i % few.len()]).collect();
        let mut nodes = vec![BvhNode::default(); nodes_needed(n as u32)];
        let mut order = vec![0u32; n];
        let bvh = build(n as u32, |i| boxes[i as usize], &mut nodes, &mut order).unwrap();
        check_tree(&bvh, &boxes)?;
    }

    /// A non-finite or inverted box is refused, naming the first such primitive.
    #[test]
    fn build_refuses_bad_boxes(
        boxes in proptest::collection::vec(any_box(), 1..100),
        at in any::<prop::sample::Index>(),
        kind in 0..4,
    ) {
        let bad_at = at.index(boxes.len());
        let bad = match kind {
            0 => Aabb::new(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::ONE),
            1 => Aabb::new(Vec3::ZERO, Vec3::new(0.0, 0.0, f32::INFINITY)),
            2 => Aabb::new(Vec3::ONE, Vec3::ZERO),
            _ => Aabb::EMPTY,
        };
        let n = boxes.len() as u32;
        let mut nodes = vec![BvhNode::default(); nodes_needed(n)];
        let mut order = vec![0u32; n as usize];
        let r = build(n, |i| if i as usize == bad_at { bad } else { boxes[i as usize] }, &mut nodes, &mut order);
        prop_assert_eq!(r.unwrap_err(), BvhError::InvalidBounds { primitive: bad_at as u32 });
    }

    /// The BVH answers exactly like testing every polygon, at three scales.
    #[test]
    fn visibility_matches_brute_force(
        (specs, segs) in proptest::collection::vec(poly(), 1..60)
            .prop_flat_map(|p| { let n = p.len(); (Just(p), proptest::collection::vec(segment(n), 1..40)) }),
        scale in prop_oneof![Just(1.0f32), Just(1e-3), Just(1e3)],
    ) {
        let polys: Vec<([Vec3; 4], u8)> = specs.iter().map(|s| s.corners(scale)).collect();
        let corners: Vec<[Vec3; 4]> = polys.iter().map(|p| p.0).collect();
        let counts: Vec<u8> = polys.iter().map(|p| p.1).collect();
        let n = polys.len() as u32;
        let mut nodes = vec![BvhNode::default(); nodes_needed(n)];
        let mut order = vec![0u32; n as usize];
        let vis = BvhVisibility::build(SlicePolygons::new(&corners, &counts), &mut nodes, &mut order)
            .unwrap();
        for s in &segs {
            let (from, to) = (s.from * scale, s.to * scale);
            let want = brute(&polys, from, to, s.skip);
            prop_assert_eq!(vis.transmittance(from, to, s.skip), want, "{:?}", s);
            prop_assert_eq!(vis.first_hit(from, to, s.skip).is_some(), want == 0.0);
        }
    }
}
