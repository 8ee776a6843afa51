//! Tests of the obvhs visibility: answers against brute force at several scales, candidates
//! of a box, coincident polygons.

use super::*;
use hirad_core::limits::NONE;
use hirad_core::sampling::hash3;

/// Deterministic numbers in [0, 1) for the random scenes.
struct Rng(u32, u32);

impl Rng {
    fn next(&mut self) -> f32 {
        self.1 += 1;
        (hash3(self.0, self.1, 0x5EED) >> 8) as f32 / 16_777_216.0
    }
    fn point(&mut self, size: f32) -> Vec3 {
        Vec3::new(self.next(), self.next(), self.next()) * size
    }
}

/// A random scene of `n` small triangles and parallelograms in the cube [0, size]^3.
fn scene(seed: u32, n: usize, size: f32) -> Vec<Vec<Vec3>> {
    let mut rng = Rng(seed, 0);
    (0..n)
        .map(|k| {
            let a = rng.point(size);
            let e1 = (rng.point(2.0) - 1.0) * size * 0.2;
            let e2 = (rng.point(2.0) - 1.0) * size * 0.2;
            if k % 2 == 0 {
                vec![a, a + e1, a + e2]
            } else {
                vec![a, a + e1, a + e1 + e2, a + e2]
            }
        })
        .collect()
}

/// Independent reference: the segment's crossing with each triangle's plane, then the
/// crossing point tested against the edges by signed volumes. `None` when the case is
/// too close to a boundary (t, or an edge) to compare two different formulations.
fn reference(polys: &[Vec<Vec3>], from: Vec3, to: Vec3, skip: [u32; 2]) -> Option<f32> {
    let (o, e) = (from.as_dvec3(), to.as_dvec3());
    let mut blocked = false;
    for (id, p) in polys.iter().enumerate() {
        if skip.contains(&(id as u32)) {
            continue;
        }
        let tris: &[[usize; 3]] = if p.len() == 4 {
            &[[0, 1, 2], [0, 2, 3]]
        } else {
            &[[0, 1, 2]]
        };
        for t in tris {
            let (a, b, c) = (p[t[0]].as_dvec3(), p[t[1]].as_dvec3(), p[t[2]].as_dvec3());
            let n = (b - a).cross(c - a);
            let (so, se) = (n.dot(o - a), n.dot(e - a));
            if so == se || (so > 0.0) == (se > 0.0) && so != 0.0 && se != 0.0 {
                continue;
            }
            let t = so / (so - se);
            let m = T_MARGIN as f64;
            if (t - m).abs() < 1e-4 || (t - (1.0 - m)).abs() < 1e-4 {
                return None;
            }
            if t <= m || t >= 1.0 - m {
                continue;
            }
            let x = o + (e - o) * t;
            let w = [
                (b - a).cross(x - a).dot(n),
                (c - b).cross(x - b).dot(n),
                (a - c).cross(x - c).dot(n),
            ];
            let scale = n.length_squared();
            if w.iter().any(|v| v.abs() < 1e-6 * scale) {
                return None;
            }
            if w.iter().all(|v| *v > 0.0) {
                blocked = true;
            }
        }
    }
    Some(if blocked { 0.0 } else { 1.0 })
}

fn compare(seed: u32, size: f32) -> (usize, usize) {
    let polys = scene(seed, 200, size);
    let vis = ObvhsVisibility::new(&polys).unwrap();
    let mut rng = Rng(seed ^ 0xABCD, 1_000_000);
    let (mut compared, mut blocked) = (0, 0);
    for k in 0..2000u32 {
        // Half the segments start and end on polygons (skipped), half are free.
        let (from, to, skip) = if k % 2 == 0 {
            let (i, j) = (k as usize % polys.len(), (k as usize * 7 + 3) % polys.len());
            let pi = &polys[i];
            let pj = &polys[j];
            let from = (pi[0] + pi[1] + pi[2]) / 3.0;
            let to = (pj[0] + pj[1] + pj[2]) / 3.0;
            (from, to, [i as u32, j as u32])
        } else {
            (rng.point(size), rng.point(size), [NONE, NONE])
        };
        let fast = vis.transmittance(from, to, skip);
        assert_eq!(fast, vis.brute_force(from, to, skip), "seed {seed} ray {k}");
        if let Some(r) = reference(&polys, from, to, skip) {
            assert_eq!(fast, r, "seed {seed} ray {k} size {size}");
            compared += 1;
            blocked += (fast == 0.0) as usize;
        }
    }
    (compared, blocked)
}

