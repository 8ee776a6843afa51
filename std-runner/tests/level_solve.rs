//! The top level solved with its instances closed (issue 18, under construction) against
//! the same scene expanded: what each plant absorbs, what the soil receives, and the power
//! balance.

mod common;

use glam::{Quat, Vec3};
use hirad::generate::palette::{diffuse, two_sided};
use hirad::generate::shapes::{add_quad, frame};
use hirad::scene::{Cluster, InstanceOf, Original, Scene, Similarity, compile};
use hirad::solve::RayonExecutor;
use hirad::tables::{TableSettings, bake_original};
use hirad_core::hr::level_probe::solve_level;
use hirad_core::hr::{Instancing, Settings};
use hirad_core::image::{LightData, SceneView, SliceSource};
use hirad_core::sink::{PolygonResult, Sink};
use hirad_core::tables::closed::Received;

const RHO: [f32; 2] = [0.08, 0.45];
const RHO_BACK: [f32; 2] = [0.1, 0.4];
const TAU: [f32; 2] = [0.05, 0.4];
const SOIL: [f32; 2] = [0.1, 0.25];

/// A small plant: `leaves` square leaves of side 0.12 m around a vertical axis, rising and
/// turning.
fn plant(leaves: u32, m: u32) -> Cluster {
    let mut c = Cluster::named("plant");
    for k in 0..leaves {
        let a = k as f32 * 2.4;
        let centre = Vec3::new(0.08 * a.cos(), 0.08 * a.sin(), 0.05 + 0.06 * k as f32);
        let n = Vec3::new(0.6 * a.cos(), 0.6 * a.sin(), 0.8).normalize();
        let (u, v) = frame(n);
        let h = 0.06;
        add_quad(
            &mut c,
            [
                centre - u * h - v * h,
                centre + u * h - v * h,
                centre + u * h + v * h,
                centre - u * h + v * h,
            ],
            m,
        );
    }
    c
}

