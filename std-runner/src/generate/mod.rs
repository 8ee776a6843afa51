//! `hirad gen KIND`: deterministic procedural scenes for testing and measuring — a poplar from
//! its botanical structure, a stand of poplars lit by bulbs, a furnished room, a forest, a crop
//! canopy. Each writes the compact (instanced) scene: it never holds the expanded scene.

pub mod bulb;
pub mod canopy;
pub mod crop;
pub mod forest;
pub mod furniture;
pub mod houseplants;
pub mod mesh;
pub mod palette;
pub mod poplar;
pub mod rng;
pub mod room;
pub mod room_layout;
pub mod room_shell;
pub mod shapes;
pub mod sky;
pub mod stand;
pub mod terrain;
pub mod tree;

#[cfg(test)]
mod tests_trees;

use crate::files::{self, Format};
use crate::scene::Scene;
use anyhow::{Result, anyhow, bail};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `hirad gen`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  hirad gen poplar --preset paper -o poplar.hirb\n  hirad gen canopy --rows 4 --plants-per-row 10 -o field.hirb\n  hirad gen room -o room.hirb && hirad solve room.hirb --image room.png"
)]
pub struct Args {
    /// The kind of scene.
    #[command(subcommand)]
    pub kind: Kind,
}

/// The generators.
#[derive(clap::Subcommand, Debug)]
pub enum Kind {
    /// A poplar from its botanical structure: axes of orders 0 to 3 with kind and age,
    /// approximate instances of originals chosen by kind and age class.
    Poplar(poplar::Args),
    /// Poplars of several ages on a ground plane, lit by bulbs of ~1000 emitting polygons.
    Stand(stand::Args),
    /// A furnished room: chairs, tables, orchids and plants as exact instances, ceiling lights.
    Room(room::Args),
    /// Trees as exact instances of a few originals on a terrain, under a sun and a sky.
    Forest(forest::Args),
    /// A crop field: rows of maize- or wheat-like plants on soil, sun and sky, PAR and NIR.
    Canopy(canopy::Args),
}

/// Options every generator takes.
#[derive(clap::Args, Debug, Clone)]
pub struct Common {
    /// Random seed: the same seed gives the same scene, byte for byte.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output scene: .hir (text) or .hirb (binary image).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Do not print the summary.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Reads a generator's options from command-line words (without the command name), with the
/// command line's own defaults: how tests and library callers build `Args`.
pub fn args_from_words<A, I, T>(name: &'static str, words: I) -> Result<A>
where
    A: clap::Args + clap::FromArgMatches,
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    let command = A::augment_args(clap::Command::new(name));
    let words =
        std::iter::once(std::ffi::OsString::from(name)).chain(words.into_iter().map(Into::into));
    let matches = command.try_get_matches_from(words)?;
    Ok(A::from_arg_matches(&matches)?)
}

/// Runs `hirad gen`.
pub fn run(a: Args) -> Result<()> {
    let start = Instant::now();
    let common = match &a.kind {
        Kind::Poplar(k) => &k.common,
        Kind::Stand(k) => &k.common,
        Kind::Room(k) => &k.common,
        Kind::Forest(k) => &k.common,
        Kind::Canopy(k) => &k.common,
    };
    // Where the scene goes, checked before it is made.
    Format::of(&common.output).map_err(crate::exit::usage)?;
    crate::paths::check_outputs(
        &[],
        &[crate::paths::Output {
            option: "-o",
            path: &common.output,
        }],
    )?;
    crate::interrupt::expect(&[&common.output]);
    let (scene, common) = match &a.kind {
        Kind::Poplar(k) => (poplar::generate(k).map_err(crate::exit::usage)?, &k.common),
        Kind::Stand(k) => (stand::generate(k).map_err(crate::exit::usage)?, &k.common),
        Kind::Room(k) => (room::generate(k).map_err(crate::exit::usage)?, &k.common),
        Kind::Forest(k) => (forest::generate(k).map_err(crate::exit::usage)?, &k.common),
        Kind::Canopy(k) => (canopy::generate(k).map_err(crate::exit::usage)?, &k.common),
    };
    let bytes = write(&scene, &common.output)?;
    if !common.quiet {
        summary(&scene, &common.output, bytes, start.elapsed().as_secs_f64())?;
    }
    Ok(())
}

/// Writes a scene as .hir or .hirb (through a temporary file); returns the bytes written.
pub fn write(scene: &Scene, path: &std::path::Path) -> Result<u64> {
    let format = Format::of(path)?;
    let image = files::compile(path, scene)?;
    match format {
        Format::Binary => {
            files::write_atomic(path, |w| Ok(w.write_all(&image)?))?;
            Ok(image.len() as u64)
        }
        Format::Text => {
            let text = crate::text::print(scene);
            files::write_atomic(path, |w| Ok(w.write_all(text.as_bytes())?))?;
            Ok(text.len() as u64)
        }
        Format::Obj => bail!(
            "{}: gen writes .hir or .hirb; use `hirad flatten` for OBJ",
            path.display()
        ),
    }
}

/// Prints polygons after expansion, instancing depth, originals and instances.
fn summary(scene: &Scene, path: &std::path::Path, bytes: u64, seconds: f64) -> Result<()> {
    let image = crate::scene::compile(scene).map_err(|e| anyhow!("{e}"))?;
    let view = crate::scene::read_image(&image).map_err(|e| anyhow!("{e}"))?;
    let i = view.info();
    let mut out = String::new();
    let _ = writeln!(
        out,
        "wrote             {} ({bytes} bytes) in {seconds:.2} s",
        path.display()
    );
    let _ = writeln!(out, "polygons          {}", i.expanded_polygons);
    let _ = writeln!(out, "stored polygons   {}", i.polygons);
    let _ = writeln!(out, "instancing depth  {}", i.instancing_depth);
    let _ = writeln!(out, "originals         {}", i.originals);
    let _ = writeln!(
        out,
        "instances         {} ({} exact, {} approximate)",
        i.exact_instances + i.approximate_instances,
        i.exact_instances,
        i.approximate_instances
    );
    crate::cli::print_out(&out)
}
