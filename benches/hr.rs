//! The hierarchical solver's hot paths: the exact point-to-polygon form factor that link
//! evaluation calls millions of times; on the Cornell box as 32 triangles (the issue-8
//! scene), the first refinement round (refinement passes from the root's self-link until
//! stable, with the patches' lighting and the links' evaluation, the closure and the
//! solution) and one iteration of the solution (gather, push, pull) on the finished
//! hierarchy; and whole solves at epsilon 1e-3 and 1e-4, with and without the final gather.
//! One thread, obvhs visibility, the planner's workspace allocated outside the timed region
//! (a phase runs from a copy of the state before it, also made outside).
//! `cargo bench --bench hr`.

use divan::{Bencher, counter::ItemsCount};
use glam::Vec3;
use hirad::output::ResultsTable;
use hirad::scene::{Scene, compile, read_image};
use hirad::solve::{RayonExecutor, world_polygons};
use hirad::visibility::ObvhsVisibility;
use hirad_core::formfactor::point_polygon;
use hirad_core::hr::{self, NoProgress, Settings, bench};
use hirad_core::sampling::{hash3, unit2};

fn main() {
    divan::main();
}

fn rnd3(a: u32, b: u32) -> Vec3 {
    let (x, y) = unit2(hash3(a, b, 1));
    let (z, _) = unit2(hash3(a, b, 2));
    Vec3::new(x, y, z)
}

/// 4096 receiving points with normals and quads in front of them, at distances from a
/// tenth of the quad's size to ten times it (near and far links).
#[divan::bench]
fn point_polygon_4096(bencher: Bencher) {
    let cases: Vec<(Vec3, Vec3, [Vec3; 4])> = (0..4096u32)
        .map(|i| {
            let p = rnd3(i, 1);
            let n = (rnd3(i, 2) - 0.5).normalize_or(Vec3::Z);
            let d = 0.1 + 10.0 * unit2(hash3(i, 3, 0)).0;
            let c = p + n * d + (rnd3(i, 4) - 0.5);
            let (u, v) = n.any_orthonormal_pair();
            (p, n, [c - u - v, c + u - v, c + u + v, c - u + v])
        })
        .collect();
    bencher.counter(ItemsCount::new(cases.len())).bench(|| {
        let mut sum = 0.0f32;
        for (p, n, q) in &cases {
            sum += point_polygon(*p, *n, q);
        }
        divan::black_box(sum)
    });
}

fn cornell() -> Scene {
    let path = hirad_tests::fixture("obj/cornell_triangles.obj");
    hirad::files::load_scene(&path).unwrap().scene
}

/// One whole solve of `scene`, the workspace and ray caster prepared outside the timing.
fn solve(bencher: Bencher, scene: &Scene, settings: Settings) {
    let bytes = compile(scene).unwrap();
    let view = read_image(&bytes).unwrap();
    let mut scratch = vec![0u8; hr::census_scratch_bytes(&view)];
    let plan = hr::plan(&view, &settings, false, &mut scratch).unwrap();
    let mut ws = vec![0u8; plan.suggested_bytes as usize];
    let vis = ObvhsVisibility::new(&world_polygons(scene)).unwrap();
    let mut exec = RayonExecutor::new(1).unwrap();
    bencher.bench_local(|| {
        let mut table = ResultsTable::new(scene.bands as usize, false);
        let stats = hr::solve(
            &view,
            &settings,
            &mut ws,
            Some(&vis),
            &mut exec,
            &mut NoProgress,
            &mut table,
        )
        .unwrap();
        divan::black_box(stats.links)
    });
}

#[divan::bench(args = [1e-3, 1e-4], sample_count = 10)]
fn cornell_triangles_hierarchy_alone(bencher: Bencher, epsilon: f32) {
    let settings = Settings {
        epsilon,
        final_rays: 0,
        ..Settings::default()
    };
    solve(bencher, &cornell(), settings);
}

#[divan::bench(args = [1e-3, 1e-4], sample_count = 10)]
fn cornell_triangles_with_final_gather(bencher: Bencher, epsilon: f32) {
    let settings = Settings {
        epsilon,
        ..Settings::default()
    };
    solve(bencher, &cornell(), settings);
}

/// The workspace and the state after `prepare` has run (from `bench::start`), for running
/// one phase again and again from the same start.
fn phase_bench(
    bencher: Bencher,
    epsilon: f32,
    prepare: impl Fn(&mut bench::Snapshot, &mut [u8], &ObvhsVisibility, &mut RayonExecutor<'static>),
    phase: impl Fn(&mut bench::Snapshot, &mut [u8], &ObvhsVisibility, &mut RayonExecutor<'static>),
) {
    let scene = cornell();
    let settings = Settings {
        epsilon,
        final_rays: 0,
        ..Settings::default()
    };
    let bytes = compile(&scene).unwrap();
    let view = read_image(&bytes).unwrap();
    let mut scratch = vec![0u8; hr::census_scratch_bytes(&view)];
    let plan = hr::plan(&view, &settings, false, &mut scratch).unwrap();
    let mut ws = vec![0u8; plan.suggested_bytes as usize];
    let vis = ObvhsVisibility::new(&world_polygons(&scene)).unwrap();
    let mut exec = RayonExecutor::new(1).unwrap();
    let mut snap = bench::start(&view, &settings, &mut ws, &vis, &mut exec).unwrap();
    prepare(&mut snap, &mut ws, &vis, &mut exec);
    bencher
        .with_inputs(|| (snap.clone(), ws.clone()))
        .bench_local_values(|(mut s, mut w)| {
            phase(&mut s, &mut w, &vis, &mut exec);
            divan::black_box(bench::links(&s))
        });
}

/// The first refinement round, from the root's self-link to a refined, solved hierarchy.
#[divan::bench(args = [1e-3, 1e-4], sample_count = 20)]
fn cornell_triangles_first_refinement_round(bencher: Bencher, epsilon: f32) {
    phase_bench(
        bencher,
        epsilon,
        |_, _, _, _| {},
        |s, w, v, e| {
            bench::round(s, w, v, e);
        },
    );
}

/// One iteration of the solution (gather, push, pull) on the hierarchy of a finished solve.
#[divan::bench(args = [1e-3, 1e-4], sample_count = 50)]
fn cornell_triangles_one_gather(bencher: Bencher, epsilon: f32) {
    phase_bench(
        bencher,
        epsilon,
        |s, w, v, e| {
            while !bench::round(s, w, v, e) {}
        },
        bench::gather,
    );
}
