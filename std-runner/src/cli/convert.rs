//! `hirad convert SCENE -o OUT`.

use super::progress::Progress;
use crate::files::{self, Format};
use anyhow::{Context, Result, anyhow};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Arguments of `hirad convert`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  hirad convert model.obj -o model.hirb     # import once, load fast\n  hirad convert poplar.hirb -o poplar.hir   # the text form, to read or edit\n  hirad convert room.hirb -o room.obj       # expanded, room.mtl beside it"
)]
pub struct Args {
    /// Input scene (.hir, .hirb or .obj).
    pub scene: PathBuf,
    /// Output scene; its extension chooses the format (.hir, .hirb or .obj). An .obj output
    /// is the expanded scene (OBJ has no instances), with its materials in the .mtl beside it.
    #[arg(short, long)]
    pub output: PathBuf,
    /// The input's up axis (x, y, z, -x, -y, -z). Default: y for an OBJ (the convention),
    /// else the first camera's up, else the sky's zenith, else z. An .obj output is written
    /// y up and a .hir/.hirb output from an OBJ z up, as hirad's scenes are (see docs/obj.md);
    /// between .hir and .hirb the scene is turned only when this is given.
    #[arg(long, allow_hyphen_values = true, value_parser = super::parse_up)]
    pub up: Option<crate::scene::Up>,
    /// Do not print warnings or progress.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Runs `hirad convert`.
pub fn run(a: Args) -> Result<()> {
    let out_format = Format::of(&a.output).map_err(crate::exit::usage)?;
    let mut loaded = files::load_scene(&a.scene)?;
    check_scene_outputs(&loaded.inputs, &a.output, out_format)?;
    super::warn_all(&loaded.warnings, loaded.warnings_total, a.quiet);
    let up = a.up.unwrap_or(loaded.up);
    if out_format != Format::Obj
        && (a.up.is_some() || loaded.format == Format::Obj)
        && up != crate::scene::Up::Z
    {
        up.rotate_scene_to_z_up(&mut loaded.scene);
        if !a.quiet {
            eprintln!(
                "note: the scene's {} axis becomes +z, as in hirad's own scenes",
                up.name()
            );
        }
    }
    if out_format != Format::Binary && !loaded.scene.tables.is_empty() && !a.quiet {
        eprintln!(
            "warning: {}: the directional tables of {} are not kept (only a .hirb holds them; `hirad tables` makes them again)",
            a.output.display(),
            super::info::plural(loaded.scene.tables.len() as u64, "original", "originals")
        );
    }
    match out_format {
        Format::Text => {
            // Compiling checks the scene, so a .hir output always reads back.
            files::compile(&a.scene, &loaded.scene)?;
            let text = crate::text::print(&loaded.scene);
            files::write_atomic(&a.output, |w| Ok(w.write_all(text.as_bytes())?))?;
        }
        Format::Binary => {
            let bytes = files::compile(&a.scene, &loaded.scene)?;
            files::write_atomic(&a.output, |w| Ok(w.write_all(&bytes)?))?;
        }
        Format::Obj => {
            let stats = write_obj(&a.scene, &loaded.scene, up, &a.output, a.quiet)?;
            super::warn_all(&stats.warnings, stats.warnings.len() as u64, a.quiet);
        }
    }
    if !a.quiet {
        eprintln!("wrote {}", a.output.display());
    }
    Ok(())
}

/// Refuses to overwrite the input with the output.
pub(crate) fn check_scene_outputs(inputs: &[PathBuf], output: &Path, format: Format) -> Result<()> {
    let mtl = super::mtl_beside(output);
    let mut outputs = vec![crate::paths::Output {
        option: "-o",
        path: output,
    }];
    if format == Format::Obj {
        outputs.push(crate::paths::Output {
            option: "-o (its .mtl)",
            path: &mtl,
        });
    }
    crate::paths::check_outputs(inputs, &outputs)?;
    crate::interrupt::expect(&outputs.iter().map(|o| o.path).collect::<Vec<_>>());
    Ok(())
}

/// Writes the expanded scene as OBJ + MTL through temporary files, renaming both into place
/// only when both are complete.
pub(crate) fn write_obj(
    input: &Path,
    scene: &crate::scene::Scene,
    up: crate::scene::Up,
    out: &Path,
    quiet: bool,
) -> Result<crate::obj::ObjExport> {
    files::compile(input, scene)?;
    let mtl_path = super::mtl_beside(out);
    let mtl_name = mtl_path
        .file_name()
        .and_then(|n| n.to_str())
        .ok_or_else(|| anyhow!("{}: output name is not valid UTF-8", out.display()))?
        .to_string();
    let obj_tmp = files::temp_beside(out)?;
    let mtl_tmp = files::temp_beside(&mtl_path)?;
    let mut obj_w = Progress::new(
        std::io::BufWriter::new(obj_tmp.as_file()),
        "writing OBJ",
        quiet,
    );
    let mut mtl_w = std::io::BufWriter::new(mtl_tmp.as_file());
    if up != crate::scene::Up::Y && !quiet {
        eprintln!(
            "note: the scene's {} axis is written as +y, the OBJ convention",
            up.name()
        );
    }
    let stats = crate::obj::export(scene, up, &mtl_name, &mut obj_w, &mut mtl_w)
        .with_context(|| format!("{}: cannot write", out.display()))?;
    obj_w
        .flush()
        .with_context(|| format!("{}: cannot write", out.display()))?;
    obj_w.finish();
    mtl_w
        .flush()
        .with_context(|| format!("{}: cannot write", mtl_path.display()))?;
    drop(obj_w);
    drop(mtl_w);
    files::persist(mtl_tmp, &mtl_path)?;
    files::persist(obj_tmp, out)?;
    Ok(stats)
}
