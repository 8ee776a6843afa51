//! `hirad gen forest` (not written yet).

use super::Common;
use crate::scene::Scene;
use anyhow::{Result, bail};

/// Arguments of `hirad gen forest`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Seed, output and summary.
    #[command(flatten)]
    pub common: Common,
}

/// Builds the scene.
pub fn generate(a: &Args) -> Result<Scene> {
    let _ = a;
    bail!("the forest generator is not written yet")
}
