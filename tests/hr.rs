//! The hierarchical solver against known answers.

use hirad::scene::read_image;
use hirad_core::hr::{self, NoProgress, Sequential, Settings};
use hirad_core::sink::{PolygonResult, Sink};
use hirad_core::visibility::Unoccluded;
use hirad_tests::fixture;

#[derive(Default)]
struct Collect {
    rows: Vec<(u64, f32, Vec<f32>, Vec<f32>, Vec<f32>, Vec<f32>)>,
}

impl Sink for Collect {
    type Error = ();
    fn polygon(&mut self, p: &PolygonResult<'_>) -> Result<(), ()> {
        self.rows.push((
            p.id,
            p.area,
            p.radiosity[0].to_vec(),
            p.irradiance[0].to_vec(),
            p.radiosity[1].to_vec(),
            p.irradiance[1].to_vec(),
        ));
        Ok(())
    }
}

fn solve(name: &str, settings: &Settings) -> (Collect, hr::Stats) {
    let scene = hirad::text::parse(&std::fs::read(fixture(name)).unwrap()).unwrap();
    let bytes = hirad::scene::compile(&scene).unwrap();
    let view = read_image(&bytes).unwrap();
    let mut scratch = vec![0u8; hr::census_scratch_bytes(&view)];
    let plan = hr::plan(&view, settings, true, &mut scratch).unwrap();
    let mut ws = vec![0u8; (plan.suggested_bytes as usize).max(std::env::var("HR_MEM").ok().and_then(|v| v.parse().ok()).unwrap_or(0))];
    let mut sink = Collect::default();
    let stats = hr::solve(&view, settings, &mut ws, None::<&Unoccluded>, &mut Sequential, &mut NoProgress, &mut sink).unwrap();
    (sink, stats)
}

#[test]
fn parallel_squares() {
    let (out, stats) = solve("parallel_squares.hir", &Settings::default());
    eprintln!("{:?}\n{stats:?}", out.rows);
}

#[test]
fn furnace() {
    for (name, expect) in [("furnace.hir", 2.0f32), ("furnace_099.hir", 100.0)] {
        let (out, stats) = solve(name, &Settings::default());
        let worst = out.rows.iter().map(|r| (r.2[0] / expect - 1.0).abs()).fold(0.0f32, f32::max);
        eprintln!("{name}: worst {worst} {stats:?}");
    }
}

#[test]
fn cornell() {
    for eps in [1e-2f32, 1e-3, 1e-4] {
        let t = std::time::Instant::now();
        let (out, stats) = solve("cornell_box.hir", &Settings { epsilon: eps, ..Settings::default() });
        eprintln!("eps {eps}: {:.2}s {stats:?}", t.elapsed().as_secs_f64());
        for r in &out.rows {
            eprintln!("  {} {:?}", r.0, r.2);
        }
    }
}

#[test]
fn cornell_direct_floor() {
    use glam::{DVec3, Vec3};
    let light = [
        Vec3::new(0.343, 0.5478, 0.227),
        Vec3::new(0.343, 0.5478, 0.332),
        Vec3::new(0.213, 0.5478, 0.332),
        Vec3::new(0.213, 0.5478, 0.227),
    ];
    let n = 200;
    let mut sum = 0.0;
    for i in 0..n {
        for j in 0..n {
            let p = DVec3::new(0.5528 * (i as f64 + 0.5) / n as f64, 0.0, 0.5592 * (j as f64 + 0.5) / n as f64);
            sum += hirad_core::formfactor::point_polygon_f64(p, DVec3::Y, &light);
        }
    }
    let f = sum / (n * n) as f64;
    eprintln!("floor->light FF {f}, direct H red {}", f * 53.40708);
    let settings = Settings { epsilon: 1e-2, ..Settings::default() };
    let (out, _) = solve("cornell_box.hir", &settings);
    eprintln!("HR floor H {:?}", out.rows[0].3);
}
