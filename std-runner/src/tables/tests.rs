//! Tables of a single two-sided leaf against their closed forms: under a sun of 1 W/m^2 at
//! cosine `c` to its normal the leaf intercepts `a |c|`, its lit side leaves `rho |c|` (the
//! front's or the back's reflectance: they differ) and its other side `tau |c|` (nothing else
//! is there to light it), and an observer sees the side facing them, at radiance `B / pi`
//! over the area `a |cosine|`.

use super::{OriginalTables, TableSettings, bake_original};
use crate::generate::palette::two_sided;
use crate::generate::shapes::add_quad;
use crate::scene::{Cluster, InstanceOf, Original, Scene, Similarity};
use crate::solve::RayonExecutor;
use crate::tables::instanced_originals;
use glam::Vec3;
use hirad_core::sampling::{hash3, unit2};
use hirad_core::tables::bake::TauSettings;

const RHO: [f32; 2] = [0.1, 0.45];
const RHO_BACK: [f32; 2] = [0.16, 0.3];
const TAU: [f32; 2] = [0.05, 0.4];

/// The reflectance of the side of a leaf of normal `n` that faces `d`.
fn rho_facing(n: Vec3, d: Vec3, b: usize) -> f32 {
    if n.dot(d) >= 0.0 { RHO[b] } else { RHO_BACK[b] }
}

/// A scene whose only original, `name`, holds the leaves `add` puts into it (given their
/// two-sided material), placed once.
fn placed_once(name: &str, add: impl FnOnce(&mut Cluster, u32)) -> Scene {
    let mut scene = Scene::new(2);
    let m = two_sided(&mut scene, "leaf", &RHO, &RHO_BACK, &TAU);
    let mut root = Cluster::named(name);
    add(&mut root, m);
    scene.originals.push(Original {
        name: name.into(),
        root,
    });
    scene.root.children.push(Cluster {
        instance: Some(InstanceOf {
            original: 0,
            exact: true,
            transform: Similarity::IDENTITY,
        }),
        ..Cluster::default()
    });
    scene
}

/// Adds a square leaf of side `side` centred at `c` with normal `n`.
fn add_square(cluster: &mut Cluster, c: Vec3, n: Vec3, side: f32, material: u32) {
    let (u, v) = crate::generate::shapes::frame(n);
    let h = side * 0.5;
    add_quad(
        cluster,
        [
            c - u * h - v * h,
            c + u * h - v * h,
            c + u * h + v * h,
            c - u * h + v * h,
        ],
        material,
    );
}

/// A scene whose only original is one square leaf of side `side` with normal `n`, placed
/// once.
pub(super) fn one_leaf(n: Vec3, side: f32) -> Scene {
    placed_once("leaf", |leaf, m| add_square(leaf, Vec3::ZERO, n, side, m))
}

fn direction(k: u32, seed: u32) -> Vec3 {
    let (a, b) = unit2(hash3(seed, k, 0xD1));
    let z = 1.0 - 2.0 * a;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let p = std::f32::consts::TAU * b;
    Vec3::new(r * p.cos(), r * p.sin(), z)
}

fn small_settings() -> TableSettings {
    TableSettings {
        tau: TauSettings {
            rays: 128,
            target: 0.02,
            checks: 16,
            seed: 1,
        },
        tau_check_rays: 256,
        max_tau_side: 32,
        first_side: 8,
        max_side: 8,
        first_out_side: 16,
        max_out_side: 16,
        checks: 2,
        out_checks: 2,
        first_single_side: 32,
        max_single_side: 128,
        ..TableSettings::default()
    }
}

fn bake(scene: &Scene) -> OriginalTables {
    let mut exec = RayonExecutor::new(2).unwrap();
    bake_original(scene, 0, &small_settings(), &mut exec, &mut |_, _, _| {}).unwrap()
}

