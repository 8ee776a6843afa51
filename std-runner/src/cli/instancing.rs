//! `--instancing` at the command line's edge: the policy applied to a scene file (its image,
//! or its loaded model compiled), and what was chosen printed.

use crate::exit::{input, usage};
use crate::files;
use crate::scene::Scene;
use crate::solve::policy::{self, Decision, Policy};
use anyhow::{Result, anyhow};
use hirad_core::image::{SceneSource, SceneView};
use std::path::Path;

/// `policy` applied to the image `view` of the scene file `path`, the originals named in
/// `expand` expanded in place (errors name the file; an unknown name is a usage error).
pub(super) fn decide<S: SceneSource>(
    path: &Path,
    view: &SceneView<S>,
    policy: Policy,
    expand: &[String],
) -> Result<Decision> {
    policy::decide(view, policy, expand).map_err(|e| {
        let e = anyhow!("{}: {e}", path.display());
        if e.to_string().contains("--expand ") {
            usage(e)
        } else {
            input(e)
        }
    })
}

/// `policy` applied to `scene`, the model loaded from `path` (see [`decide`]).
pub(super) fn decide_model(
    path: &Path,
    scene: &Scene,
    policy: Policy,
    expand: &[String],
) -> Result<Decision> {
    let bytes = files::compile(path, scene)?;
    let view =
        crate::scene::read_image(&bytes).map_err(|e| input(anyhow!("{}: {e}", path.display())))?;
    decide(path, &view, policy, expand)
}

/// Prints what `d` chose for each instanced original, unless `quiet`.
pub(super) fn print(d: &Decision, quiet: bool) {
    if !quiet && d.originals.iter().any(|c| c.instances > 0) {
        eprintln!("{}", d.describe());
    }
}

/// Refuses a decision that closes an original emitting light (a usage error).
pub(super) fn refuse_closed_emitter(d: &Decision) -> Result<()> {
    match d.closed_emitter() {
        Some(c) => Err(usage(anyhow!(
            "--instancing {} closes the instances of '{}', which emit light: tables carry no emission, so their light would be lost (--instancing auto expands them in place)",
            d.policy,
            c.name
        ))),
        None => Ok(()),
    }
}