#[test]
fn agrees_with_brute_force_on_random_scenes_at_any_scale() {
    for seed in 0..4 {
        for size in [1.0, 1e-3, 1e3] {
            let (compared, blocked) = compare(seed, size);
            // Nearly every case is comparable, and both outcomes occur often.
            assert!(compared > 1900, "{compared}");
            assert!(blocked > 200 && blocked < compared - 200, "{blocked}");
        }
    }
}

#[test]
fn candidates_of_a_box_give_the_same_answers() {
    for (seed, size) in [(11, 1.0f32), (12, 1e-3), (13, 1e3)] {
        let polys = scene(seed, 300, size);
        let vis = ObvhsVisibility::new(&polys).unwrap();
        let mut rng = Rng(seed, 5_000_000);
        let mut out = Vec::new();
        let mut empty = 0;
        for k in 0..400u32 {
            let lo = rng.point(size);
            let hi = lo + rng.point(size * 0.05);
            let skip = [k % 300, NONE];
            vis.candidates(lo, hi, skip, &mut out);
            empty += out.is_empty() as usize;
            // Every polygon whose own box overlaps the query is a candidate.
            for (id, p) in polys.iter().enumerate() {
                let (mut a, mut b) = (p[0], p[0]);
                for v in p {
                    a = a.min(*v);
                    b = b.max(*v);
                }
                let overlaps = a.cmple(hi).all() && lo.cmple(b).all();
                if overlaps && !skip.contains(&(id as u32)) {
                    assert!(out.binary_search(&(id as u32)).is_ok(), "{id}");
                }
            }
            // Segments inside the box: the candidates decide exactly as the BVH does.
            for _ in 0..20 {
                let t = |r: &mut Rng| lo + (hi - lo) * Vec3::new(r.next(), r.next(), r.next());
                let (a, b) = (t(&mut rng), t(&mut rng));
                assert_eq!(
                    vis.transmittance_among(a, b, &out),
                    vis.transmittance(a, b, skip)
                );
            }
        }
        assert!(empty > 20 && empty < 380, "{empty}");
    }
}

#[test]
fn same_answer_in_millimetres_and_kilometres() {
    let polys = scene(9, 100, 1.0);
    let scaled = |s: f32| -> Vec<Vec<Vec3>> {
        polys
            .iter()
            .map(|p| p.iter().map(|v| *v * s).collect())
            .collect()
    };
    let (small, big) = (scaled(1.0 / 1024.0), scaled(1024.0));
    let (vs, vb) = (
        ObvhsVisibility::new(&small).unwrap(),
        ObvhsVisibility::new(&big).unwrap(),
    );
    let v1 = ObvhsVisibility::new(&polys).unwrap();
    let mut rng = Rng(77, 0);
    for _ in 0..2000 {
        let (a, b) = (rng.point(1.0), rng.point(1.0));
        let r = v1.transmittance(a, b, [NONE, NONE]);
        // Powers of two scale exactly, so the answers are identical.
        assert_eq!(vs.transmittance(a / 1024.0, b / 1024.0, [NONE, NONE]), r);
        assert_eq!(vb.transmittance(a * 1024.0, b * 1024.0, [NONE, NONE]), r);
    }
}

