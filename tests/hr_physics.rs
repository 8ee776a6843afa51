//! The hierarchical solver right on every polygon (issue 7): leaves lit through their cluster,
//! soil under a canopy, power balance on random scenes at every scale, furnaces at extreme
//! albedo, a tiny lamp over a huge floor, coincident polygons. References: the exact solver,
//! closed forms, and shadow rays cast here, apart from the solver.

use hirad::exact::{ExactSettings, solve_exact_obvhs};
use hirad::output::ResultsTable;
use hirad::scene::Scene;
use hirad::solve::world_polygons;
use hirad::visibility::ObvhsVisibility;
use hirad_core::hr::{HrError, NoProgress, Settings, Stats};
use hirad_core::visibility::Visibility;
use hirad_tests::Rng;

fn parse(text: &str) -> Scene {
    hirad::text::parse(text.as_bytes()).unwrap()
}

fn solve(scene: &Scene, settings: &Settings) -> Result<(ResultsTable, Stats), HrError> {
    hirad_tests::solve_hr(scene, settings, &mut NoProgress)
}

fn exact(scene: &Scene, elements: usize) -> ResultsTable {
    let two_sided = scene.materials.iter().any(|m| m.data.two_sided);
    let mut table = ResultsTable::new(scene.bands as usize, two_sided);
    let settings = ExactSettings {
        max_elements: elements,
        ..ExactSettings::default()
    };
    solve_exact_obvhs(scene, &settings, &mut table).unwrap();
    table
}

/// A quad of half-size (`a`, `b`) centred at `c`, spanned by the orthonormal `u`, `v`.
fn quad(mat: &str, c: [f32; 3], u: [f32; 3], v: [f32; 3], a: f32, b: f32) -> String {
    let p = |su: f32, sv: f32| {
        format!(
            "{} {} {}",
            c[0] + su * a * u[0] + sv * b * v[0],
            c[1] + su * a * u[1] + sv * b * v[1],
            c[2] + su * a * u[2] + sv * b * v[2]
        )
    };
    format!(
        "quad {mat} {}  {}  {}  {}\n",
        p(-1., -1.),
        p(1., -1.),
        p(1., 1.),
        p(-1., 1.)
    )
}

