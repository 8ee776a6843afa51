//! Lamps around an opened instance (issue 18): the contents of a closed instance, once
//! opened, take the light of a small emitter of the levels around polygon by polygon, as
//! the expanded scene's polygons do. The reference is a double integral of the form factor
//! from each polygon to the lamp with visibility by an independent segment-quad test; it
//! shares no code with the solver.

mod common;

use glam::{DVec3, Quat, Vec3};
use hirad::generate::palette::{diffuse, emitter};
use hirad::generate::shapes::{add_quad, frame};
use hirad::scene::{Cluster, InstanceOf, Original, Scene, Similarity, compile};
use hirad::solve::{RayonExecutor, world_polygons};
use hirad::tables::bake_original;
use hirad_core::hr::{NoProgress, Settings, solve_hi};
use hirad_core::image::{SceneView, SliceSource};
use hirad_core::sink::{PolygonResult, Sink};

/// The lamp's exitance per band (W/m^2).
const LAMP: [f32; 2] = [1000.0, 400.0];
/// Side of a piece's small squares (m).
const PIECE: f32 = 0.08;

/// A square of side `side` centred at `c` whose front faces `n`.
fn square(c: Vec3, n: Vec3, side: f32) -> [Vec3; 4] {
    let (u, v) = frame(n);
    let (u, v) = if u.cross(v).dot(n) > 0.0 {
        (u, v)
    } else {
        (v, u)
    };
    let h = 0.5 * side;
    [
        c - u * h - v * h,
        c + u * h - v * h,
        c + u * h + v * h,
        c - u * h + v * h,
    ]
}

/// A piece of furniture in small: four black squares facing up, sideways, askew and down,
/// apart enough that the lamp sees each of them whole or in part.
fn piece(m: u32) -> Cluster {
    let mut c = Cluster::named("piece");
    for (at, n) in [
        (Vec3::new(0.0, 0.0, 0.0), Vec3::Z),
        (Vec3::new(0.15, 0.0, 0.05), Vec3::X),
        (Vec3::new(0.0, 0.15, 0.08), Vec3::new(0.0, -0.7, 0.7)),
        (Vec3::new(-0.12, -0.06, 0.12), Vec3::new(-0.6, 0.3, 0.74)),
        (Vec3::new(0.05, -0.14, 0.02), -Vec3::Y),
    ] {
        add_quad(&mut c, square(at, n.normalize(), PIECE), m);
    }
    c
}

fn instance(original: usize, transform: Similarity) -> Cluster {
    Cluster {
        instance: Some(InstanceOf {
            original,
            exact: true,
            transform,
        }),
        ..Cluster::default()
    }
}

fn place(at: Vec3, turn: f32) -> Similarity {
    Similarity {
        rotation: Quat::from_rotation_z(turn),
        translation: at,
        scale: 1.0,
    }
}

/// A room in small: `grid x grid` lamps of side `lamp` facing down at height `height` (one
/// in the middle, or spread over 2.4 m x 2.4 m), pieces around under them (or, `nested`,
/// stands of two pieces each: the lamps two levels out), and a black board in the top level
/// that shades part of them. The lamps are the first polygons, the board the next.
fn room(lamp: f32, height: f32, grid: u32, nested: bool) -> Scene {
    let mut s = Scene::new(2);
    let black = diffuse(&mut s, "black", &[0.0, 0.0]);
    let light = emitter(&mut s, "lamp", &[0.0, 0.0], &LAMP);
    s.originals.push(Original {
        name: "piece".into(),
        root: piece(black),
    });
    if nested {
        let mut stand = Cluster::named("stand");
        stand
            .children
            .push(instance(0, place(Vec3::new(0.0, 0.0, 0.0), 0.0)));
        stand
            .children
            .push(instance(0, place(Vec3::new(0.1, 0.45, 0.1), 2.0)));
        s.originals.push(Original {
            name: "stand".into(),
            root: stand,
        });
    }
    for i in 0..grid * grid {
        let at = |k: u32| {
            if grid == 1 {
                0.0
            } else {
                -1.2 + 2.4 * k as f32 / (grid - 1) as f32
            }
        };
        add_quad(
            &mut s.root,
            square(
                Vec3::new(at(i % grid), at(i / grid), height),
                -Vec3::Z,
                lamp,
            ),
            light,
        );
    }
    // A quarter of the way down from the lamp, off to one side: its shadow falls on some
    // pieces.
    add_quad(
        &mut s.root,
        square(Vec3::new(0.3, 0.1, 0.75 * height), -Vec3::Z, 0.3),
        black,
    );
    let original = if nested { 1 } else { 0 };
    for (k, (x, y)) in [
        (0.0f32, 0.0f32),
        (0.6, 0.2),
        (-0.5, 0.4),
        (0.3, -0.7),
        (0.9, 0.5),
        (-0.8, -0.6),
    ]
    .into_iter()
    .enumerate()
    {
        let z = 0.1 * (k % 3) as f32;
        s.root.children.push(instance(
            original,
            place(Vec3::new(x, y, z), 1.3 * k as f32),
        ));
    }
    s
}