#[test]
fn margins_are_relative_to_the_segment() {
    // A unit square in z = 0, and segments crossing it at chosen parameters.
    let sq = vec![vec![
        Vec3::new(-1., -1., 0.),
        Vec3::new(1., -1., 0.),
        Vec3::new(1., 1., 0.),
        Vec3::new(-1., 1., 0.),
    ]];
    let v = ObvhsVisibility::new(&sq).unwrap();
    let none = [NONE, NONE];
    for len in [1e-3f32, 1.0, 1e3] {
        let seg = |t_cross: f32| {
            let from = Vec3::new(0.1, 0.2, -t_cross * len);
            (from, from + Vec3::new(0.0, 0.0, len))
        };
        for (t, expect) in [
            (0.5, 0.0),
            (1.1e-5, 0.0),
            (1.0 - 1.1e-5, 0.0),
            (5e-6, 1.0),
            (1.0 - 5e-6, 1.0),
        ] {
            let (a, b) = seg(t);
            assert_eq!(v.transmittance(a, b, none), expect, "t {t} len {len}");
        }
    }
    // The skipped polygon never blocks; a segment beside the square is clear.
    let (a, b) = (Vec3::new(0., 0., -1.), Vec3::new(0., 0., 1.));
    assert_eq!(v.transmittance(a, b, [0, NONE]), 1.0);
    assert_eq!(v.transmittance(a, b, [NONE, 0]), 1.0);
    assert_eq!(v.transmittance(a, b, none), 0.0);
    let (a, b) = (Vec3::new(1.5, 0., -1.), Vec3::new(1.5, 0., 1.));
    assert_eq!(v.transmittance(a, b, none), 1.0);
    // Through the quad's diagonal (where its two triangles meet): blocked.
    let (a, b) = (Vec3::new(0.3, 0.3, -1.), Vec3::new(0.3, 0.3, 1.));
    assert_eq!(v.transmittance(a, b, none), 0.0);
    // In the plane of the square: never blocked.
    let (a, b) = (Vec3::new(-2., 0., 0.), Vec3::new(2., 0., 0.));
    assert_eq!(v.transmittance(a, b, none), 1.0);
}

#[test]
fn empty_one_polygon_and_bad_input() {
    let empty: Vec<Vec<Vec3>> = Vec::new();
    let v = ObvhsVisibility::new(&empty).unwrap();
    assert!(v.is_empty());
    assert_eq!(v.transmittance(Vec3::ZERO, Vec3::ONE, [NONE, NONE]), 1.0);
    let tri = vec![vec![
        Vec3::new(0., 0., 1.),
        Vec3::new(1., 0., 1.),
        Vec3::new(0., 1., 1.),
    ]];
    let v = ObvhsVisibility::new(&tri).unwrap();
    assert_eq!(v.len(), 1);
    let p = Vec3::new(0.2, 0.2, 0.0);
    assert_eq!(v.transmittance(p, p + Vec3::Z * 2.0, [NONE, NONE]), 0.0);
    assert_eq!(v.transmittance(p, p, [NONE, NONE]), 1.0);
    let nan = Vec3::splat(f32::NAN);
    assert_eq!(v.transmittance(nan, p, [NONE, NONE]), 1.0);
    let bad = vec![vec![Vec3::ZERO, Vec3::X]];
    assert_eq!(
        ObvhsVisibility::new(&bad).unwrap_err(),
        VisibilityError::Corners {
            polygon: 0,
            count: 2
        }
    );
    let bad = vec![vec![Vec3::ZERO, Vec3::X, nan]];
    assert_eq!(
        ObvhsVisibility::new(&bad).unwrap_err(),
        VisibilityError::NonFinite { polygon: 0 }
    );
}

#[test]
fn shared_across_threads() {
    fn is_sync<T: Sync + Send>() {}
    is_sync::<ObvhsVisibility>();
}

