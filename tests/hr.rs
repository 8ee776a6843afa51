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
    let plan = hr::plan(&view, settings, &mut scratch).unwrap();
    let mut ws = vec![0u8; plan.suggested_bytes as usize];
    let mut sink = Collect::default();
    let stats = hr::solve(&view, settings, &mut ws, &Unoccluded, &mut Sequential, &mut NoProgress, &mut sink).unwrap();
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