#[test]
fn a_leafs_tables_match_their_closed_forms() {
    for (k, side) in [(0u32, 0.5f32), (1, 0.02), (2, 3.0)] {
        let n = direction(k, 17);
        let scene = one_leaf(n, side);
        let t = bake(&scene);
        let a = side * side;
        let view = t.view();
        // Energy per incoming cell: intercepted, scattered, absorbed and uncollided add up.
        for (i, r) in t.residual.iter().enumerate() {
            assert!(r.abs() < 0.005, "leaf {k}: residual {r} at {i}");
        }
        // The albedo is rho + tau of the lit side in every cell of the tau grid where the
        // leaf is met (none where it is seen edge-on), all of it from that side.
        let mut met = 0;
        for c in 0..t.tau_grid.cells() {
            let d = t.tau_grid.direction(c);
            if t.tau[c as usize] > 0.99 {
                continue;
            }
            met += 1;
            // All of it from the side facing the sun, none from the other.
            let lit = if n.dot(d) >= 0.0 { 0 } else { 1 };
            let at = |side: usize, b: usize| view.albedo_values()[(c as usize * 2 + side) * 2 + b];
            for (b, tau) in TAU.iter().enumerate() {
                let want = rho_facing(n, d, b) + tau;
                let got = at(lit, b);
                assert_eq!(at(1 - lit, b), 0.0, "leaf {k} cell {c}");
                assert!(
                    (got - want).abs() < 0.02 * want,
                    "leaf {k} cell {c}: {got} vs {want}; cos {} shadow {} area {}",
                    n.dot(d),
                    view.shadow(d),
                    view.area(d)
                );
            }
        }
        assert!(met * 2 > t.tau_grid.cells(), "leaf {k}: met in {met} cells");
        for j in 0..40 {
            let source = direction(j, 100 + k);
            let observer = direction(j, 200 + k);
            let (ci, co) = (n.dot(source), n.dot(observer));
            // Scattered power away from the leaf's plane (where |cos| folds).
            if ci.abs() > 0.2 {
                for (b, tau) in TAU.iter().enumerate() {
                    let want = (rho_facing(n, source, b) + tau) * a * ci.abs();
                    let got = view.scattered(source, b);
                    assert!(
                        (got - want).abs() < 0.02 * want,
                        "leaf {k}: scattered {got} vs {want}"
                    );
                }
            }
            // The bidirectional intensity, right on either side of the plane where the side lit
            // flips (each side lit has its own response), away from where the side seen does.
            if ci.abs() > 0.25 && co.abs() > 0.6 {
                for (b, &tau) in TAU.iter().enumerate() {
                    let seen = if (ci > 0.0) == (co > 0.0) {
                        rho_facing(n, source, b)
                    } else {
                        tau
                    };
                    let want = seen * ci.abs() / std::f32::consts::PI * a * co.abs();
                    let got = view.intensity(source, observer, b);
                    assert!(
                        (got - want).abs() < 0.03 * want,
                        "leaf {k}: intensity {got} vs {want}"
                    );
                }
            }
        }
    }
}

#[test]
fn originals_come_after_the_originals_they_hold() {
    let mut scene = one_leaf(Vec3::Z, 1.0);
    // "twig" holds two leaves; "branch" holds a twig; the scene holds a branch only.
    let leaf_at = |x: f32| Cluster {
        instance: Some(InstanceOf {
            original: 0,
            exact: true,
            transform: Similarity {
                translation: Vec3::new(x, 0.0, 0.0),
                ..Similarity::IDENTITY
            },
        }),
        ..Cluster::default()
    };
    let mut twig = Cluster::named("twig");
    twig.children = vec![leaf_at(0.0), leaf_at(2.0)];
    let mut branch = Cluster::named("branch");
    branch.children.push(Cluster {
        instance: Some(InstanceOf {
            original: 2,
            exact: true,
            transform: Similarity::IDENTITY,
        }),
        ..Cluster::default()
    });
    // Stored out of order: branch (1) before twig (2); an unused original last.
    scene.originals.push(Original {
        name: "branch".into(),
        root: branch,
    });
    scene.originals.push(Original {
        name: "twig".into(),
        root: twig,
    });
    scene.originals.push(Original {
        name: "unused".into(),
        root: Cluster::named("unused"),
    });
    scene.root.children[0].instance.as_mut().unwrap().original = 1;
    assert_eq!(instanced_originals(&scene), vec![0, 2, 1]);
}