#[test]
fn thousands_of_coincident_polygons_are_all_found() {
    // 3000 copies of one small triangle and a few others: the tree is built over distinct
    // boxes, so it stays shallow, and every query agrees with testing each polygon.
    let tri = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1e-6, 0.0, 0.0),
        Vec3::new(0.0, 1e-6, 0.0),
    ];
    let mut polys = vec![tri.clone(); 3000];
    polys.push(vec![
        Vec3::new(-1.0, -1.0, 0.5),
        Vec3::new(1.0, -1.0, 0.5),
        Vec3::new(0.0, 1.0, 0.5),
    ]);
    let vis = ObvhsVisibility::new(&polys).unwrap();
    let x = Vec3::new(2e-7, 2e-7, -1.0);
    let up = Vec3::new(2e-7, 2e-7, 1.0);
    // Through the stack from below: blocked, first by a copy (lowest id), then the cover.
    assert_eq!(vis.transmittance(x, up, [NONE, NONE]), 0.0);
    let hit = vis.first_hit(x, up, [NONE, NONE]).unwrap();
    assert_eq!(hit, vis.first_hit_brute_force(x, up, [NONE, NONE]).unwrap());
    assert_eq!(hit.0, 0);
    // From a copy upwards: the cover.
    let from = Vec3::new(2e-7, 2e-7, 0.0);
    let hit = vis.first_hit(from, up, [5, NONE]).unwrap();
    assert_eq!(hit.0, 3000);
    let mut candidates = Vec::new();
    vis.candidates(
        Vec3::splat(-1e-7),
        Vec3::splat(2e-6),
        [NONE, NONE],
        &mut candidates,
    );
    assert_eq!(candidates.len(), 3000);
}

#[test]
fn a_stack_of_coincident_polygons_blocks_through_it_and_not_from_it() {
    // 1,000 identical triangles (one group of the BVH) and a quad above them: a segment
    // through the stack is blocked by its lowest id; one that starts on the stack is not
    // blocked by the stack (its crossings lie within the end margin), only by the quad.
    let tri = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1e-6, 0.0, 0.0),
        Vec3::new(0.0, 1e-6, 0.0),
    ];
    let mut polys: Vec<Vec<Vec3>> = (0..1000).map(|_| tri.clone()).collect();
    polys.push(vec![
        Vec3::new(-1.0, -1.0, 1.0),
        Vec3::new(1.0, -1.0, 1.0),
        Vec3::new(1.0, 1.0, 1.0),
        Vec3::new(-1.0, 1.0, 1.0),
    ]);
    let v = ObvhsVisibility::new(&polys).unwrap();
    let x = Vec3::new(2e-7, 2e-7, 0.0);
    let below = Vec3::new(2e-7, 2e-7, -0.5);
    assert_eq!(v.transmittance(below, x + Vec3::Z * 0.5, [NONE, NONE]), 0.0);
    assert_eq!(
        v.first_hit(below, x + Vec3::Z * 0.5, [NONE, NONE])
            .map(|h| h.0),
        Some(0)
    );
    assert_eq!(v.transmittance(x, x + Vec3::Z * 0.5, [3, NONE]), 1.0);
    assert_eq!(
        v.first_hit(x, x + Vec3::Z * 2.0, [3, NONE]).map(|h| h.0),
        Some(1000)
    );
    // The brute-force answers agree.
    assert_eq!(v.brute_force(x, x + Vec3::Z * 0.5, [3, NONE]), 1.0);
    assert_eq!(v.brute_force(below, x + Vec3::Z * 0.5, [NONE, NONE]), 0.0);
}

/// Unit directions over zenith angles 0 to 85 degrees and all azimuths, with the axes
/// themselves and a direction just off the vertical.
fn sweep_directions() -> Vec<Vec3> {
    let mut dirs = vec![
        Vec3::Z,
        Vec3::X,
        -Vec3::Y,
        Vec3::new(1e-4, 0.0, 1.0).normalize(),
    ];
    for zenith in [0.0f32, 10.0, 30.0, 45.0, 60.0, 70.0, 85.0] {
        for azimuth in [0.0f32, 37.0, 90.0, 200.0, 315.0] {
            let (z, a) = (zenith.to_radians(), azimuth.to_radians());
            dirs.push(Vec3::new(z.sin() * a.cos(), z.sin() * a.sin(), z.cos()).normalize());
        }
    }
    dirs
}

