//! `hirad solve --method hi` on a scene without some of its tables: they come from the
//! table cache, or are made before the solve (and cached).

use super::solve_args::{Args, Method};
use crate::output::Progress;
use crate::scene::Scene;
use crate::tables::Completed;
use anyhow::{Context, Result};

/// Adds to `scene` the tables it lacks of the originals `closed` names (those `--method hi`
/// closes) when `a` asks for that method (saying so, and warning about tables that miss
/// their targets); `None` when none was needed. Warns that `--table-max-side` does nothing
/// with another method.
pub(super) fn complete(
    a: &Args,
    scene: &mut Scene,
    closed: &[usize],
    threads: usize,
    progress: &Progress,
) -> Result<Option<Completed>> {
    if a.method == Method::Hi {
        let missing = crate::tables::missing_of(scene, closed);
        if !missing.is_empty() {
            if !a.quiet {
                let names: Vec<&str> = missing
                    .iter()
                    .map(|&o| scene.originals[o].name.as_str())
                    .collect();
                eprintln!(
                    "note: {} has no directional tables for {}: taking them from the table cache or making them now (minutes for an original of a few thousand polygons at the defaults, hours for tens of thousands; `hirad tables SCENE -o OUT.hirb` keeps them in a file)",
                    a.scene.display(),
                    names.join(", ")
                );
            }
            let made = crate::tables::complete(
                scene,
                &missing,
                threads,
                a.table_max_side,
                &mut |what: &str, done: u64, total: u64| progress.phase_at(what, Some(total), done),
            )
            .with_context(|| format!("{}: making its directional tables", a.scene.display()))?;
            progress.finish();
            if !a.quiet && !made.unmet.is_empty() {
                eprintln!(
                    "warning: the tables of {} missed their error targets on the finest grids allowed{}; the solve goes on with them",
                    made.unmet.join(", "),
                    if a.table_max_side.is_some() {
                        " (--table-max-side)"
                    } else {
                        ""
                    }
                );
            }
            return Ok(Some(made));
        }
    } else if a.table_max_side.is_some() && !a.quiet {
        eprintln!("warning: --table-max-side has no effect without --method hi");
    }
    Ok(None)
}