fn d(v: Vec3) -> DVec3 {
    DVec3::new(v.x as f64, v.y as f64, v.z as f64)
}

/// True when the segment `a..b` crosses the quad `q` strictly between its ends.
fn crosses(a: DVec3, b: DVec3, q: &[DVec3]) -> bool {
    let n = (q[1] - q[0]).cross(q[2] - q[0]);
    let (da, db) = ((a - q[0]).dot(n), (b - q[0]).dot(n));
    if da * db >= 0.0 {
        return false;
    }
    let t = da / (da - db);
    let p = a + (b - a) * t;
    (0..q.len()).all(|i| (q[(i + 1) % q.len()] - q[i]).cross(p - q[i]).dot(n) >= 0.0)
}

/// Irradiance per band on the front of polygon `i` from the lamps (the first `lamps`
/// polygons): the lamps' exitance times the form factor by the midpoint rule on `n x n`
/// cells of the polygon and `m x m` of each lamp, a cell pair counted when the segment
/// between them crosses no polygon but the lamps (with `occlude`).
fn reference(
    polys: &[Vec<DVec3>],
    lamps: usize,
    i: usize,
    n: usize,
    m: usize,
    occlude: bool,
) -> [f64; 2] {
    let cell = |q: &[DVec3], k: usize, a: usize, b: usize| {
        let (u, v) = ((a as f64 + 0.5) / k as f64, (b as f64 + 0.5) / k as f64);
        q[0] + (q[1] - q[0]) * u + (q[3] - q[0]) * v
    };
    let normal = |q: &[DVec3]| (q[1] - q[0]).cross(q[3] - q[0]).normalize();
    let area = |q: &[DVec3]| (q[1] - q[0]).cross(q[3] - q[0]).length();
    let p = &polys[i];
    let np = normal(p);
    let mut f = 0.0;
    for l in &polys[..lamps] {
        let nl = normal(l);
        let da = area(l) / (m * m) as f64;
        for a in 0..n {
            for b in 0..n {
                let x = cell(p, n, a, b);
                for c in 0..m {
                    for e in 0..m {
                        let y = cell(l, m, c, e);
                        let r = y - x;
                        let r2 = r.length_squared();
                        let (cp, cl) = (np.dot(r), -nl.dot(r));
                        if cp <= 0.0 || cl <= 0.0 {
                            continue;
                        }
                        let blocked = occlude
                            && polys
                                .iter()
                                .enumerate()
                                .any(|(j, q)| j != i && j >= lamps && crosses(x, y, q));
                        if !blocked {
                            f += cp * cl / (std::f64::consts::PI * r2 * r2) * da;
                        }
                    }
                }
            }
        }
    }
    f /= (n * n) as f64;
    [f * LAMP[0] as f64, f * LAMP[1] as f64]
}

#[derive(Default)]
struct Front(Vec<[f64; 2]>);

impl Sink for Front {
    type Error = std::convert::Infallible;
    fn polygon(&mut self, p: &PolygonResult<'_>) -> Result<(), Self::Error> {
        assert_eq!(p.id, self.0.len() as u64);
        self.0
            .push([p.irradiance[0][0] as f64, p.irradiance[0][1] as f64]);
        Ok(())
    }
}

