//! The core's own BVH: build time and occlusion queries per second over random triangle soups
//! of 10k and 1M triangles in the unit cube. `cargo bench --bench bvh`.
//!
//! Triangles have edges of about `0.5 n^(-1/3)`, so the soup looks alike at both sizes.
//! Queries: 4096 segments between random points of the cube ("long": 25% blocked at 10k
//! triangles, 69% at 1M; a blocked query stops at the first hit) and 4096 segments spanning at
//! most 0.05 per axis ("short": 2% and 9% blocked, mostly a full search of the path). Trees are
//! 17 and 24 levels deep. Storage is allocated once outside the timed region, as a caller of
//! the no-alloc core would.

use divan::{Bencher, counter::ItemsCount};
use glam::Vec3;
use hirad_core::bvh::{BvhNode, BvhVisibility, SlicePolygons, build, nodes_needed};
use hirad_core::geometry::Aabb;
use hirad_core::limits::NONE;
use hirad_core::sampling::{hash3, unit2};
use hirad_core::visibility::Visibility;

fn main() {
    divan::main();
}

const SIZES: [u32; 2] = [10_000, 1_000_000];
const QUERIES: u32 = 4096;

fn rnd3(a: u32, b: u32) -> Vec3 {
    let (x, y) = unit2(hash3(a, b, 1));
    let (z, _) = unit2(hash3(a, b, 2));
    Vec3::new(x, y, z)
}

/// `n` random triangles in the unit cube (corner slot 3 unused).
fn soup(n: u32) -> (Vec<[Vec3; 4]>, Vec<u8>) {
    let edge = 0.5 / (n as f32).cbrt();
    let corners = (0..n)
        .map(|i| {
            let c = rnd3(i, 1);
            let a = c + (rnd3(i, 2) - 0.5) * edge;
            let b = c + (rnd3(i, 3) - 0.5) * edge;
            let d = c + (rnd3(i, 4) - 0.5) * edge;
            [a, b, d, Vec3::ZERO]
        })
        .collect();
    (corners, vec![3; n as usize])
}

fn segments(short: bool) -> Vec<(Vec3, Vec3)> {
    (0..QUERIES)
        .map(|q| {
            let from = rnd3(q, 100);
            let to = if short {
                from + (rnd3(q, 101) - 0.5) * 0.1
            } else {
                rnd3(q, 101)
            };
            (from, to)
        })
        .collect()
}

/// Building from the polygons (bounds computed from corners on every call), as
/// `BvhVisibility::build` does.
#[divan::bench(args = SIZES, sample_count = 5, sample_size = 1)]
fn build_from_polygons(bencher: Bencher, n: u32) {
    let (corners, counts) = soup(n);
    let mut nodes = vec![BvhNode::default(); nodes_needed(n)];
    let mut order = vec![0u32; n as usize];
    bencher.counter(ItemsCount::new(n)).bench_local(|| {
        let set = SlicePolygons::new(&corners, &counts);
        BvhVisibility::build(set, &mut nodes, &mut order)
            .unwrap()
            .bvh()
            .nodes()
            .len()
    });
}

/// Building from precomputed boxes (the cost of the `bounds` callback removed).
#[divan::bench(args = SIZES, sample_count = 5, sample_size = 1)]
fn build_from_boxes(bencher: Bencher, n: u32) {
    let (corners, _) = soup(n);
    let boxes: Vec<Aabb> = corners
        .iter()
        .map(|c| Aabb::new(c[0].min(c[1]).min(c[2]), c[0].max(c[1]).max(c[2])))
        .collect();
    let mut nodes = vec![BvhNode::default(); nodes_needed(n)];
    let mut order = vec![0u32; n as usize];
    bencher.counter(ItemsCount::new(n)).bench_local(|| {
        build(n, |i| boxes[i as usize], &mut nodes, &mut order)
            .unwrap()
            .nodes()
            .len()
    });
}

fn queries(bencher: Bencher, n: u32, short: bool) {
    let (corners, counts) = soup(n);
    let mut nodes = vec![BvhNode::default(); nodes_needed(n)];
    let mut order = vec![0u32; n as usize];
    let vis = BvhVisibility::build(
        SlicePolygons::new(&corners, &counts),
        &mut nodes,
        &mut order,
    )
    .unwrap();
    let segs = segments(short);
    bencher
        .counter(ItemsCount::new(segs.len()))
        .bench_local(|| {
            let mut open = 0.0f32;
            for &(a, b) in &segs {
                open += vis.transmittance(divan::black_box(a), b, [NONE; 2]);
            }
            open
        });
}

/// Occlusion queries between random points of the cube.
#[divan::bench(args = SIZES, sample_count = 20)]
fn occlusion_long(bencher: Bencher, n: u32) {
    queries(bencher, n, false);
}

/// Occlusion queries over short segments (mostly unblocked: full traversal).
#[divan::bench(args = SIZES, sample_count = 20)]
fn occlusion_short(bencher: Bencher, n: u32) {
    queries(bencher, n, true);
}