#[test]
fn rays_along_a_source_direction_get_the_bvh_answers() {
    for (seed, size) in [(21, 1.0f32), (22, 1e-3), (23, 1e3), (24, 40.0)] {
        let polys = scene(seed, 400, size);
        let dirs = sweep_directions();
        let plain = ObvhsVisibility::new(&polys).unwrap();
        let vis = ObvhsVisibility::new(&polys)
            .unwrap()
            .with_directions(&polys, &dirs);
        assert!(vis.directional_bytes() > 0);
        let mut rng = Rng(seed ^ 0x51, 7);
        let (mut blocked, mut total, mut compared) = (0, 0, 0);
        for (k, &d) in dirs.iter().enumerate() {
            for j in 0..240u32 {
                let p = &polys[(j as usize * 13 + k) % polys.len()];
                let id = ((j as usize * 13 + k) % polys.len()) as u32;
                let (from, skip) = match j % 4 {
                    // On a polygon, skipping it (as the solver casts).
                    0 => ((p[0] + p[1] + p[2]) / 3.0, [id, NONE]),
                    // Straight below a corner along the ray: it grazes the corner, on the
                    // edge of the polygon's projected box.
                    1 => (p[1] - d * size * 0.3, [NONE, NONE]),
                    // Anywhere, also outside the scene's projection.
                    2 => ((rng.point(3.0) - 1.0) * size, [NONE, NONE]),
                    _ => (rng.point(size), [NONE, NONE]),
                };
                let to = from + d * size * 4.0;
                let fast = vis.transmittance_towards(from, to, d, skip);
                assert_eq!(fast, plain.transmittance(from, to, skip), "{seed} {k} {j}");
                assert_eq!(fast, vis.brute_force(from, to, skip), "{seed} {k} {j}");
                // And the independent formulation, where the case is not at a boundary.
                if let Some(r) = reference(&polys, from, to, skip) {
                    assert_eq!(fast, r, "{seed} {k} {j} reference");
                    compared += 1;
                }
                // A segment that does not run along the direction it names is cast.
                let bent = to + Vec3::new(0.3, -0.2, 0.1) * size;
                assert_eq!(
                    vis.transmittance_towards(from, bent, d, skip),
                    vis.brute_force(from, bent, skip),
                    "{seed} {k} {j} bent"
                );
                blocked += (fast == 0.0) as usize;
                total += 1;
            }
        }
        // Both outcomes occur often; most cases are away from boundaries.
        assert!(
            blocked > total / 10 && blocked < total * 9 / 10,
            "{blocked} of {total}"
        );
        assert!(compared > total / 2, "{compared} of {total}");
    }
}

#[test]
fn directional_grids_stay_within_their_memory() {
    // Large overlapping squares, each covering the whole projection: the grid coarsens
    // rather than list every square in every cell; a thousand suns stop at the budget.
    let n = 3000;
    let polys: Vec<Vec<Vec3>> = (0..n)
        .map(|k| {
            let z = k as f32 * 0.01;
            let o = (k % 7) as f32 * 0.01;
            vec![
                Vec3::new(o, 0.0, z),
                Vec3::new(10.0 + o, 0.0, z),
                Vec3::new(10.0 + o, 10.0, z),
                Vec3::new(o, 10.0, z),
            ]
        })
        .collect();
    let suns: Vec<Vec3> = (0..1000)
        .map(|k| Vec3::new((k as f32 * 0.001).sin() * 0.3, 0.1, 1.0).normalize())
        .collect();
    let vis = ObvhsVisibility::new(&polys)
        .unwrap()
        .with_directions(&polys, &suns);
    let budget = (DIRECTIONAL_BYTES_PER_POLYGON * n).max(16 << 20);
    // Other polygons than the caster's: no grid, the BVH answers.
    let other = ObvhsVisibility::new(&polys)
        .unwrap()
        .with_directions(&polys[..10], &suns);
    assert_eq!(other.directional_bytes(), 0);
    assert!(vis.directional_bytes() > 0 && vis.directional_bytes() <= budget);
    // Under the stack: blocked; above it: clear; in between, blocked by what lies above.
    for (z, expect) in [(-1.0f32, 0.0f32), (40.0, 1.0), (15.0, 0.0)] {
        let from = Vec3::new(5.0, 5.0, z);
        let d = suns[0];
        assert_eq!(
            vis.transmittance_towards(from, from + d * 100.0, d, [NONE, NONE]),
            expect
        );
    }
}