/// The colour-map value (0..=1) whose viridis colour is nearest to `px`.
fn viridis_value(px: &[u8]) -> f32 {
    use crate::output::colormap::viridis_u8;
    let dist = |t: f32| {
        let c = viridis_u8(t);
        (0..3)
            .map(|i| (c[i] as i32 - px[i] as i32).pow(2))
            .sum::<i32>()
    };
    (0..=1000)
        .map(|k| k as f32 / 1000.0)
        .min_by_key(|&t| dist(t))
        .unwrap()
}

#[test]
fn the_plot_draws_tau_and_both_phase_forms_at_their_directions() {
    use crate::output::colorbar::Scale;
    // A level leaf whose front (up) and back reflect differently, one square metre.
    let t = bake(&one_leaf(Vec3::Z, 1.0));
    let b = 1;
    let (w, h, rgb) = super::picture(&t, b, "nir");
    assert_eq!(rgb.len(), (w * h * 3) as usize);
    let at = |panel: u32, az: f32, el: f32| {
        let (x, y) = super::map_pixel(panel, az, el);
        let i = ((y * w + x) * 3) as usize;
        viridis_value(&rgb[i..i + 3])
    };
    // tau: the leaf fills its box, so nothing passes from above or below.
    for (az, el) in [(10.0, 80.0), (200.0, -70.0), (300.0, 30.0)] {
        assert!(at(0, az, el) < 0.02, "tau at {az} {el}: {}", at(0, az, el));
    }
    // Scattered power: (rho of the lit side + tau) x |cos|, on a scale whose top is the
    // round value above the largest, the front's from the zenith.
    let top = Scale::new(f64::from(RHO[b] + TAU[b])).top as f32;
    for (el, rho) in [
        (89.0f32, RHO[b]),
        (-89.0, RHO_BACK[b]),
        (40.0, RHO[b]),
        (-50.0, RHO_BACK[b]),
    ] {
        let want = (rho + TAU[b]) * el.to_radians().sin().abs() / top;
        let got = at(1, 123.0, el);
        assert!(
            (got - want).abs() < 0.02,
            "scattered at el {el}: {got} vs {want}"
        );
    }
    // Bidirectional, sun at elevation 60 on the front: the front is seen from above at
    // radiance rho E / pi, the back from below at tau E / pi.
    let e = 60f32.to_radians().sin();
    let up = RHO[b] * e / std::f32::consts::PI;
    let top = Scale::new(f64::from(up)).top as f32;
    for (el, seen) in [(85.0f32, RHO[b]), (-85.0, TAU[b]), (-30.0, TAU[b])] {
        let want = seen * e / std::f32::consts::PI * el.to_radians().sin().abs() / top;
        let got = at(2, 250.0, el);
        assert!(
            (got - want).abs() < 0.03,
            "intensity at el {el}: {got} vs {want}"
        );
    }
}

/// A scene whose only original is a clump of square leaves of side `size` (below 0.7) with
/// random normals, one at each point of a 2 x 2 x 2 lattice of spacing 0.5 m (they shade
/// and light each other, and do not cross), placed once.
fn clump(size: f32, seed: u32) -> Scene {
    placed_once("clump", |leaves, m| {
        for k in 0..8u32 {
            let c = Vec3::new((k & 1) as f32, ((k >> 1) & 1) as f32, (k >> 2) as f32) * 0.5;
            add_square(leaves, c, direction(k, seed + 1), size, m);
        }
    })
}

