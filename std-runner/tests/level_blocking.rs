//! How a level's closed instances block rays (issue 18): by their tables' transmittance along
//! the chord they cross, the sun through the others, and with polygons, their original's or
//! an approximate instance's own, against exact chords and segment-triangle tests.

mod level_scene;

use glam::Vec3;
use hirad::generate::shapes::add_quad;
use hirad::scene::{Cluster, InstanceOf, Similarity, compile};
use hirad_core::hr::level_probe::load_level;
use hirad_core::hr::{Instancing, Settings, census_scratch_bytes};
use hirad_core::image::{SceneView, SliceSource};
use hirad_core::tables::directional::DirectionalTables;
use level_scene::{place, scene};

/// Of the chord of `place`'s box `lo..hi` along the line through `a` and `b`, the share the
/// segment `a..b` runs through (points along the line, from 2 segment lengths before `a` to
/// 2 after `b`), or `None` when the segment misses the box.
fn chord_share(place: &Similarity, lo: Vec3, hi: Vec3, a: Vec3, b: Vec3) -> Option<f32> {
    let steps = 100_000;
    let (mut on_line, mut on_segment) = (0u32, 0u32);
    for j in 0..=steps {
        let s = -2.0 + 5.0 * j as f32 / steps as f32;
        if inside(place, lo, hi, a + (b - a) * s) {
            on_line += 1;
            if (0.0..=1.0).contains(&s) {
                on_segment += 1;
            }
        }
    }
    (on_segment > 0).then(|| on_segment as f32 / on_line as f32)
}

/// A point of `place`'s original box `lo..hi`, or not (the inverse transform, in f64).
fn inside(place: &Similarity, lo: Vec3, hi: Vec3, w: Vec3) -> bool {
    let local = place.rotation.conjugate() * (w - place.translation) / place.scale;
    (0..3).all(|k| local[k] >= lo[k] && local[k] <= hi[k])
}

#[test]
fn closed_instances_block_by_tau_along_what_they_cross() {
    let (s, places) = scene(12);
    let bytes = compile(&s).unwrap();
    let view = SceneView::open(SliceSource(&bytes[..])).unwrap();
    let image_tables: Vec<_> = s
        .tables
        .iter()
        .map(|t| DirectionalTables::from_record(&t.record, &t.values, &t.visible).unwrap())
        .collect();
    let mut ws = vec![0u8; 64 << 20];
    // Every closed instance as a medium (its tau), not with its own polygons.
    let settings = Settings {
        blocking_polygons: 0,
        ..Settings::default()
    };
    load_level(&view, &settings, Instancing::Top, &mut ws, |level| {
        // Instances by node: the scene's order, as `places`.
        let mut by_node: Vec<u32> = (0..level.instances()).collect();
        by_node.sort_by_key(|&i| level.instance(i).node);
        let original = |k: usize| if (12..14).contains(&k) { 1 } else { 0 };
        // The reference: points along the segment tell which boxes it enters.
        let reference = |a: Vec3, b: Vec3, skip: Option<usize>| -> (f32, usize) {
            let d = (b - a).normalize();
            let (mut t, mut crossed) = (1.0f32, 0);
            for (k, p) in places.iter().enumerate() {
                if Some(k) == skip {
                    continue;
                }
                let tables = &image_tables[original(k)];
                let (lo, hi) = tables.bounds();
                if let Some(share) = chord_share(p, lo, hi, a, b) {
                    let tau = tables.tau(p.rotation.conjugate() * d);
                    t *= if share >= 1.0 { tau } else { tau.powf(share) };
                    crossed += 1;
                }
            }
            (t, crossed)
        };
        let mut crossings = 0;
        for k in 0..200u32 {
            let h = |j: u32| ((k * 7919 + j * 104_729) % 1000) as f32 / 1000.0;
            let a = Vec3::new(-6.0 + 12.0 * h(1), -6.0 + 12.0 * h(2), 0.1 + 1.5 * h(3));
            let b = Vec3::new(-6.0 + 12.0 * h(4), -6.0 + 12.0 * h(5), 0.1 + 1.5 * h(6));
            let (want, crossed) = reference(a, b, None);
            crossings += crossed;
            let got = level.transmittance(a, b, None);
            // Partial crossings' shares are sampled in the reference.
            assert!(
                (got - want).abs() < 1e-5 + 0.01 * want,
                "segment {k}: {got} vs {want} ({crossed} boxes)"
            );
        }
        assert!(crossings > 20, "the segments must cross boxes: {crossings}");
        // From inside an instance with it skipped: the others only.
        for (k, p) in places.iter().enumerate() {
            let (lo, hi) = image_tables[original(k)].bounds();
            let a = p.point((lo + hi) * 0.5);
            let b = a + Vec3::new(3.0, -1.0, 0.5);
            let (want, _) = reference(a, b, Some(k));
            let got = level.transmittance(a, b, Some(by_node[k]));
            assert!(
                (got - want).abs() < 1e-5 + 0.01 * want,
                "from inside {k}: {got} vs {want}"
            );
            let (with_self, _) = reference(a, b, None);
            let got = level.transmittance(a, b, None);
            assert!(
                (got - with_self).abs() < 1e-5 + 0.01 * with_self,
                "from inside {k}, not skipped"
            );
        }
    })
    .unwrap();
}

