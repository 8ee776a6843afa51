//! Running the `hirad` binary from the integration tests.
#![allow(dead_code)] // each test file uses a different subset

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs `hirad` with `args`.
pub fn hirad(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hirad"))
        .args(args)
        .output()
        .expect("run hirad")
}

/// Runs a command that must succeed; returns its stdout.
pub fn ok(args: &[&str]) -> String {
    let out = hirad(args);
    assert!(
        out.status.success(),
        "hirad {args:?} failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// Runs a command that must fail with one of the documented error statuses (1 not right,
/// 2 usage, 3 input, 4 failed; see `hirad::exit`) and no panic; returns its stderr.
pub fn fails(args: &[&str]) -> String {
    let out = hirad(args);
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(
        matches!(out.status.code(), Some(1..=4)),
        "hirad {args:?}: exit status {:?}\n{err}",
        out.status
    );
    assert!(!err.contains("panicked"), "hirad {args:?} panicked:\n{err}");
    err
}

/// Runs a command that must fail with exactly `status` and no panic; returns its stderr.
pub fn fails_with(status: i32, args: &[&str]) -> String {
    let out = hirad(args);
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(
        out.status.code(),
        Some(status),
        "hirad {args:?}: exit status\n{err}"
    );
    assert!(!err.contains("panicked"), "hirad {args:?} panicked:\n{err}");
    err
}

/// A file in fixtures/.
pub fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fixtures")
        .join(name)
}

/// A path as an argument.
pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Writes `text` to `dir/name`; returns the path.
pub fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// A maize field of `rows` x `plants` plants (two bands, sun and sky) in `dir`.
pub fn canopy(dir: &Path, rows: u32, plants: u32) -> PathBuf {
    let scene = dir.join("field.hirb");
    let (rows, plants) = (rows.to_string(), plants.to_string());
    ok(&[
        "gen",
        "canopy",
        "--rows",
        &rows,
        "--plants-per-row",
        &plants,
        "-q",
        "-o",
        s(&scene),
    ]);
    scene
}

/// Directional-table settings coarse enough for a test's small originals (a few seconds to
/// bake): tau to 2% on grids up to 32, phase up to 8, first scattering up to 64.
pub fn quick_tables() -> hirad::tables::TableSettings {
    hirad::tables::TableSettings {
        tau: hirad_core::tables::bake::TauSettings {
            rays: 64,
            target: 0.02,
            checks: 16,
            seed: 1,
        },
        tau_check_rays: 128,
        max_tau_side: 32,
        max_side: 8,
        first_out_side: 8,
        max_out_side: 8,
        first_single_side: 32,
        max_single_side: 64,
        checks: 4,
        out_checks: 4,
        ..hirad::tables::TableSettings::default()
    }
}

/// A sink that drops every polygon's results (level tests look at the level itself).
pub struct Nothing;

impl hirad_core::sink::Sink for Nothing {
    type Error = std::convert::Infallible;
    fn polygon(&mut self, _: &hirad_core::sink::PolygonResult<'_>) -> Result<(), Self::Error> {
        Ok(())
    }
}

/// Grids of `hirad tables` coarse enough for a test (their targets are not met: exit 1).
pub const COARSE_TABLES: [&str; 8] = [
    "--max-side",
    "4",
    "--max-tau-side",
    "8",
    "--max-out-side",
    "8",
    "--max-single-side",
    "32",
];

/// `hirad tables SCENE -o OUT --instancing all` on [`COARSE_TABLES`], uncached: the image
/// is written though the targets are not met.
pub fn coarse_tables(scene: &Path, out: &Path) -> Output {
    let mut args = vec![
        "tables",
        s(scene),
        "-o",
        s(out),
        "--instancing",
        "all",
        "--no-cache",
        "-q",
    ];
    args.extend(COARSE_TABLES);
    hirad(&args)
}
