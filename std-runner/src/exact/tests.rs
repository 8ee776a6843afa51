//! Unit tests of the reference solver on scenes built in code: meshing within budget,
//! translucent leaves, suns and shadows, determinism across thread counts, refusals.

use super::*;
use crate::scene::{Cluster, InstanceOf, Material, MaterialData, Original, Similarity, light};
use glam::{Quat, Vec3};
use hirad_core::sink::{PatchResult, PolygonResult};
use std::convert::Infallible;

/// One polygon's results, as the sink received them.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Got {
    pub area: f32,
    pub two_sided: bool,
    pub radiosity: [Vec<f32>; 2],
    pub irradiance: [Vec<f32>; 2],
    /// Per patch: area and radiosity `[front, back]`.
    pub patches: Vec<(f32, [Vec<f32>; 2])>,
}

/// Keeps everything, and checks the order of the calls.
#[derive(Default)]
struct Keep {
    polygons: Vec<Got>,
    pending: Vec<(f32, [Vec<f32>; 2])>,
}

impl Sink for Keep {
    type Error = Infallible;

    fn patch(&mut self, p: &PatchResult<'_>) -> Result<(), Infallible> {
        assert_eq!(p.id, self.polygons.len() as u64);
        self.pending.push((
            mesh::area_of(p.corners),
            [p.radiosity[0].to_vec(), p.radiosity[1].to_vec()],
        ));
        Ok(())
    }

    fn polygon(&mut self, p: &PolygonResult<'_>) -> Result<(), Infallible> {
        assert_eq!(p.id, self.polygons.len() as u64);
        self.polygons.push(Got {
            area: p.area,
            two_sided: p.two_sided,
            radiosity: [p.radiosity[0].to_vec(), p.radiosity[1].to_vec()],
            irradiance: [p.irradiance[0].to_vec(), p.irradiance[1].to_vec()],
            patches: std::mem::take(&mut self.pending),
        });
        Ok(())
    }
}

fn material(name: &str, f: impl FnOnce(&mut MaterialData)) -> Material {
    let mut data = MaterialData::black(1);
    f(&mut data);
    Material {
        name: name.into(),
        data,
    }
}

/// Adds the square `[x0, x0 + s] x [y0, y0 + s]` at height `z`, front up or down.
fn square(c: &mut Cluster, x0: f32, y0: f32, s: f32, z: f32, up: bool, mat: u32) {
    let mut v = [
        c.vertex(Vec3::new(x0, y0, z)),
        c.vertex(Vec3::new(x0 + s, y0, z)),
        c.vertex(Vec3::new(x0 + s, y0 + s, z)),
        c.vertex(Vec3::new(x0, y0 + s, z)),
    ];
    if !up {
        v.reverse();
    }
    c.polygons
        .push(crate::scene::quad(v[0], v[1], v[2], v[3], mat));
}

pub(super) fn solve(scene: &Scene, settings: &ExactSettings) -> (Vec<Got>, ExactReport) {
    let mut keep = Keep::default();
    let report = solve_exact_obvhs(scene, settings, &mut keep).unwrap();
    (keep.polygons, report)
}

pub(super) fn small(max_elements: usize) -> ExactSettings {
    ExactSettings {
        max_elements,
        ..ExactSettings::default()
    }
}

/// Form factor between coaxial parallel unit squares `d` apart (closed form).
fn parallel_unit_squares(d: f64) -> f64 {
    let x = 1.0 / d;
    let s = (1.0 + x * x).sqrt();
    let pi = std::f64::consts::PI;
    2.0 / (pi * x * x)
        * (((1.0 + x * x) / s.hypot(x)).ln() + 2.0 * x * s * (x / s).atan() - 2.0 * x * x.atan())
}

#[test]
fn closed_form_of_the_plates() {
    assert!((parallel_unit_squares(1.0) - 0.199825).abs() < 1e-6);
}

/// Emitter (z = 0, up, E = 1), a leaf at z = 0.5 (front down), a black receiver at z = 1.
fn leaf_scene(tau: f32) -> Scene {
    let mut s = Scene::new(1);
    s.materials = vec![
        material("lamp", |m| m.emit_front[0] = 1.0),
        material("leaf", |m| {
            m.two_sided = true;
            m.rho_front[0] = 0.3;
            m.rho_back[0] = 0.2;
            m.tau[0] = tau;
        }),
        material("black", |_| {}),
    ];
    square(&mut s.root, 0., 0., 1., 0.0, true, 0);
    square(&mut s.root, 0., 0., 1., 0.5, false, 1);
    square(&mut s.root, 0., 0., 1., 1.0, false, 2);
    s
}