/// True when the segment `a..b` meets `place`'s box `lo..hi` (slabs in the local frame).
fn meets(place: &Similarity, lo: Vec3, hi: Vec3, a: Vec3, b: Vec3) -> bool {
    let to_local = |w: Vec3| place.rotation.conjugate() * (w - place.translation) / place.scale;
    let (p, q) = (to_local(a), to_local(b));
    let (mut enter, mut leave) = (0.0f32, 1.0f32);
    for k in 0..3 {
        let d = q[k] - p[k];
        if d.abs() < 1e-12 {
            if p[k] < lo[k] || p[k] > hi[k] {
                return false;
            }
            continue;
        }
        let (t0, t1) = ((lo[k] - p[k]) / d, (hi[k] - p[k]) / d);
        enter = enter.max(t0.min(t1));
        leave = leave.min(t0.max(t1));
    }
    enter <= leave
}

#[test]
fn closed_instances_see_the_sun_through_the_others() {
    use hirad_core::tables::closed::Received;
    let (mut s, places) = scene(12);
    // A sun low enough for the shrubs to shade part of the row.
    let sun = Vec3::new(-0.5, 0.9, 0.6).normalize();
    s.suns[0].towards = sun;
    let bytes = compile(&s).unwrap();
    let view = SceneView::open(SliceSource(&bytes[..])).unwrap();
    let image_tables: Vec<_> = s
        .tables
        .iter()
        .map(|t| DirectionalTables::from_record(&t.record, &t.values, &t.visible).unwrap())
        .collect();
    let original = |k: usize| if (12..14).contains(&k) { 1 } else { 0 };
    // The others as media (their tau), not with their own polygons.
    let settings = Settings {
        rays: 64,
        blocking_polygons: 0,
        ..Settings::default()
    };
    let mut ws = vec![0u8; 64 << 20];
    let mut shaded = 0;
    load_level(&view, &settings, Instancing::Top, &mut ws, |level| {
        let mut by_node: Vec<u32> = (0..level.instances()).collect();
        by_node.sort_by_key(|&i| level.instance(i).node);
        for (k, p) in places.iter().enumerate() {
            let c = level.instance(by_node[k]);
            let r = Received::over(&c.placed, c.received).unwrap();
            // Reference: 4096 points of its box, each ray's product of the others' tau.
            let (lo, hi) = image_tables[original(k)].bounds();
            let m = 4096u32;
            let mut sum = 0.0f64;
            for j in 0..m {
                let u = |s: u32| {
                    ((j.wrapping_mul(2654435761).wrapping_add(s * 40503)) % 9973) as f32 / 9973.0
                };
                let x = p.point(lo + (hi - lo) * Vec3::new(u(1), u(2), u(3)));
                let y = x + sun * 100.0;
                let mut t = 1.0f32;
                for (k2, p2) in places.iter().enumerate() {
                    let tables = &image_tables[original(k2)];
                    let (lo2, hi2) = tables.bounds();
                    if k2 != k && meets(p2, lo2, hi2, x, y) {
                        let tau = tables.tau(p2.rotation.conjugate() * sun);
                        // A point inside a neighbour's box crosses part of it.
                        let inside_it = inside(p2, lo2, hi2, x);
                        t *= if inside_it {
                            tau.powf(chord_share(p2, lo2, hi2, x, y).unwrap_or(1.0))
                        } else {
                            tau
                        };
                    }
                }
                sum += t as f64;
            }
            let v = (sum / m as f64) as f32;
            if v < 0.97 {
                shaded += 1;
            }
            let shadow =
                p.scale * p.scale * image_tables[original(k)].shadow(p.rotation.conjugate() * sun);
            for (band, e) in [500.0f32, 400.0].into_iter().enumerate() {
                let want = e * shadow * v;
                let got = r.intercepted(band);
                assert!(
                    (got - want).abs() <= 0.04 * e * shadow + 1e-6,
                    "instance {k} band {band}: {got} vs {want} (seen {v})"
                );
            }
        }
    })
    .unwrap();
    assert!(shaded >= 2, "the test must shade some instances: {shaded}");
}