/// Soil of side `size` under a grid of `nx x ny` plants `spacing` apart, each turned.
fn field(nx: u32, ny: u32, spacing: f32, size: f32) -> Scene {
    let mut s = Scene::new(2);
    let soil = diffuse(&mut s, "soil", &SOIL);
    let leaf = two_sided(&mut s, "leaf", &RHO, &RHO_BACK, &TAU);
    s.originals.push(Original {
        name: "plant".into(),
        root: plant(7, leaf),
    });
    let h = 0.5 * size;
    debug_assert_eq!(s.materials.len(), 2);
    add_quad(
        &mut s.root,
        [
            Vec3::new(-h, -h, 0.0),
            Vec3::new(h, -h, 0.0),
            Vec3::new(h, h, 0.0),
            Vec3::new(-h, h, 0.0),
        ],
        soil,
    );
    for i in 0..nx {
        for j in 0..ny {
            let at = Vec3::new(
                (i as f32 - 0.5 * (nx - 1) as f32) * spacing,
                (j as f32 - 0.5 * (ny - 1) as f32) * spacing,
                0.0,
            );
            s.root.children.push(Cluster {
                instance: Some(InstanceOf {
                    original: 0,
                    exact: true,
                    transform: Similarity {
                        rotation: Quat::from_rotation_z(1.3 * (i * ny + j) as f32),
                        translation: at,
                        scale: 1.0,
                    },
                }),
                ..Cluster::default()
            });
        }
    }
    s.suns.push(LightData {
        towards: Vec3::new(0.4, 0.3, 0.85).normalize(),
        irradiance: [400.0, 350.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    });
    s
}

/// Polygons' absorbed power, in global-id order.
#[derive(Default)]
struct Absorbed {
    power: Vec<[f64; 2]>,
}

impl Sink for Absorbed {
    type Error = std::convert::Infallible;
    fn polygon(&mut self, p: &PolygonResult<'_>) -> Result<(), Self::Error> {
        let id = p.id as usize;
        let (rf, rb, t) = if id == 0 {
            (SOIL, [0.0; 2], [0.0; 2])
        } else {
            (RHO, RHO_BACK, TAU)
        };
        let mut a = [0.0f64; 2];
        for b in 0..2 {
            a[b] += (p.area * p.irradiance[0][b] * (1.0 - rf[b] - t[b])) as f64;
            if p.two_sided {
                a[b] += (p.area * p.irradiance[1][b] * (1.0 - rb[b] - t[b])) as f64;
            }
        }
        self.power.push(a);
        Ok(())
    }
}

fn tables_settings() -> TableSettings {
    common::quick_tables()
}

/// What each plant absorbs and what the soil absorbs, per band (W), and the stats: the
/// scene expanded, then its top level with the plants closed.
type Outcome = (Vec<[f64; 2]>, [f64; 2], hirad_core::hr::Stats);

fn solve_both(s: &Scene, exec: &mut RayonExecutor) -> (Outcome, Outcome) {
    let bytes = compile(s).unwrap();
    let view = SceneView::open(SliceSource(&bytes[..])).unwrap();
    let settings = Settings {
        epsilon: 2e-4,
        ..Settings::default()
    };
    let mut ws = vec![0u8; 256 << 20];
    let mut expanded = Absorbed::default();
    let full = solve_level(
        &view,
        &settings,
        Instancing::None,
        &mut ws,
        exec,
        &mut expanded,
        |_| {},
    )
    .unwrap();
    let per_plant = 7;
    let plants = (expanded.power.len() - 1) / per_plant;
    let mut want = vec![[0.0f64; 2]; plants];
    for (k, p) in expanded.power[1..].iter().enumerate() {
        for b in 0..2 {
            want[k / per_plant][b] += p[b];
        }
    }
    let mut level = Absorbed::default();
    let mut got = vec![[0.0f64; 2]; plants];
    let top = solve_level(
        &view,
        &settings,
        Instancing::Top,
        &mut ws,
        exec,
        &mut level,
        |l| {
            // By node: the scene's order, as the expanded plants'.
            let mut by_node: Vec<u32> = (0..l.instances()).collect();
            by_node.sort_by_key(|&i| l.instance(i).node);
            for (k, &i) in by_node.iter().enumerate() {
                let c = l.instance(i);
                let r = Received::over(&c.placed, c.received).unwrap();
                got[k] = [r.absorbed(0) as f64, r.absorbed(1) as f64];
            }
        },
    )
    .unwrap();
    assert_eq!(
        level.power.len(),
        1,
        "the level's own polygon only: the soil"
    );
    ((want, expanded.power[0], full), (got, level.power[0], top))
}

/// Plants apart from each other (boxes that do not overlap), under suns high and low: what
/// each closed plant absorbs is within 6% of what its expanded leaves absorb, the soil
/// within 1.5%, and the level's light balances within 1%.
#[test]
fn closed_plants_absorb_what_expanded_plants_do() {
    let mut exec = RayonExecutor::new(2).unwrap();
    let base = field(1, 1, 1.0, 3.0);
    let t = bake_original(&base, 0, &tables_settings(), &mut exec, &mut |_, _, _| {}).unwrap();
    let tables = t.to_scene();
    let mut worst = 0.0f64;
    for (nx, ny, spacing) in [(1u32, 1u32, 1.0f32), (2, 2, 0.6), (3, 1, 0.7)] {
        for sun in [Vec3::new(0.4, 0.3, 0.85), Vec3::new(-0.6, 0.25, 0.5)] {
            let mut s = field(nx, ny, spacing, 3.0);
            s.suns[0].towards = sun.normalize();
            s.tables = vec![tables.clone()];
            let ((want, soil_want, full), (got, soil_got, top)) = solve_both(&s, &mut exec);
            let case = format!("{nx} x {ny} plants {spacing} m apart, sun {sun}");
            assert_eq!(got.len(), (nx * ny) as usize, "{case}");
            for b in 0..2 {
                for (k, (w, g)) in want.iter().zip(got.iter()).enumerate() {
                    let e = g[b] / w[b] - 1.0;
                    worst = worst.max(e.abs());
                    assert!(
                        e.abs() <= 0.06,
                        "{case}: plant {k} band {b}: {} vs {}",
                        g[b],
                        w[b]
                    );
                }
                let e = soil_got[b] / soil_want[b] - 1.0;
                assert!(
                    e.abs() <= 0.015,
                    "{case}: soil band {b}: {} vs {}",
                    soil_got[b],
                    soil_want[b]
                );
                assert!(full.balance.relative_imbalance(b).abs() <= 0.01, "{case}");
                assert!(
                    top.balance.relative_imbalance(b).abs() <= 0.01,
                    "{case}: closed imbalance {}",
                    top.balance.relative_imbalance(b)
                );
                // What the suns bring is the same light, however it is taken in.
                let d = top.balance.direct[b] / full.balance.direct[b] - 1.0;
                assert!(d.abs() <= 0.01, "{case}: direct {d}");
            }
        }
    }
    println!("worst plant error {:.2}%", 100.0 * worst);
}

/// True when `a` and `b` absorb the same power in both bands, bit for bit.
fn same_bits(a: &Absorbed, b: &Absorbed) -> bool {
    a.power.len() == b.power.len()
        && a.power
            .iter()
            .zip(&b.power)
            .all(|(x, y)| x.iter().zip(y).all(|(p, q)| p.to_bits() == q.to_bits()))
}

/// Every polygon's global id once, in order, and what it absorbs.
#[derive(Default)]
struct ById {
    ids: Vec<u64>,
    absorbed: Absorbed,
}

impl Sink for ById {
    type Error = std::convert::Infallible;
    fn polygon(&mut self, p: &PolygonResult<'_>) -> Result<(), Self::Error> {
        self.ids.push(p.id);
        self.absorbed.polygon(p)
    }
}

/// Relative errors of `got` against `want`, polygon by polygon, band by band, for polygons
/// that absorb at least `floor` of the largest.
fn relative_errors(want: &[[f64; 2]], got: &[[f64; 2]], floor: f64) -> Vec<f64> {
    let top = want
        .iter()
        .flat_map(|w| w.iter().copied())
        .fold(0.0f64, f64::max);
    let mut e = Vec::new();
    for (w, g) in want.iter().zip(got) {
        for b in 0..2 {
            if w[b] >= floor * top {
                e.push((g[b] / w[b] - 1.0).abs());
            }
        }
    }
    e.sort_by(f64::total_cmp);
    e
}

/// Hierarchical instantiation against the scene expanded, plants apart and interpenetrating:
/// every polygon once, in global-id order, the same on one thread as on two; each plant's
/// absorbed power within 4%, the soil's within 1.5%; per leaf, the median error within
/// 1.5%, nine in ten within 6% and the worst within 15% (closed neighbours shade with their
/// own polygons, trade light through the exchange, and are read by the final gather through
/// the stack).
#[test]
fn hierarchical_instantiation_gives_every_polygon_its_light() {
    let mut exec = RayonExecutor::new(2).unwrap();
    let base = field(1, 1, 1.0, 3.0);
    let t = bake_original(&base, 0, &tables_settings(), &mut exec, &mut |_, _, _| {}).unwrap();
    let tables = t.to_scene();
    let mut all = Vec::new();
    let mut worst_plant = 0.0f64;
    for (nx, ny, spacing, sun) in [
        (1u32, 1u32, 1.0f32, Vec3::new(0.4, 0.3, 0.85)),
        (3, 2, 0.6, Vec3::new(0.4, 0.3, 0.85)),
        (2, 2, 0.7, Vec3::new(-0.6, 0.25, 0.5)),
        // Interpenetrating: boxes of 0.34 m, 0.25 m apart, as a canopy's plants.
        (3, 3, 0.25, Vec3::new(-0.6, 0.25, 0.5)),
    ] {
        let mut s = field(nx, ny, spacing, 3.0);
        s.suns[0].towards = sun.normalize();
        s.tables = vec![tables.clone()];
        let bytes = compile(&s).unwrap();
        let view = SceneView::open(SliceSource(&bytes[..])).unwrap();
        let settings = Settings {
            epsilon: 2e-4,
            ..Settings::default()
        };
        let mut ws = vec![0u8; 256 << 20];
        let mut expanded = ById::default();
        hirad_core::hr::solve(
            &view,
            &settings,
            &mut ws,
            None::<&hirad_core::visibility::Unoccluded>,
            &mut exec,
            &mut hirad_core::hr::NoProgress,
            &mut expanded,
        )
        .unwrap();
        let mut hi = ById::default();
        let stats = hirad_core::hr::solve_hi(
            &view,
            &settings,
            hirad_core::hr::Inline::NONE,
            &mut ws,
            &mut exec,
            &mut hirad_core::hr::NoProgress,
            &mut hi,
        )
        .unwrap();
        let case = format!("{nx} x {ny} plants {spacing} m apart, sun {sun}");
        // The same on one thread, bit for bit.
        let mut one = ById::default();
        hirad_core::hr::solve_hi(
            &view,
            &settings,
            hirad_core::hr::Inline::NONE,
            &mut ws,
            &mut RayonExecutor::new(1).unwrap(),
            &mut hirad_core::hr::NoProgress,
            &mut one,
        )
        .unwrap();
        assert_eq!(one.ids, hi.ids, "{case}");
        assert!(
            same_bits(&one.absorbed, &hi.absorbed),
            "{case}: one thread and two differ"
        );
        assert_eq!(
            hi.ids,
            (0..expanded.ids.len() as u64).collect::<Vec<_>>(),
            "{case}"
        );
        assert_eq!(stats.polygons, expanded.ids.len() as u64, "{case}");
        let (want, got) = (&expanded.absorbed.power, &hi.absorbed.power);
        for b in 0..2 {
            let e = got[0][b] / want[0][b] - 1.0;
            assert!(e.abs() <= 0.015, "{case}: soil band {b}: {e}");
        }
        let per = 7;
        for plant in 0..(nx * ny) as usize {
            let range = 1 + plant * per..1 + (plant + 1) * per;
            for b in 0..2 {
                let w: f64 = want[range.clone()].iter().map(|p| p[b]).sum();
                let g: f64 = got[range.clone()].iter().map(|p| p[b]).sum();
                worst_plant = worst_plant.max((g / w - 1.0).abs());
                assert!(
                    (g / w - 1.0).abs() <= 0.04,
                    "{case}: plant {plant} band {b}: {g} vs {w}"
                );
            }
        }
        all.extend(relative_errors(&want[1..], &got[1..], 0.02));
    }
    all.sort_by(f64::total_cmp);
    let median = all[all.len() / 2];
    let p90 = all[all.len() * 9 / 10];
    let worst = all[all.len() - 1];
    println!(
        "leaves: median error {:.2}%, 90th percentile {:.2}%, worst {:.2}%; worst plant {:.2}%",
        100.0 * median,
        100.0 * p90,
        100.0 * worst,
        100.0 * worst_plant
    );
    // Measured at a2765f8: 0.67%, 3.6%, 15.6% (a leaf of the interpenetrating plants; 14.3%
    // on another leaf before an opened level's rays counted its binned links' light as
    // gathered, with median 0.90% and 90th percentile 4.3%).
    assert!(median <= 0.01, "median {median}");
    assert!(p90 <= 0.05, "90th percentile {p90}");
    assert!(worst <= 0.18, "worst {worst}");
}

/// Between the clusters that hold closed instances no link can carry light before they open
/// (see `refine::must_open`): such pairs are opened at once, never made as links only to be
/// split again. The top level's links at their peak are then the links it keeps, give or
/// take the ordinary refinement's (a canopy of 2,400 plants made 495,407 for 35,271 kept).
#[test]
fn links_between_clusters_of_closed_instances_are_never_made_to_be_split() {
    let mut exec = RayonExecutor::new(2).unwrap();
    let base = field(1, 1, 1.0, 3.0);
    let t = bake_original(&base, 0, &tables_settings(), &mut exec, &mut |_, _, _| {}).unwrap();
    let tables = t.to_scene();
    // Enough plants that the pairs of their clusters outnumber the links kept (without the
    // rule 40 x 40 plants peaked at 207,327 links for 3,452 kept, after 810,824 evaluations).
    for (nx, ny, spacing) in [(40u32, 40u32, 0.3f32), (12, 90, 0.25)] {
        let mut s = field(nx, ny, spacing, 0.3 * nx.max(ny) as f32 + 1.0);
        s.tables = vec![tables.clone()];
        let bytes = compile(&s).unwrap();
        let view = SceneView::open(SliceSource(&bytes[..])).unwrap();
        let settings = Settings {
            epsilon: 1e-2,
            ..Settings::default()
        };
        let mut ws = vec![0u8; 256 << 20];
        let top = solve_level(
            &view,
            &settings,
            Instancing::Top,
            &mut ws,
            &mut exec,
            &mut Absorbed::default(),
            |_| {},
        )
        .unwrap();
        assert!(top.links > 0);
        assert!(
            top.peak_links as f64 <= 1.5 * top.links as f64,
            "{nx} x {ny} plants: {} links at the peak for {} kept",
            top.peak_links,
            top.links
        );
        assert!(
            top.evaluations as f64 <= 1.5 * top.links as f64,
            "{nx} x {ny} plants: {} evaluations for {} links",
            top.evaluations,
            top.links
        );
    }
}

/// hi's own plan (`plan_hi`): its least opens every level (the solve at that size runs to
/// its end), half of it is refused with no more than the plan's least named as needed, and
/// its suggestion, which the command line takes without `--memory`, lets the fields refine
/// as far as a huge workspace does: the same absorbed power, bit for bit. Swept over fields
/// of 4 to 36 plants.
#[test]
fn the_hi_plan_is_what_the_solve_needs() {
    use hirad_core::hr::{HrError, Inline, SolveError, plan_hi, plan_hi_scratch_bytes, solve_hi};
    let mut exec = RayonExecutor::new(2).unwrap();
    let base = field(1, 1, 1.0, 3.0);
    let t = bake_original(&base, 0, &tables_settings(), &mut exec, &mut |_, _, _| {}).unwrap();
    let tables = t.to_scene();
    let settings = Settings::default();
    let mut huge = vec![0u8; 256 << 20];
    let mut last = 0u64;
    for (nx, ny, spacing) in [(2u32, 2u32, 0.7f32), (4, 3, 0.5), (6, 6, 0.3)] {
        let mut s = field(nx, ny, spacing, 3.0);
        s.tables = vec![tables.clone()];
        let bytes = compile(&s).unwrap();
        let view = SceneView::open(SliceSource(&bytes[..])).unwrap();
        let mut scratch = vec![0u8; plan_hi_scratch_bytes(&view)];
        let plan = plan_hi(&view, &settings, Inline::NONE, &mut scratch).unwrap();
        let case = format!("{nx} x {ny} plants: {plan:?}");
        println!("{case}");
        assert!(plan.min_bytes < plan.suggested_bytes, "{case}");
        assert!(
            plan.suggested_bytes >= plan.top_level_bytes + plan.children_bytes,
            "{case}"
        );
        // More plants, more closed instances in the top level: a larger plan.
        assert!(plan.min_bytes > last, "{case}");
        last = plan.min_bytes;
        let mut want = ById::default();
        solve_hi(
            &view,
            &settings,
            Inline::NONE,
            &mut huge,
            &mut exec,
            &mut hirad_core::hr::NoProgress,
            &mut want,
        )
        .unwrap();
        let mut run = |size: u64| {
            let mut ws = vec![0u8; size as usize];
            let mut got = ById::default();
            solve_hi(
                &view,
                &settings,
                Inline::NONE,
                &mut ws,
                &mut exec,
                &mut hirad_core::hr::NoProgress,
                &mut got,
            )
            .map(|stats| (stats, got))
        };
        let (_, least) = run(plan.min_bytes).unwrap_or_else(|e| panic!("{case}: at least: {e:?}"));
        assert_eq!(least.ids, want.ids, "{case}");
        match run(plan.min_bytes / 2) {
            Err(SolveError::Hr(HrError::WorkspaceTooSmall { needed })) => {
                assert!(
                    needed > plan.min_bytes / 2 && needed <= plan.min_bytes,
                    "{case}: needs {needed}"
                );
            }
            other => panic!("{case}: half the least: {:?}", other.map(|r| r.0)),
        }
        let (stats, got) = run(plan.suggested_bytes).unwrap();
        assert!(!stats.budget_limited, "{case}");
        assert_eq!(got.ids, want.ids, "{case}");
        assert!(
            same_bits(&got.absorbed, &want.absorbed),
            "{case}: the suggestion and a huge workspace differ"
        );
    }
}
