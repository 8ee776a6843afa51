//! Helpers shared by the integration tests in `tests/`.

use hirad::output::ResultsTable;
use hirad::scene::{Scene, read_image};
use hirad::solve::{RayonExecutor, world_polygons};
use hirad::visibility::ObvhsVisibility;
use hirad_core::hr::{self, HrError, Progress, Settings, SolveError, Stats};
use hirad_core::sink::Sink;
use std::path::PathBuf;

pub mod sample;

/// Solves `scene` with the hierarchical solver as `hirad solve` does (obvhs visibility, two
/// threads, the planner's suggested workspace), into a results table.
pub fn solve_hr<P: Progress>(
    scene: &Scene,
    settings: &Settings,
    progress: &mut P,
) -> Result<(ResultsTable, Stats), HrError> {
    let two_sided = scene.materials.iter().any(|m| m.data.two_sided);
    let mut table = ResultsTable::new(scene.bands as usize, two_sided);
    let stats = solve_hr_into(scene, settings, progress, &mut table).map_err(|e| match e {
        SolveError::Hr(h) => h,
        SolveError::Sink(_) => unreachable!("the table never refuses"),
    })?;
    Ok((table, stats))
}

/// [`solve_hr`] into any sink (every leaf patch, then every polygon).
pub fn solve_hr_into<P: Progress, S: Sink>(
    scene: &Scene,
    settings: &Settings,
    progress: &mut P,
    sink: &mut S,
) -> Result<Stats, SolveError<S::Error>> {
    let bytes = hirad::scene::compile(scene).unwrap();
    let view = read_image(&bytes).unwrap();
    let mut scratch = vec![0u8; hr::census_scratch_bytes(&view)];
    let plan = hr::plan(&view, settings, false, &mut scratch)?;
    let mut ws = vec![0u8; plan.suggested_bytes as usize];
    let vis = ObvhsVisibility::new(&world_polygons(scene)).unwrap();
    let mut exec = RayonExecutor::new(2).unwrap();
    hr::solve(
        &view,
        settings,
        &mut ws,
        Some(&vis),
        &mut exec,
        progress,
        sink,
    )
}

/// Path of a file in `fixtures/`.
pub fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(name)
}

pub mod canopy;

/// Deterministic numbers in [0, 1) from a seed and a counter.
pub struct Rng(pub u32, pub u32);

impl Rng {
    /// The next number in [0, 1).
    pub fn unit(&mut self) -> f32 {
        self.1 += 1;
        hirad_core::sampling::unit2(hirad_core::sampling::hash3(self.0, self.1, 0x7E57)).0
    }
    /// The next number in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }
}