/// Where the segment `a..b` crosses the triangle `t` (its parameter), by Moller and
/// Trumbore in f64: a reference that shares no code with the core's watertight test.
fn segment_triangle(a: Vec3, b: Vec3, t: [Vec3; 3]) -> Option<f64> {
    let f = |v: Vec3| glam::DVec3::new(v.x as f64, v.y as f64, v.z as f64);
    let (o, d) = (f(a), f(b) - f(a));
    let (p0, p1, p2) = (f(t[0]), f(t[1]), f(t[2]));
    let (e1, e2) = (p1 - p0, p2 - p0);
    let h = d.cross(e2);
    let det = e1.dot(h);
    if det.abs() < 1e-14 {
        return None;
    }
    let s = o - p0;
    let u = s.dot(h) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    let s_t = e2.dot(q) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && s_t > 0.0 && s_t < 1.0).then_some(s_t)
}

/// Closed instances block with their originals' own polygons, placed (the default): the
/// leaf's quad under each of its placements, and the shrub's three nested leaves under
/// each shrub's. Segments through the row against every placed quad, tested apart.
#[test]
fn closed_instances_block_with_their_own_polygons() {
    let (s, places) = scene(12);
    let bytes = compile(&s).unwrap();
    let view = SceneView::open(SliceSource(&bytes[..])).unwrap();
    let leaf = [
        Vec3::new(-0.1, -0.1, 0.0),
        Vec3::new(0.1, -0.1, 0.0),
        Vec3::new(0.1, 0.1, 0.02),
        Vec3::new(-0.1, 0.1, 0.02),
    ];
    // Every closed instance's quads in the world, by instance (the scene's order).
    let mut quads: Vec<Vec<[Vec3; 4]>> = Vec::new();
    for (k, p) in places.iter().enumerate() {
        if (12..14).contains(&k) {
            let mut q = Vec::new();
            for m in 0..3 {
                let inner = place(Vec3::Z, m as f32, Vec3::new(0.0, 0.0, 0.2 * m as f32), 1.0);
                q.push(leaf.map(|c| p.point(inner.point(c))));
            }
            quads.push(q);
        } else {
            quads.push(vec![leaf.map(|c| p.point(c))]);
        }
    }
    let blocked = |a: Vec3, b: Vec3, skip: Option<usize>| -> bool {
        quads.iter().enumerate().any(|(k, qs)| {
            Some(k) != skip
                && qs.iter().any(|q| {
                    segment_triangle(a, b, [q[0], q[1], q[2]]).is_some()
                        || segment_triangle(a, b, [q[0], q[2], q[3]]).is_some()
                })
        })
    };
    let mut ws = vec![0u8; 64 << 20];
    load_level(
        &view,
        &Settings::default(),
        Instancing::Top,
        &mut ws,
        |level| {
            let mut by_node: Vec<u32> = (0..level.instances()).collect();
            by_node.sort_by_key(|&i| level.instance(i).node);
            let (mut hits, mut wrong) = (0, 0);
            for k in 0..4000u32 {
                let h = |j: u32| ((k * 7919 + j * 104_729) % 1000) as f32 / 1000.0;
                // Segments along the row, low over the ground, so that many meet leaves.
                let a = Vec3::new(-5.0 + 10.0 * h(1), 0.2 + 1.6 * h(2), 0.2 + 0.6 * h(3));
                let b = Vec3::new(-5.0 + 10.0 * h(4), 0.2 + 1.6 * h(5), 0.2 + 0.6 * h(6));
                let want = if blocked(a, b, None) { 0.0 } else { 1.0 };
                let got = level.transmittance(a, b, None);
                hits += (want == 0.0) as u32;
                wrong += (got != want) as u32;
            }
            assert!(hits > 40, "the segments must meet leaves: {hits}");
            assert_eq!(
                wrong, 0,
                "{wrong} of 4000 segments disagree ({hits} blocked)"
            );
            // The nearest instance met, and where: the one of the nearest quad crossed.
            let nearest = |a: Vec3, b: Vec3| -> Option<(usize, f64)> {
                let mut best: Option<(usize, f64)> = None;
                for (k, qs) in quads.iter().enumerate() {
                    for q in qs {
                        for t in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
                            if let Some(s) = segment_triangle(a, b, t)
                                && best.is_none_or(|(_, b)| s < b)
                            {
                                best = Some((k, s));
                            }
                        }
                    }
                }
                best
            };
            let mut met = 0;
            for k in 0..4000u32 {
                let h = |j: u32| ((k * 7919 + j * 104_729 + 17) % 1000) as f32 / 1000.0;
                let a = Vec3::new(-5.0 + 10.0 * h(1), 0.2 + 1.6 * h(2), 0.2 + 0.6 * h(3));
                let b = Vec3::new(-5.0 + 10.0 * h(4), 0.2 + 1.6 * h(5), 0.2 + 0.6 * h(6));
                let got = level.first_instance(a, b, None, k);
                match nearest(a, b) {
                    Some((q, t)) => {
                        met += 1;
                        let (i, s) = got.unwrap_or_else(|| panic!("segment {k} meets quad {q}"));
                        assert_eq!(i, by_node[q], "segment {k}: nearest instance");
                        assert!((s as f64 - t).abs() < 1e-4, "segment {k}: at {s}, not {t}");
                    }
                    None => assert_eq!(got, None, "segment {k} meets no quad"),
                }
            }
            assert!(met > 40, "the segments must meet leaves: {met}");
            // From a point of each instance's own quad, with it skipped: the others only.
            for (k, qs) in quads.iter().enumerate() {
                let a = (qs[0][0] + qs[0][2]) * 0.5;
                for j in 0..50u32 {
                    let t = j as f32 * 0.4;
                    let b = a + Vec3::new(6.0 * t.cos(), 1.0 * t.sin(), 0.3 * (t * 1.7).sin());
                    let want = if blocked(a, b, Some(k)) { 0.0 } else { 1.0 };
                    let got = level.transmittance(a, b, Some(by_node[k]));
                    assert_eq!(got, want, "from instance {k}, segment {j}");
                }
            }
        },
    )
    .unwrap();
}