#[test]
fn the_response_by_reciprocity_agrees_with_solves_that_light_one_side() {
    // The phase table comes from solves under suns at the outgoing cells (reciprocity);
    // here each value at a pair of cell centres is set against a solve under a sun at the
    // incoming centre that lights only the side the table keeps it for, its light read
    // from the surfaces seen from the outgoing centre. The phase table holds all the
    // light here (no first scattering kept apart).
    use super::sample::sample_sides;
    // Two clumps: leaves of 0.4 m (close to touching) and of 0.15 m (sparse).
    for (size, seed) in [(0.4f32, 3u32), (0.15, 11)] {
        let scene = clump(size, seed);
        let settings = TableSettings {
            max_single_side: 0,
            ..small_settings()
        };
        let mut exec = RayonExecutor::new(2).unwrap();
        let t = bake_original(&scene, 0, &settings, &mut exec, &mut |_, _, _| {}).unwrap();
        let view = t.view();
        let phase = view.phase();
        let alone = super::Alone::new(&scene, 0).unwrap();
        let mut compared = 0;
        for k in 0..6u32 {
            let ci = hash3(7, k, 1) % t.incoming.cells();
            let d = t.incoming.direction(ci);
            for side in 0..2 {
                if phase.share_at(ci, side, 0) < 0.2 {
                    continue;
                }
                let s = sample_sides(&alone, d, &settings, 1 << side, &mut exec).unwrap();
                for j in 0..4u32 {
                    let co = hash3(7, k * 8 + j, 2) % t.outgoing.cells();
                    let o = t.outgoing.direction(co);
                    let (i, _) = s.intensity(&alone, o, 12, j);
                    for (b, &light) in i.iter().enumerate().take(2) {
                        let scattered = s.scattered[b] * s.area;
                        let mean = scattered / (4.0 * std::f32::consts::PI);
                        let want = light / scattered / view.shadow(o);
                        let got = phase.response_at(ci, co, side, b);
                        let scale = light.max(mean) / scattered / view.shadow(o);
                        assert!(
                            (got - want).abs() < 0.04 * scale,
                            "cell {ci} side {side} to {co} band {b}: {got} vs {want}"
                        );
                        compared += 1;
                    }
                }
            }
        }
        assert!(compared >= 32, "clump of {size} m: {compared}");
    }
}

#[test]
fn the_first_scattering_kept_apart_and_the_rest_add_up_to_a_solves_light() {
    // With the polygons' first scattering kept apart, the phase table holds the rest. At
    // pairs of cell centres, set against a solve under a sun at the incoming centre (its
    // light read from the surfaces seen from the outgoing centre): the rest plus the first
    // scattering from visible fractions cast at those directions (the decomposition), and
    // the table's whole intensity (the fractions interpolated on their grid). The same
    // clumps as above; the first scattering is most of their light.
    for (size, seed) in [(0.4f32, 3u32), (0.15, 11)] {
        let scene = clump(size, seed);
        let settings = small_settings();
        let mut exec = RayonExecutor::new(2).unwrap();
        let t = bake_original(&scene, 0, &settings, &mut exec, &mut |_, _, _| {}).unwrap();
        let single = t
            .single
            .as_ref()
            .expect("a clump of 8 leaves keeps its first scattering");
        assert_eq!(single.polygons, 8);
        let view = t.view();
        let alone = super::Alone::new(&scene, 0).unwrap();
        let (mut compared, mut first_share, mut worst) = (0, 0.0f32, 0.0f32);
        for k in 0..6u32 {
            let d = t.incoming.direction(hash3(9, k, 1) % t.incoming.cells());
            let s = super::sample_at(&alone, d, &settings, &mut exec).unwrap();
            let vd = alone.visible(d, 15, k);
            for j in 0..4u32 {
                let o = t
                    .outgoing
                    .direction(hash3(9, k * 8 + j, 2) % t.outgoing.cells());
                let (i, _) = s.intensity(&alone, o, 12, j);
                let vo = alone.visible(o, 15, 100 + j);
                for (b, &light) in i.iter().enumerate().take(2) {
                    let mean = s.scattered[b] * s.area / (4.0 * std::f32::consts::PI);
                    let scale = light.max(mean);
                    let first =
                        super::single_bake::first_scattering(&alone, d, o, b, |p| vd[p], |p| vo[p]);
                    let sum = first + view.response_intensity(d, o, b);
                    assert!(
                        (sum - light).abs() < 0.04 * scale,
                        "clump {size}: sun {d} to {o} band {b}: {sum} vs {light}"
                    );
                    worst = worst.max((view.intensity(d, o, b) - light).abs() / scale);
                    first_share = first_share.max(first / scale);
                    compared += 1;
                }
            }
        }
        assert_eq!(compared, 48);
        assert!(first_share > 0.5, "clump {size}: {first_share}");
        if size > 0.3 {
            assert!(worst < 0.04, "clump {size}: the table's intensity {worst}");
        } else {
            // Small leaves far apart: each one's shadows move across it within a few
            // degrees, so the bake had to refine the grid of visible fractions.
            assert!(single.tried.len() > 1, "{:?}", single.tried);
        }
    }
}