#[test]
fn a_translucent_leaf_passes_tau_times_its_irradiance_to_its_back() {
    let (got, report) = solve(&leaf_scene(0.4), &small(200));
    assert_eq!(report.polygons, 3);
    assert!(
        report.elements <= 200 && report.elements > 100,
        "{report:?}"
    );
    let leaf = &got[1];
    assert!(leaf.two_sided && !got[0].two_sided);
    assert!(got[0].radiosity[1].is_empty() && got[0].irradiance[1].is_empty());
    // The leaf's front sees the lamp as plates 0.5 apart do.
    let h_front = leaf.irradiance[0][0] as f64;
    let f = parallel_unit_squares(0.5);
    assert!((h_front / f - 1.0).abs() < 0.005, "{h_front} vs {f}");
    // Its back faces a black receiver: no irradiance; it shows tau x the front's.
    assert_eq!(leaf.irradiance[1][0], 0.0);
    let b_back = leaf.radiosity[1][0] as f64;
    assert!((b_back / (0.4 * h_front) - 1.0).abs() < 1e-5, "{b_back}");
    // The front reflects rho_front (the lamp is black, nothing else lights the front).
    let b_front = leaf.radiosity[0][0] as f64;
    assert!((b_front / (0.3 * h_front) - 1.0).abs() < 1e-5, "{b_front}");
    // The receiver only sees the leaf's back (the lamp is hidden behind the leaf); the
    // closed form with the leaf's mean is close (its radiosity varies a little).
    let h_recv = got[2].irradiance[0][0] as f64;
    assert!((h_recv / (f * b_back) - 1.0).abs() < 0.05, "{h_recv}");
}

#[test]
fn an_opaque_leaf_casts_a_full_shadow() {
    let (got, _) = solve(&leaf_scene(0.0), &small(200));
    // Rays that graze the leaf's edges may pass: a tiny remainder at most.
    assert!(got[2].irradiance[0][0] < 1e-3, "{:?}", got[2]);
    assert_eq!(got[1].radiosity[1][0], 0.0);
}

/// A 2 x 2 floor (front up, grey), and optionally a black 0.5 x 0.5 blocker at height 1.
fn sun_scene(towards: Vec3, blocker: bool) -> Scene {
    let mut s = Scene::new(1);
    s.materials = vec![
        material("floor", |m| m.rho_front[0] = 0.5),
        material("black", |_| {}),
    ];
    square(&mut s.root, -1., -1., 2., 0.0, true, 0);
    if blocker {
        square(&mut s.root, -0.25, -0.25, 0.5, 1.0, true, 1);
    }
    s.suns.push(light(towards, &[800.0]));
    s
}

#[test]
fn a_sun_lights_a_floor_with_its_cosine_and_a_blocker_shades_it() {
    let towards = Vec3::new(0.6, 0.0, 0.8);
    let (got, report) = solve(&sun_scene(towards, false), &small(256));
    assert!(report.rays > 0);
    for (_, r) in &got[0].patches {
        assert!((r[0][0] - 0.5 * 800.0 * 0.8).abs() < 1e-3, "{r:?}");
    }
    assert!((got[0].irradiance[0][0] - 640.0).abs() < 1e-3);
    // From below the horizon a one-sided floor gets nothing.
    let (got, _) = solve(&sun_scene(-towards, false), &small(64));
    assert_eq!(got[0].irradiance[0][0], 0.0);
    // The blocker's shadow covers its own area (0.25 of 4 m^2), shifted by the sun.
    let (got, _) = solve(&sun_scene(towards, true), &small(1024));
    let h = got[0].irradiance[0][0] as f64;
    let expect = 640.0 * (1.0 - 0.25 / 4.0);
    assert!((h / expect - 1.0).abs() < 0.01, "{h} vs {expect}");
    let dark = got[0]
        .patches
        .iter()
        .filter(|(_, r)| r[0][0] == 0.0)
        .count();
    assert!(dark > 0);
}

