//! `hirad flatten SCENE -o OUT.obj`.

use crate::files::{self, Format};
use anyhow::Result;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `hirad flatten`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  hirad flatten fixtures/chair_room.hir -o room.obj\n  hirad flatten poplar.hirb -o poplar.obj -q   # face k: results row k-1\n  hirad flatten cad.obj --up z -o upright.obj  # a z-up OBJ, written y up"
)]
pub struct Args {
    /// Input scene (.hir, .hirb or .obj).
    pub scene: PathBuf,
    /// Output .obj; materials go to the .mtl beside it. Face k (1-based) is the polygon with
    /// global id k-1.
    #[arg(short, long)]
    pub output: PathBuf,
    /// The input's up axis (x, y, z, -x, -y, -z), written as +y (the OBJ convention).
    /// Default: y for an OBJ, else the first camera's up, else the sky's zenith, else z.
    #[arg(long, allow_hyphen_values = true, value_parser = super::parse_up)]
    pub up: Option<crate::scene::Up>,
    /// Do not print warnings, progress or the summary.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Runs `hirad flatten`.
pub fn run(a: Args) -> Result<()> {
    if Format::of(&a.output).ok() != Some(Format::Obj) {
        return Err(crate::exit::usage(anyhow::anyhow!(
            "{}: flatten writes Wavefront OBJ; give an output ending in .obj",
            a.output.display()
        )));
    }
    let start = Instant::now();
    let loaded = files::load_scene(&a.scene)?;
    super::convert::check_scene_outputs(&loaded.inputs, &a.output, files::Format::Obj)?;
    super::warn_all(&loaded.warnings, loaded.warnings_total, a.quiet);
    let stats = super::convert::write_obj(
        &a.scene,
        &loaded.scene,
        a.up.unwrap_or(loaded.up),
        &a.output,
        a.quiet,
    )?;
    super::warn_all(&stats.warnings, stats.warnings.len() as u64, a.quiet);
    if !a.quiet {
        eprintln!(
            "flattened {} faces, {} vertices into {} in {:.2} s",
            stats.faces,
            stats.vertices,
            a.output.display(),
            start.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