#[test]
fn suns_sharing_a_solve_each_get_their_own_light() {
    // `solve_many` puts several suns in one solve, each in its own copy of the bands; each
    // sun's light must be what a solve under it alone gives (the shared refinement is
    // finer, never coarser): the scattered and absorbed power per band, and every lit
    // polygon side's irradiance. Two bands (four suns a solve, six suns: 4 + 2) and three
    // bands (two a solve, three suns: 2 + 1, the last alone).
    use hirad_core::hr::Settings;
    for bands in [2usize, 3] {
        let mut scene = clump(0.4, 3);
        if bands == 3 {
            scene.bands = 3;
            if !scene.band_names.is_empty() {
                scene.band_names.push("third".into());
            }
            for m in &mut scene.materials {
                m.data.bands = 3;
                m.data.rho_front[2] = 0.3;
                m.data.rho_back[2] = 0.2;
                if m.data.two_sided {
                    m.data.tau[2] = 0.25;
                }
            }
        }
        let alone = super::Alone::new(&scene, 0).unwrap();
        let settings = Settings {
            epsilon: 1e-4,
            final_rays: 0,
            ..Settings::default()
        };
        let mut exec = RayonExecutor::new(2).unwrap();
        let suns: Vec<Vec3> = (0..if bands == 2 { 6 } else { 3 })
            .map(|k| direction(k, 40 + bands as u32))
            .collect();
        let many = alone.solve_many(&suns, &settings, &mut exec).unwrap();
        assert_eq!(many.len(), suns.len());
        for (k, (d, got)) in suns.iter().zip(&many).enumerate() {
            let want = alone.solve(*d, &settings, &mut exec).unwrap();
            assert_eq!(got.table.bands, bands);
            assert_eq!(got.table.len(), want.table.len());
            let (g, w) = (&got.stats.balance, &want.stats.balance);
            for b in 0..bands {
                for (what, x, y) in [
                    ("direct", g.direct[b], w.direct[b]),
                    ("escaped", g.escaped[b], w.escaped[b]),
                    (
                        "absorbed",
                        g.absorbed[b] + g.absorbed_backs[b],
                        w.absorbed[b] + w.absorbed_backs[b],
                    ),
                ] {
                    assert!(
                        (x - y).abs() <= 0.01 * y.abs().max(1e-3),
                        "{bands} bands, sun {k} band {b}: {what} {x} vs {y}"
                    );
                }
                for p in 0..want.table.len() {
                    for side in 0..2 {
                        let (x, y) = (
                            got.table.irradiance(p, side)[b],
                            want.table.irradiance(p, side)[b],
                        );
                        assert!(
                            (x - y).abs() <= 0.03 * y.max(0.05),
                            "{bands} bands, sun {k} band {b} polygon {p} side {side}: {x} vs {y}"
                        );
                    }
                }
            }
            // Nothing of the band copies beyond this sun's is left in its light.
            assert!(got.stats.balance.escaped[bands..].iter().all(|&e| e == 0.0));
        }
    }
}
