//! `hirad solve --image`'s view: its size and camera, chosen on the scene model before the
//! solve (a solve that reads its `.hirb` as it goes then drops the model's vertices).

use super::solve_args::{Args, DEFAULT_SIZE};
use crate::exit::usage;
use crate::output;
use anyhow::{Result, anyhow};

/// The image's size and camera: `--size`, then `--camera`, the scene's first camera, or the
/// view that shows most (see `output::view`), not the backs of walls, upright
/// (`scene::Up`: OBJ files are y up, hirad's own scenes z up).
pub(super) fn image_view(
    a: &Args,
    scene: &crate::scene::Scene,
    up: crate::scene::Up,
) -> Result<(output::Size, crate::scene::Camera)> {
    let size = output::parse_size(a.size.as_deref().unwrap_or(DEFAULT_SIZE))
        .map_err(|e| usage(anyhow!("{e}")))?;
    let camera = match &a.camera {
        Some(c) => output::parse_camera(c).map_err(|e| usage(anyhow!("{e}")))?,
        None => match scene.cameras.first() {
            Some(c) => {
                if a.up.is_some() && !a.quiet {
                    eprintln!(
                        "warning: --up has no effect: the scene's first camera gives the view and its up"
                    );
                }
                c.clone()
            }
            None => {
                let c = output::view::choose(scene, &output::scene_bounds(scene), size, up)
                    .map_err(|e| usage(anyhow!("{e}")))?;
                if !a.quiet {
                    eprintln!(
                        "note: the default view, {} up: --camera {} (change it, or --up)",
                        up.name(),
                        output::camera_arg(&c)
                    );
                }
                c
            }
        },
    };
    Ok((size, camera))
}
