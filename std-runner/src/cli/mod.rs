//! The `hirad` commands. Each command lives in its own file; errors carry the file and the
//! location of the fault and end the process with a non-zero status.

mod convert;
mod flatten;
mod info;
mod instancing;
mod progress;
pub(crate) mod solve;
pub(crate) mod solve_args;
mod solve_tables;
mod solve_view;
mod tables;
mod verdict;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use std::path::PathBuf;

/// hirad: radiosity (diffuse global illumination) for huge scenes that repeat themselves.
///
/// Scenes are read from `.hir` (text), `.hirb` (binary image) or `.obj` (+ `.mtl`) files.
/// Units: metres, W/m^2.
#[derive(Parser, Debug)]
#[command(
    name = "hirad",
    version,
    about,
    long_about = None,
    after_help = "Each command has --help with examples. Documentation: README.md, and in docs/ the\n\
                  scene format (format.md), OBJ import (obj.md) and the solvers (solver.md).\n\n\
                  Exit status: 0 success (the numbers are right), 1 the outputs were written but a\n\
                  check failed, 2 usage error, 3 an input file is missing or invalid, 4 the run\n\
                  could not complete, 130/143 interrupted.\n\n\
                  Examples:\n  \
                  hirad solve fixtures/cornell_box.hir --results box.csv --image box.png\n  \
                  hirad gen poplar --preset paper -o poplar.hirb && hirad info poplar.hirb"
)]
pub struct Cli {
    /// The command to run.
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Describe a scene: its counts, bands, materials and instancing
    ///
    /// Bands, materials, polygons after expansion, clusters, originals, instances, instancing
    /// depth, size of the binary image.
    Info(info::Args),
    /// Convert a scene between .hir, .hirb and .obj
    ///
    /// An .obj output is the expanded scene, with its .mtl beside it.
    Convert(convert::Args),
    /// Write the scene as OBJ with every instance expanded
    ///
    /// Faces in global-id order (face k is row k-1 of solve's results), materials in the
    /// .mtl beside it.
    Flatten(flatten::Args),
    /// Compute the radiosity of every polygon: results table, image, statistics
    ///
    /// Radiosity in W/m^2 by hierarchical radiosity (default) or the exact full-matrix
    /// solver; optionally the error against a reference results table.
    Solve(solve_args::Args),
    /// Directional tables of the instanced originals: tau, areas, phase function
    ///
    /// Each original is solved alone under suns from a grid of directions; the tables are
    /// what a closed instance knows of its contents (--method hi).
    Tables(tables::Args),
    /// Generate a procedural scene: poplar, stand, room, forest, canopy
    Gen(crate::generate::Args),
}

/// Parses the command line and runs the command.
pub fn run() -> anyhow::Result<()> {
    let args = joined_negative_values(std::env::args_os().collect());
    let matches = negative_numbers(Cli::command()).get_matches_from(args);
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    match cli.command {
        Command::Info(a) => info::run(a),
        Command::Convert(a) => convert::run(a),
        Command::Flatten(a) => flatten::run(a),
        Command::Solve(a) => solve::run(a),
        Command::Tables(a) => tables::run(a),
        Command::Gen(a) => crate::generate::run(a),
    }
}

/// Lets every option's value be a negative number (`--epsilon -1` is then refused by the
/// option's own check, with its range, instead of clap advising `-- -1`), in every command.
fn negative_numbers(cmd: clap::Command) -> clap::Command {
    cmd.mut_args(|a| {
        if a.get_action().takes_values() && !a.is_positional() {
            a.allow_negative_numbers(true)
        } else {
            a
        }
    })
    .mut_subcommands(negative_numbers)
}

/// `--option -1e-3` as `--option=-1e-3`: clap takes `-1` and `-0.5` for values (see
/// [`negative_numbers`]) but not a negative number with a signed exponent.
fn joined_negative_values(args: Vec<std::ffi::OsString>) -> Vec<std::ffi::OsString> {
    let mut out: Vec<std::ffi::OsString> = Vec::with_capacity(args.len());
    for arg in args {
        let negative = arg
            .to_str()
            .is_some_and(|s| s.starts_with('-') && s.parse::<f64>().is_ok());
        if let Some(prev) = out.last_mut().filter(|_| negative)
            && prev
                .to_str()
                .is_some_and(|p| p.starts_with("--") && p.len() > 2 && !p.contains('='))
        {
            prev.push("=");
            prev.push(&arg);
            continue;
        }
        out.push(arg);
    }
    out
}

/// Parses `--up`: a signed axis (`x`, `y`, `z`, `-x`, `-y`, `-z`).
pub(crate) fn parse_up(s: &str) -> Result<crate::scene::Up, String> {
    crate::scene::Up::parse(s)
        .ok_or_else(|| format!("'{s}' is not an axis: give x, y, z, -x, -y or -z"))
}

/// Writes `text` to standard output. A closed pipe (`hirad info x | head -1`) ends the output
/// quietly instead of failing.
pub fn print_out(text: &str) -> anyhow::Result<()> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        r => Ok(r?),
    }
}

/// Prints the first warnings to stderr, and how many more there were: `total` counts every
/// warning made (a loader keeps only the first thousand in `warnings`).
pub(crate) fn warn_all(warnings: &[String], total: u64, quiet: bool) {
    if quiet {
        return;
    }
    const SHOWN: usize = 20;
    let total = total.max(warnings.len() as u64);
    let shown = warnings.len().min(SHOWN);
    if warnings.len() > SHOWN {
        for w in &warnings[..shown] {
            eprintln!("warning: {w}");
        }
        eprintln!(
            "warning: ... and {} more warnings ({total} in all)",
            total - shown as u64
        );
    } else {
        for w in warnings {
            eprintln!("warning: {w}");
        }
    }
}

/// The `.mtl` path beside an `.obj` path.
pub(crate) fn mtl_beside(obj: &std::path::Path) -> PathBuf {
    obj.with_extension("mtl")
}