/// A closed approximate instance blocks rays with its own polygons, which need not lie where
/// its original's do (the leaf's own quad here lies beside the original's, out of the
/// original's box): by default the own quad blocks and the original's place lets light
/// through; with `own_polygons` 0, or a level's own polygons above it, the reverse. The
/// census counts them, and the exchange (which lands light on the polygons the tables
/// know) still meets the original's quad.
#[test]
fn closed_approximate_instances_block_with_the_polygons_they_hold() {
    let (mut s, places) = scene(3);
    let approx = places[places.len() - 1];
    let shift = Vec3::new(0.6, 0.0, 0.0);
    let own_local = [
        Vec3::new(-0.1, -0.1, 0.0) + shift,
        Vec3::new(0.1, -0.1, 0.0) + shift,
        Vec3::new(0.1, 0.1, 0.02) + shift,
        Vec3::new(-0.1, 0.1, 0.02) + shift,
    ];
    let leaf_m = 1;
    let mut own = Cluster::named("leaf");
    add_quad(&mut own, own_local, leaf_m);
    own.instance = Some(InstanceOf {
        original: 0,
        exact: false,
        transform: approx,
    });
    *s.root.children.last_mut().unwrap() = own;
    let bytes = compile(&s).unwrap();
    let view = SceneView::open(SliceSource(&bytes[..])).unwrap();
    // Through the middle of a quad (local corners), along its normal, 0.4 m each way.
    let through = |c: [Vec3; 4]| {
        let w = c.map(|p| approx.point(p));
        let mid = (w[0] + w[2]) * 0.5;
        let n = (w[1] - w[0]).cross(w[3] - w[0]).normalize();
        (mid - 0.4 * n, mid + 0.4 * n)
    };
    let original_local = own_local.map(|p| p - shift);
    let (own_a, own_b) = through(own_local);
    let (org_a, org_b) = through(original_local);
    let mut ws = vec![0u8; 64 << 20];
    let mut scratch = vec![0u8; census_scratch_bytes(&view)];
    // The level holds one own polygon: at the limit it blocks with it, below it not.
    for (own_polygons, uses_own) in [(Settings::OWN_POLYGONS, true), (1, true), (0, false)] {
        let settings = Settings {
            own_polygons,
            ..Settings::default()
        };
        let c = hirad_core::hr::census_level(
            &view,
            settings.max_children,
            Instancing::Top,
            hirad_core::hr::Inline::NONE,
            hirad_core::hr::BlockingLimits::of(&settings),
            &mut scratch,
        )
        .unwrap();
        assert_eq!(c.own_polygons, u64::from(uses_own), "{own_polygons}");
        assert_eq!(c.own_bytes > 0, uses_own, "{own_polygons}");
        load_level(&view, &settings, Instancing::Top, &mut ws, |level| {
            let i = (0..level.instances())
                .max_by_key(|&i| level.instance(i).node)
                .unwrap();
            let b = level.instance(i).bounds;
            if uses_own {
                // Its box holds the quad it blocks with.
                for p in own_local.map(|p| approx.point(p)) {
                    assert!(
                        (b.min - Vec3::splat(1e-4)).cmple(p).all()
                            && p.cmple(b.max + Vec3::splat(1e-4)).all(),
                        "{p} outside {b:?}"
                    );
                }
            }
            let (own_t, org_t) = (
                level.transmittance(own_a, own_b, None),
                level.transmittance(org_a, org_b, None),
            );
            if uses_own {
                assert_eq!((own_t, org_t), (0.0, 1.0), "{own_polygons}");
            } else {
                assert_eq!((own_t, org_t), (1.0, 0.0), "{own_polygons}");
            }
            // Skipped (a ray from its own contents): nothing of it is in the way.
            assert_eq!(level.transmittance(own_a, own_b, Some(i)), 1.0);
            // The exchange meets the quad its tables know, halfway.
            let met = level.first_instance(org_a, org_b, None, 7);
            let (j, t) = met.expect("the original's quad is met");
            assert_eq!(j, i);
            assert!((t - 0.5).abs() < 1e-3, "{t}");
            assert_eq!(level.first_instance(own_a, own_b, None, 7), None);
        })
        .unwrap();
    }
}