#[test]
fn a_shadow_edge_inside_an_element_is_resolved() {
    // A vertical sun and the blocker moved so that its shadow, [-0.13, 0.37]^2, cuts each of
    // the floor's four elements in a corner: the lit fractions are exact areas, which a few
    // quadrature points per element would give as thirds or quarters.
    let mut s = Scene::new(1);
    s.materials = vec![
        material("floor", |m| m.rho_front[0] = 0.5),
        material("black", |_| {}),
    ];
    square(&mut s.root, -1., -1., 2., 0.0, true, 0);
    square(&mut s.root, -0.13, -0.13, 0.5, 1.0, true, 1);
    s.suns.push(light(Vec3::Z, &[800.0]));
    let (got, _) = solve(&s, &small(5));
    let mut b: Vec<f32> = got[0].patches.iter().map(|(_, r)| r[0][0]).collect();
    b.sort_by(f32::total_cmp);
    let mut expect: Vec<f32> = [0.13f32 * 0.13, 0.13 * 0.37, 0.13 * 0.37, 0.37 * 0.37]
        .iter()
        .map(|shade| 0.5 * 800.0 * (1.0 - shade))
        .collect();
    expect.sort_by(f32::total_cmp);
    assert_eq!(b.len(), 4, "{b:?}");
    for (g, e) in b.iter().zip(&expect) {
        assert!((g / e - 1.0).abs() < 0.01, "{b:?} vs {expect:?}");
    }
}

#[test]
fn a_two_sided_leaf_lit_from_behind_receives_on_its_back() {
    let mut s = Scene::new(1);
    s.materials = vec![material("leaf", |m| {
        m.two_sided = true;
        m.rho_front[0] = 0.1;
        m.rho_back[0] = 0.3;
        m.tau[0] = 0.5;
    })];
    square(&mut s.root, 0., 0., 1., 0.0, true, 0);
    s.sky.push(light(Vec3::new(0.0, -0.6, -0.8), &[100.0]));
    let (got, _) = solve(&s, &small(16));
    let g = &got[0];
    assert_eq!(g.irradiance[0][0], 0.0);
    assert!((g.irradiance[1][0] - 80.0).abs() < 1e-4);
    assert!((g.radiosity[1][0] - 24.0).abs() < 1e-4);
    assert!((g.radiosity[0][0] - 40.0).abs() < 1e-4);
}

#[test]
fn elements_stay_within_budget_and_tile_their_polygons() {
    // A big and a small square: the big one gets the finer split (equal element areas).
    let mut s = Scene::new(1);
    s.materials = vec![material("lamp", |m| m.emit_front[0] = 1.0)];
    square(&mut s.root, 0., 0., 4., 0.0, true, 0);
    square(&mut s.root, 0., 0., 1., 1.0, false, 0);
    let (got, report) = solve(&s, &small(100));
    assert!(report.elements <= 100);
    assert_eq!(got[0].patches.len(), 64);
    assert_eq!(got[1].patches.len(), 4);
    for g in &got {
        let sum: f32 = g.patches.iter().map(|p| p.0).sum();
        assert!((sum / g.area - 1.0).abs() < 1e-5);
    }
    // Fewer elements than polygons is not possible: each polygon is kept whole.
    let (got, report) = solve(&s, &small(1));
    assert_eq!((report.elements, got.len()), (2, 2));
}

#[test]
fn identical_results_with_one_and_two_threads() {
    let mut s = leaf_scene(0.3);
    s.suns
        .push(light(Vec3::new(0.3, 0.2, 0.9).normalize(), &[50.0]));
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| solve(&s, &small(300)))
    };
    let (a, ra) = run(1);
    let (b, rb) = run(2);
    assert_eq!(a, b);
    let bits = |g: &[Got]| -> Vec<u32> {
        g.iter()
            .flat_map(|p| p.patches.iter().flat_map(|(_, r)| r.iter().flatten()))
            .map(|v| v.to_bits())
            .collect()
    };
    assert_eq!(bits(&a), bits(&b));
    assert_eq!(
        (ra.rays, ra.entries, ra.iterations),
        (rb.rays, rb.entries, rb.iterations)
    );
}