/// Pieces under a lamp of 0.1 m to 0.4 m at 0.6 m to 1.4 m, one level and two levels down:
/// each lit polygon's irradiance within 2% of the double integral, 20% in a shadow's edge
/// (the gather's noise there: 4% typically, with 6 times the rays within 5%), a median
/// within 1%. The stands hold only instances: a level without polygons of its own. With 81
/// lamps (more than are taken one by one) each sample draws one down the top level's light
/// cut, from the opened levels too (measured within 1.7%; the rays alone left a square
/// +41%), and the top level's own cut passes over the closed instances beside its lamps
/// (it read them as patches and panicked). Before the lamps around an
/// opened level were added directly, its polygons read them through the gather rays that
/// happened to meet them: medians of 30% too dark, a few 50 times too bright.
#[test]
fn an_opened_instance_takes_a_lamp_around_it_polygon_by_polygon() {
    let mut exec = RayonExecutor::new(2).unwrap();
    let mut all = Vec::new();
    for (lamp, height, grid, nested) in [
        (0.3f32, 1.0f32, 1u32, false),
        (0.1, 0.6, 1, false),
        (0.4, 1.4, 1, false),
        (0.2, 0.9, 1, true),
        // More lamps than are taken one by one: drawn down the top level's light cut.
        (0.05, 1.0, 9, false),
        (0.04, 0.8, 9, true),
    ] {
        let lamps = (grid * grid) as usize;
        // Cells of each lamp in the reference: small lamps far away need few.
        let m = |n: usize| if grid == 1 { n } else { 2 };
        let mut s = room(lamp, height, grid, nested);
        for o in 0..s.originals.len() {
            let t = bake_original(&s, o, &common::quick_tables(), &mut exec, &mut |_, _, _| {})
                .unwrap();
            s.tables.push(t.to_scene());
        }
        let polys: Vec<Vec<DVec3>> = world_polygons(&s)
            .into_iter()
            .map(|p| p.into_iter().map(d).collect())
            .collect();
        let bytes = compile(&s).unwrap();
        let view = SceneView::open(SliceSource(&bytes[..])).unwrap();
        let mut ws = vec![0u8; 64 << 20];
        let mut got = Front::default();
        let stats = solve_hi(
            &view,
            &Settings::default(),
            hirad_core::hr::Inline::NONE,
            &mut ws,
            &mut exec,
            &mut NoProgress,
            &mut got,
        )
        .unwrap();
        assert_eq!(got.0.len(), polys.len());
        // Every level's rays, by phase (the opened levels' final gather included).
        let r = stats.rays_by_phase;
        assert_eq!(r.lighting + r.links + r.final_gather, stats.rays);
        let want: Vec<[f64; 2]> = (0..polys.len())
            .map(|i| reference(&polys, lamps, i, 8, m(8), true))
            .collect();
        let top = want.iter().map(|w| w[0]).fold(0.0f64, f64::max);
        let case = format!("{lamps} lamps of {lamp} m at {height} m, nested {nested}");
        // The lamps and the board first, then the pieces' polygons.
        for (i, &coarse) in want.iter().enumerate().skip(lamps + 1) {
            let open = reference(&polys, lamps, i, 8, m(8), false);
            // In a shadow's edge: a finer reference, and the gather's noise there (its
            // points see the lamp in part, each through one ray).
            let penumbra = coarse[0] > 0.02 * top && coarse[0] < 0.98 * open[0];
            let (want_i, bound) = if penumbra {
                (reference(&polys, lamps, i, 24, m(24), true), 0.2)
            } else {
                (coarse, 0.02)
            };
            for b in 0..2 {
                let (w, g) = (want_i[b], got.0[i][b]);
                let scale = top * LAMP[b] as f64 / LAMP[0] as f64;
                if w < 0.02 * scale {
                    assert!(
                        g <= 0.03 * scale,
                        "{case}: polygon {i} band {b}: {g} for {w}"
                    );
                    continue;
                }
                let e = g / w - 1.0;
                assert!(
                    e.abs() <= bound,
                    "{case}: polygon {i} band {b}: {g} for {w} ({e:+.3}, penumbra {penumbra})"
                );
                all.push(e.abs());
            }
        }
    }
    all.sort_by(f64::total_cmp);
    let median = all[all.len() / 2];
    println!(
        "{} polygon bands: median {:.2}%, worst {:.2}%",
        all.len(),
        100.0 * median,
        100.0 * all[all.len() - 1]
    );
    assert!(median <= 0.01, "median {median}");
}