/// A random orthonormal pair for a leaf: tilt in 0..100 degrees (some face down).
fn leaf_axes(r: &mut Rng) -> ([f32; 3], [f32; 3]) {
    let tilt = r.range(0.0, 1.75);
    let az = r.range(0.0, std::f32::consts::TAU);
    let n = [tilt.sin() * az.cos(), tilt.sin() * az.sin(), tilt.cos()];
    let t = if n[2].abs() < 0.9 {
        [0.0, 0.0, 1.0]
    } else {
        [1.0, 0.0, 0.0]
    };
    let cross = |a: [f32; 3], b: [f32; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let norm = |a: [f32; 3]| {
        let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        [a[0] / l, a[1] / l, a[2] / l]
    };
    let u = norm(cross(t, n));
    let v = cross(n, u);
    (u, v)
}

/// Relative difference of `got` from `want`.
fn rel(got: f32, want: f32) -> f64 {
    (got as f64 - want as f64) / want as f64
}

#[test]
fn leaves_lit_through_their_cluster_match_the_exact_solver_front_and_back() {
    // fixtures/leaves_cluster.hir: twelve translucent leaves of several orientations in a
    // cluster over a tiled soil, lit by a sun from one side (PAR and NIR): every leaf's
    // radiosity, front and back, within 3% of the exact solver at the default epsilon.
    let scene =
        parse(&std::fs::read_to_string(hirad_tests::fixture("leaves_cluster.hir")).unwrap());
    let (hr, stats) = solve(&scene, &Settings::default()).unwrap();
    assert!(stats.converged);
    let ex = exact(&scene, 3000);
    let n = hr.len();
    let mut worst = 0.0f64;
    for row in n - 12..n {
        for side in 0..2 {
            for band in 0..2 {
                let (g, w) = (hr.radiosity(row, side)[band], ex.radiosity(row, side)[band]);
                let e = rel(g, w);
                assert!(
                    e.abs() < 0.03,
                    "leaf {row} side {side} band {band}: {g} vs exact {w} ({:+.2}%)",
                    100.0 * e
                );
                worst = worst.max(e.abs());
            }
        }
    }
    eprintln!("worst leaf {:.2}%", 100.0 * worst);
}

#[test]
fn a_stem_in_the_sun_gets_the_light_of_the_soil_on_its_shaded_faces() {
    // A closed square stem (2 cm wide, 1 m tall in 10 segments) on a 4 x 4 m soil of 0.5 m
    // quads in a cluster, a sun at 30 degrees from the zenith along +x: the -x and +-y faces
    // get no sun, only what the soil and the sunlit faces reflect, and that through the
    // stem's cluster. Their mean within 3% of the exact solver and every face within 15%:
    // the final gather gives each face its own light (through the cluster alone it was too
    // even along the stem, +48% at the foot and -35% half way up; before that the stem's far
    // side counted as shadow for the whole stem, -55%).
    let mut text = String::from(
        "hirad 1\nbands 1\nmaterial soil rho 0.25\nmaterial stem rho 0.4\n\
         sun from 0.5 0 0.8660254 irradiance 400\nscene {\n  cluster soil {\n",
    );
    for j in 0..8 {
        for i in 0..8 {
            let c = [-1.75 + 0.5 * i as f32, -1.75 + 0.5 * j as f32, 0.0];
            text += &quad("soil", c, [1., 0., 0.], [0., 1., 0.], 0.25, 0.25);
        }
    }
    text += "  }\n  cluster stem {\n";
    let w = 0.01f32;
    // Outward normal, then the face's horizontal axis (u x v = normal, v up).
    let faces: [([f32; 3], [f32; 3]); 4] = [
        ([1., 0., 0.], [0., 1., 0.]),
        ([-1., 0., 0.], [0., -1., 0.]),
        ([0., 1., 0.], [-1., 0., 0.]),
        ([0., -1., 0.], [1., 0., 0.]),
    ];
    for k in 0..10 {
        let z = 0.05 + 0.1 * k as f32;
        for (n, u) in faces {
            let c = [w * n[0], w * n[1], z];
            text += &quad("stem", c, u, [0., 0., 1.], w, 0.05);
        }
    }
    text += &quad("stem", [0., 0., 1.], [1., 0., 0.], [0., 1., 0.], w, w);
    text += "  }\n}\n";
    let scene = parse(&text);
    let (hr, _) = solve(&scene, &Settings::default()).unwrap();
    let ex = exact(&scene, 3000);
    let (mut got, mut want, mut worst) = (0.0f64, 0.0f64, 0.0f64);
    for k in 0..10 {
        for f in 1..4 {
            let row = 64 + 4 * k + f;
            let (g, w) = (hr.irradiance(row, 0)[0], ex.irradiance(row, 0)[0]);
            got += g as f64;
            want += w as f64;
            worst = worst.max(rel(g, w).abs());
        }
    }
    let e = got / want - 1.0;
    assert!(
        e.abs() < 0.03,
        "shaded faces: {got} vs exact {want} ({:+.1}%)",
        100.0 * e
    );
    assert!(worst < 0.15, "worst shaded face {:.1}%", 100.0 * worst);
    eprintln!(
        "shaded stem faces {:+.1}%, worst face {:.1}%",
        100.0 * e,
        100.0 * worst
    );
}

#[test]
fn soil_under_a_random_canopy_gets_the_sunlight_its_own_shadows_let_through() {
    // 1500 black square leaves of 0.1 m, spherical angle distribution, in a 0.6 m slab over
    // 4 x 4 m of black soil in 0.5 m quads, one sun at 30 degrees from the zenith. The
    // reference for each soil quad: 64 x 64 points, each lit if its ray to the sun misses
    // every leaf, cast here apart from the solver. Per quad within 5% rms of the mean.
    let mut r = Rng(11, 0);
    let (zen, az) = (30f32.to_radians(), 0.7f32);
    let towards = [zen.sin() * az.cos(), zen.sin() * az.sin(), zen.cos()];
    let mut text = format!(
        "hirad 1\nbands 1\nmaterial black rho 0\nsun from {} {} {} irradiance 1000\nscene {{\n  cluster soil {{\n",
        towards[0], towards[1], towards[2]
    );
    for i in 0..8 {
        for j in 0..8 {
            let c = [
                -2.0 + 0.25 + 0.5 * i as f32,
                -2.0 + 0.25 + 0.5 * j as f32,
                0.0,
            ];
            text += &quad("black", c, [1., 0., 0.], [0., 1., 0.], 0.25, 0.25);
        }
    }
    text += "  }\n  cluster canopy {\n";
    for _ in 0..1500 {
        // Spherical leaf angle distribution: normals uniform on the sphere (cos uniform).
        let cz = r.range(-1.0, 1.0);
        let phi = r.range(0.0, std::f32::consts::TAU);
        let s = (1.0 - cz * cz).max(0.0).sqrt();
        let n = [s * phi.cos(), s * phi.sin(), cz];
        let t = if n[2].abs() < 0.9 {
            [0.0, 0.0, 1.0]
        } else {
            [1.0, 0.0, 0.0]
        };
        let u = {
            let c = [
                t[1] * n[2] - t[2] * n[1],
                t[2] * n[0] - t[0] * n[2],
                t[0] * n[1] - t[1] * n[0],
            ];
            let l = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
            [c[0] / l, c[1] / l, c[2] / l]
        };
        let v = [
            n[1] * u[2] - n[2] * u[1],
            n[2] * u[0] - n[0] * u[2],
            n[0] * u[1] - n[1] * u[0],
        ];
        let c = [r.range(-2.4, 2.4), r.range(-2.4, 2.4), r.range(0.5, 1.1)];
        text += &quad("black", c, u, v, 0.05, 0.05);
    }
    text += "  }\n}\n";
    let scene = parse(&text);
    let (hr, stats) = solve(&scene, &Settings::default()).unwrap();
    // Every surface is black: the final gather has nothing to recompute and casts no ray
    // (it cost five times the hierarchy on such a canopy before issue 15).
    let hierarchy = Settings {
        final_rays: 0,
        ..Settings::default()
    };
    let (_, alone) = solve(&scene, &hierarchy).unwrap();
    assert_eq!(
        stats.rays, alone.rays,
        "the gather cast rays in a black scene"
    );
    let polys = world_polygons(&scene);
    let vis = ObvhsVisibility::new(&polys).unwrap();
    let sun = glam::Vec3::from(towards);
    let (mut sum2, mut mean) = (0.0f64, 0.0f64);
    // The central 4 x 4 quads (their shadows come from leaves all around).
    let central: Vec<usize> = (0..64)
        .filter(|k| (2..6).contains(&(k / 8)) && (2..6).contains(&(k % 8)))
        .collect();
    for &k in &central {
        let p = &polys[k];
        let mut lit = 0u32;
        const N: u32 = 64;
        for a in 0..N {
            for b in 0..N {
                let (u, v) = ((a as f32 + 0.5) / N as f32, (b as f32 + 0.5) / N as f32);
                let x = p[0] * ((1. - u) * (1. - v))
                    + p[1] * (u * (1. - v))
                    + p[2] * (u * v)
                    + p[3] * ((1. - u) * v);
                lit += (vis.transmittance(x, x + sun * 50.0, [k as u32, u32::MAX]) > 0.5) as u32;
            }
        }
        let want = 1000.0 * sun.z as f64 * lit as f64 / (N * N) as f64;
        let got = hr.irradiance(k, 0)[0] as f64;
        sum2 += (got - want).powi(2);
        mean += want;
    }
    mean /= central.len() as f64;
    let rms = (sum2 / central.len() as f64).sqrt() / mean;
    assert!(mean > 100.0, "the canopy should let light through: {mean}");
    assert!(rms < 0.05, "rms {:.2}% of the mean {mean}", 100.0 * rms);
}

/// A random scene for the balance: boxes on a floor (open) or inside a room (closed), one-
/// or two-sided materials, lit by a lamp or a sun, at a random scale, with a size ratio.
fn random_scene(seed: u32) -> String {
    let mut r = Rng(seed, 0);
    let scale = 10f32.powf(r.range(-3.0, 3.0));
    let closed = seed.is_multiple_of(3);
    let two_sided = seed.is_multiple_of(2);
    let sun = !closed && seed % 4 == 1;
    let ratio = 10f32.powf(r.range(0.0, if closed { 3.0 } else { 6.0 }));
    let mut t = format!(
        "hirad 1\nbands 2\nmaterial wall rho {} {}\n",
        r.range(0.1, 0.8),
        r.range(0.1, 0.8)
    );
    if two_sided {
        t += &format!(
            "material leaf rho {} {} back_rho {} {} tau {} {}\n",
            r.range(0.05, 0.45),
            r.range(0.05, 0.45),
            r.range(0.05, 0.45),
            r.range(0.05, 0.45),
            r.range(0.0, 0.5),
            r.range(0.0, 0.5)
        );
    } else {
        t += "material leaf rho 0.5 0.3\n";
    }
    if sun {
        t += &format!(
            "sun from {} {} 1 irradiance 100 80\n",
            r.range(-0.5, 0.5),
            r.range(-0.5, 0.5)
        );
    }
    let s = scale;
    // The lamp's side is the floor's divided by the ratio.
    let lamp = s / ratio;
    let e = 100.0 * ratio * ratio;
    t += &format!("material lamp rho 0 0 emit {e} {e}\nscene {{\n");
    let (x, y, z) = ([1., 0., 0.], [0., 1., 0.], [0., 0., 1.]);
    let neg = |a: [f32; 3]| [-a[0], -a[1], -a[2]];
    t += &quad("wall", [0., 0., 0.], x, y, s, s);
    if closed {
        // A closed room: five more walls facing in.
        t += &quad("wall", [0., 0., 2. * s], y, x, s, s);
        t += &quad("wall", [s, 0., s], neg(z), y, s, s);
        t += &quad("wall", [-s, 0., s], z, y, s, s);
        t += &quad("wall", [0., s, s], x, neg(z), s, s);
        t += &quad("wall", [0., -s, s], x, z, s, s);
    }
    if !sun {
        t += &quad(
            "lamp",
            [0., 0., (1.9 * s).min(0.5 * s + 2. * lamp)],
            y,
            x,
            lamp,
            lamp,
        );
    }
    t += "  cluster things {\n";
    for _ in 0..6 {
        let c = [
            r.range(-0.6, 0.6) * s,
            r.range(-0.6, 0.6) * s,
            r.range(0.2, 1.2) * s,
        ];
        let (u, v) = leaf_axes(&mut r);
        let size = r.range(0.05, 0.3) * s;
        t += &quad("leaf", c, u, v, size, size * 0.5);
    }
    t += "  }\n}\n";
    t
}

#[test]
fn power_balances_on_random_scenes_at_every_scale() {
    // Emitted plus direct light equals absorbed plus absorbed by backs plus escaped, per
    // band: scenes from 1 mm to 1 km across, lamps down to a millionth of the floor's size,
    // open and closed, one- and two-sided. Escape and back absorption are measured by rays
    // apart from the links, so the balance checks the transport: the hierarchy alone within
    // 2%, and after the final gather within 3% (the gather is unbiased but its few hundred
    // rays per side are noisy where a small patch of a reflector is lit thousands of times
    // brighter than the rest: seed 10, a leaf 19 m from a 2.5 cm lamp, moves by +-2.4%
    // between 600 and 10,000 rays per side).
    let mut worst = [0.0f64; 2];
    for seed in 0..12 {
        let text = random_scene(seed);
        let scene = parse(&text);
        for (gathered, limit) in [(false, 0.02), (true, 0.03)] {
            let mut settings = Settings::default();
            if !gathered {
                settings.final_rays = 0;
            }
            let (_, stats) = solve(&scene, &settings).unwrap();
            for band in 0..2 {
                let b = &stats.balance;
                let imbalance = b.relative_imbalance(band);
                assert!(
                    imbalance.abs() < limit,
                    "seed {seed} band {band}, gathered {gathered}: imbalance {:+.3}% (emitted {} direct {} absorbed {} backs {} escaped {})\n{text}",
                    100.0 * imbalance,
                    b.emitted[band],
                    b.direct[band],
                    b.absorbed[band],
                    b.absorbed_backs[band],
                    b.escaped[band]
                );
                let w = &mut worst[gathered as usize];
                *w = w.max(imbalance.abs());
            }
        }
    }
    eprintln!(
        "worst imbalance: hierarchy {:.3}%, gathered {:.3}%",
        100.0 * worst[0],
        100.0 * worst[1]
    );
}

#[test]
fn a_one_millimetre_lamp_beside_a_kilometre_floor_lights_it_with_exactly_its_power() {
    // 16 W from a 1 mm lamp 1 mm above a 1000 m floor: nearly all of it reaches the floor,
    // and the balance holds within 0.5% (the floor received 1000 times the lamp's power
    // when integrated at its own quadrature points).
    let scene = parse(
        "hirad 1\nbands 1\nmaterial floor rho 0.5\nmaterial lamp rho 0 emit 16000000\nscene {\n\
         quad floor -500 -500 0  500 -500 0  500 500 0  -500 500 0\n\
         quad lamp -0.0005 -0.0005 0.001  -0.0005 0.0005 0.001  0.0005 0.0005 0.001  0.0005 -0.0005 0.001\n}\n",
    );
    let (table, stats) = solve(&scene, &Settings::default()).unwrap();
    let received = table.irradiance(0, 0)[0] as f64 * table.areas[0] as f64;
    assert!(
        (received - 16.0).abs() < 0.08,
        "the floor receives {received} W"
    );
    let imbalance = stats.balance.relative_imbalance(0);
    assert!(
        imbalance.abs() < 0.005,
        "imbalance {:+.3}%",
        100.0 * imbalance
    );
}

fn furnace(rho: &str) -> Scene {
    let text = std::fs::read_to_string(hirad_tests::fixture("furnace.hir")).unwrap();
    parse(&text.replace(
        "material wall rho 0.5 emit 1",
        &format!("material wall rho {rho} emit 1"),
    ))
}

#[test]
fn furnaces_of_extreme_albedo_are_right_or_say_they_did_not_converge() {
    for (rho, exact) in [("0.999", 1000.0f64), ("0.9999", 10_000.0)] {
        let (table, stats) = solve(&furnace(rho), &Settings::default()).unwrap();
        for row in 0..table.len() {
            let e = (table.radiosity(row, 0)[0] as f64 - exact) / exact;
            if stats.converged {
                assert!(
                    e.abs() < 1e-3,
                    "rho {rho}, polygon {row}: {:+.4}%",
                    100.0 * e
                );
            } else {
                // Not final, and it says how far it may still move.
                assert!(
                    stats.remaining_change.is_finite() && stats.remaining_change > 0.0,
                    "rho {rho}: {}",
                    stats.remaining_change
                );
                assert!(
                    e.abs() < 1e-2,
                    "rho {rho}, polygon {row}: {:+.4}%",
                    100.0 * e
                );
            }
        }
    }
    // A closed lossless room with a lamp has no steady state: refused up front.
    match solve(&furnace("1"), &Settings::default()) {
        Err(HrError::NoSteadyState { band: 0 }) => {}
        other => panic!("{:?}", other.map(|(_, s)| s.iterations)),
    }
    // At the iteration cap the run is not converged and says how far it may still be.
    let capped = Settings {
        max_iterations: 6,
        ..Settings::default()
    };
    let (_, stats) = solve(&furnace("0.99"), &capped).unwrap();
    assert!(!stats.converged && stats.iteration_capped);
    assert!(stats.remaining_change > 1e-4 && stats.remaining_change.is_finite());
}

#[test]
fn coincident_tiny_triangles_get_identical_light() {
    // 2000 identical 1 um triangles stacked at one point under a lamp: all the same, finite,
    // and what a point on the axis of a unit square 1 m away receives: 4 x (1 / 2 pi)
    // (2 x 0.5 / sqrt(1.25) x atan(0.5 / sqrt(1.25))) = 0.239454.
    let mut text = String::from(
        "hirad 1\nbands 1\nmaterial grey rho 0.5\nmaterial lamp rho 0 emit 1\nscene {\n\
         quad lamp -0.5 -0.5 1  -0.5 0.5 1  0.5 0.5 1  0.5 -0.5 1\n  cluster stack {\n",
    );
    for _ in 0..2000 {
        text += "    tri grey 0 0 0  0.000001 0 0  0 0.000001 0\n";
    }
    text += "  }\n}\n";
    let (table, stats) = solve(&parse(&text), &Settings::default()).unwrap();
    assert!(stats.converged);
    let first = table.irradiance(1, 0)[0];
    assert!((first - 0.239454).abs() < 2e-4, "{first}");
    for row in 1..table.len() {
        assert_eq!(
            table.irradiance(row, 0)[0].to_bits(),
            first.to_bits(),
            "row {row}"
        );
    }
}

#[test]
fn every_face_of_the_triangulated_cornell_box_matches_the_exact_solver_even_slanted() {
    // The Cornell box as 32 triangles (each published quad split in two, as OBJ exporters
    // write it), and the same box turned about two axes so that no face is aligned with
    // one: every face but the lamp within 4% of `--method exact` at 3,000 elements (its
    // own worst face is 2.7% from 8,000 elements), within 8% where a face is dim (a band
    // below 2% of the walls' largest radiosity: the short block's sides in blue), the
    // walls-only L2 within 0.06% of the walls' largest radiosity. The bias this guards against made the tall block's upper front
    // triangle 12% dark at every epsilon; without the final gather the short block's dim
    // front is 9.5% bright at 1e-5.
    let path = hirad_tests::fixture("obj/cornell_triangles.obj");
    let scene = hirad::files::load_scene(&path).unwrap().scene;
    let ex = exact(&scene, 3000);
    let mut slanted = scene.clone();
    fn turn(c: &mut hirad::scene::Cluster, q: glam::Quat) {
        for v in &mut c.vertices {
            *v = q * *v;
        }
        for child in &mut c.children {
            turn(child, q);
        }
    }
    let q = glam::Quat::from_rotation_x(0.3) * glam::Quat::from_rotation_z(0.5);
    turn(&mut slanted.root, q);
    let settings = Settings {
        epsilon: 3e-5,
        ..Settings::default()
    };
    for (name, s) in [("upright", &scene), ("slanted", &slanted)] {
        let (hr, _) = solve(s, &settings).unwrap();
        let (mut sq, mut area, mut top, mut worst) = (0.0f64, 0.0f64, 0.0f32, (0.0f64, 0));
        for row in (0..hr.len()).filter(|r| !(10..=11).contains(r)) {
            for (g, w) in hr.radiosity(row, 0).iter().zip(ex.radiosity(row, 0)) {
                // Measured against the tolerance of its class: 4% bright, 8% dim.
                let scale = if *w >= 0.02 * 2.77 { 1.0 } else { 0.5 };
                let e = rel(*g, *w) * scale;
                if e.abs() > worst.0.abs() {
                    worst = (e, row);
                }
                sq += ex.areas[row] as f64 * ((g - w) as f64).powi(2);
                area += ex.areas[row] as f64;
                top = top.max(*w);
            }
        }
        let l2 = 100.0 * (sq / area).sqrt() / top as f64;
        eprintln!(
            "{name}: walls L2 {l2:.4}%, worst face {} at {:.0}% of its tolerance",
            worst.1,
            100.0 * worst.0.abs() / 0.04
        );
        assert!(
            worst.0.abs() < 0.04,
            "{name}: face {} is off the exact solver by {:.0}% of its tolerance",
            worst.1,
            100.0 * worst.0.abs() / 0.04
        );
        assert!(l2 < 0.06, "{name}: walls L2 {l2:.4}%");
    }
}

/// Leaves that emit from their front only (`emit`, no `back_emit`) in random orientations,
/// and beside them a cluster of black leaves: the light the black cluster takes, summed over
/// both sides of its leaves.
fn one_sided_lamps(seed: u32, lamps: usize, distance: f32) -> (String, Vec<f32>) {
    let mut r = Rng(seed, 0);
    let mut text = String::from(
        "hirad 1\nbands b\nmaterial lamp rho 0 emit 100 back_rho 0\n\
         material black rho 0 back_rho 0\nscene {\n  cluster lamps {\n",
    );
    for i in 0..lamps {
        // Half face the black cluster (+x), half turn their dark backs to it.
        let s = if i % 2 == 0 { 1.0 } else { -1.0 };
        let n = glam::Vec3::new(s, r.range(-0.5, 0.5), r.range(-0.5, 0.5)).normalize();
        let u = n.cross(glam::Vec3::Z).normalize();
        let (u, v) = (u.to_array(), n.cross(u).to_array());
        let c = [r.range(-0.2, 0.2), r.range(-0.2, 0.2), r.range(1.0, 1.4)];
        text += &format!("  {}", quad("lamp", c, u, v, 0.05, 0.03));
    }
    text += "  }\n  cluster black {\n";
    let mut areas = Vec::new();
    for _ in 0..40 {
        let (u, v) = leaf_axes(&mut r);
        let c = [
            distance + r.range(-0.25, 0.25),
            r.range(-0.25, 0.25),
            r.range(0.9, 1.5),
        ];
        let (a, b) = (r.range(0.02, 0.04), r.range(0.01, 0.02));
        text += &format!("  {}", quad("black", c, u, v, a, b));
        areas.push(4.0 * a * b);
    }
    text += "  }\n}\n";
    (text, areas)
}

#[test]
fn a_cluster_takes_light_only_from_the_sides_of_leaves_that_emit() {
    // A link into a cluster from a leaf took the light of whichever side of the leaf its
    // sample points saw at the radiosity of the front: a cluster that sees the dark backs
    // of lamps got their fronts' light (a 3 x 4 canopy of such leaves made 8% of its light).
    // Against the exact solver, the black cluster's absorbed power within 10% (plus what
    // epsilon allows), and the power balance within 1%, at several distances and lamp
    // counts. Measured: -2.6% to +0.1%, and +17.6% (2.8 mW of 7.2 W emitted) with 12 lamps;
    // before the fix +18% to +118%.
    for (seed, lamps, distance) in [(1, 4, 0.8), (2, 8, 1.2), (3, 6, 2.0), (4, 12, 1.0)] {
        let (text, areas) = one_sided_lamps(seed, lamps, distance);
        let scene = parse(&text);
        let settings = Settings {
            final_rays: 0,
            ..Settings::default()
        };
        let (hr, stats) = solve(&scene, &settings).unwrap();
        let ex = exact(&scene, 1200);
        let n = hr.len();
        let taken = |t: &ResultsTable| -> f64 {
            (0..40)
                .map(|i| {
                    let row = n - 40 + i;
                    (t.irradiance(row, 0)[0] + t.irradiance(row, 1)[0]) as f64 * areas[i] as f64
                })
                .sum()
        };
        let (got, want) = (taken(&hr), taken(&ex));
        let e = (got - want) / want;
        eprintln!(
            "seed {seed}: black cluster takes {got:.4} W, exact {want:.4} W ({:+.2}%)",
            100.0 * e
        );
        // Coarse links into the cluster may each be off by what epsilon allows (a thousandth
        // of the light leaving all surfaces); the side mix-up was 20% to 120% of its take.
        let emitted = 100.0 * 0.006 * lamps as f64;
        let allowed = 0.1 * want + 1e-3 * emitted;
        assert!(
            (got - want).abs() < allowed,
            "seed {seed}: {got} W vs exact {want} W ({:+.2}%)\n{text}",
            100.0 * e
        );
        let imbalance = stats.balance.relative_imbalance(0);
        assert!(
            imbalance.abs() < 0.01,
            "seed {seed}: imbalance {:+.3}%",
            100.0 * imbalance
        );
    }
}