#[test]
fn instances_are_expanded_in_global_id_order() {
    // An original with one emitting square, placed twice facing a black floor.
    let mut s = Scene::new(1);
    s.materials = vec![
        material("lamp", |m| m.emit_front[0] = 2.0),
        material("black", |_| {}),
    ];
    let mut lamp = Cluster::named("lamp");
    square(&mut lamp, 0., 0., 1., 0.0, false, 0);
    s.originals.push(Original {
        name: "lamp".into(),
        root: lamp,
    });
    square(&mut s.root, 0., 0., 1., 0.0, true, 1);
    for (k, z) in [1.0f32, 2.0].into_iter().enumerate() {
        s.root.children.push(Cluster {
            name: Some(format!("lamp{k}")),
            instance: Some(InstanceOf {
                original: 0,
                exact: true,
                transform: Similarity {
                    rotation: Quat::IDENTITY,
                    translation: Vec3::new(0., 0., z),
                    scale: 1.0,
                },
            }),
            ..Cluster::default()
        });
    }
    let (got, report) = solve(&s, &small(48));
    assert_eq!(report.polygons, 3);
    // Floor first; the lower lamp hides the upper one.
    assert!(
        (got[0].irradiance[0][0] as f64 / (2.0 * parallel_unit_squares(1.0)) - 1.0).abs() < 0.01
    );
    assert_eq!(got[1].radiosity[0][0], 2.0);
    assert_eq!(got[2].irradiance[0][0], 0.0);
}

#[test]
fn refuses_bad_settings_huge_scenes_and_reports_no_convergence() {
    let mut keep = Keep::default();
    let s = leaf_scene(0.2);
    let bad = ExactSettings {
        max_elements: 0,
        ..ExactSettings::default()
    };
    assert!(matches!(
        solve_exact_obvhs(&s, &bad, &mut keep),
        Err(ExactError::Settings(_))
    ));
    let bad = ExactSettings {
        rays: MAX_RAYS + 1,
        ..ExactSettings::default()
    };
    assert!(matches!(
        solve_exact_obvhs(&s, &bad, &mut keep),
        Err(ExactError::Settings(_))
    ));
    // 201 instances of 100 squares: more polygons than the solver takes.
    let mut big = Scene::new(1);
    big.materials = vec![material("grey", |m| m.rho_front[0] = 0.5)];
    let mut o = Cluster::named("row");
    for k in 0..100 {
        square(&mut o, k as f32, 0., 1., 0., true, 0);
    }
    big.originals.push(Original {
        name: "row".into(),
        root: o,
    });
    for k in 0..201 {
        big.root.children.push(Cluster {
            instance: Some(InstanceOf {
                original: 0,
                exact: true,
                transform: Similarity {
                    rotation: Quat::IDENTITY,
                    translation: Vec3::new(0., 2.0 * k as f32, 0.),
                    scale: 1.0,
                },
            }),
            ..Cluster::default()
        });
    }
    let e = solve_exact_obvhs(&big, &ExactSettings::default(), &mut keep).unwrap_err();
    assert!(matches!(e, ExactError::TooLarge { .. }), "{e}");
    assert!(e.to_string().contains("20000"), "{e}");
    // A bright closed box with one sweep allowed.
    let one = ExactSettings {
        max_iterations: 1,
        max_elements: 50,
        ..ExactSettings::default()
    };
    let e = solve_exact_obvhs(&leaf_scene(0.4), &one, &mut keep).unwrap_err();
    assert!(
        matches!(e, ExactError::NotConverged { iterations: 1, .. }),
        "{e}"
    );
    // An invalid scene is refused with the core's message.
    let mut broken = leaf_scene(0.4);
    broken.materials[0].data.rho_front[0] = 2.0;
    let e = solve_exact_obvhs(&broken, &ExactSettings::default(), &mut keep).unwrap_err();
    assert!(matches!(e, ExactError::Scene(_)), "{e}");
}

#[test]
fn pair_culling_gives_the_same_matrix_as_casting_every_ray() {
    // The Cornell box (blocks and a light that cast shadows), three bands.
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/cornell_box.hir");
    let scene = crate::files::load_scene(&path).unwrap().scene;
    let settings = small(200);
    let (culled, rc) = solve(&scene, &settings);
    assert!(rc.clear_pairs > 0);
    let m = Mesh::build::<Infallible>(&scene, &settings).unwrap();
    let polygons: Vec<&[Vec3]> = m.polygons.iter().map(|p| p.corners()).collect();
    let vis = ObvhsVisibility::new(&polygons).unwrap();
    let mut keep = Keep::default();
    let rp = solve_exact(&scene, &settings, &vis, &mut keep).unwrap();
    assert_eq!(keep.polygons, culled);
    assert_eq!(rp.clear_pairs, 0);
    assert!(rp.rays > rc.rays);
    assert_eq!((rp.entries, rp.iterations), (rc.entries, rc.iterations));
}
