//! `hirad tables SCENE`: the directional tables of every instanced original.

use crate::files;
use crate::output::Progress;
use crate::scene::{Cluster, Scene};
use crate::solve::RayonExecutor;
use crate::tables::{OriginalTables, TableSettings, bake_original};
use anyhow::Result;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Arguments of `hirad tables`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  hirad gen canopy -o canopy.hirb && hirad tables canopy.hirb --export maize.csv\n  hirad tables poplar.hirb --check 20 --stats checks.json"
)]
pub struct Args {
    /// Scene file (.hir, .hirb or .obj).
    pub scene: PathBuf,
    /// Accuracy of the hr solves of each original under each sun (relative power).
    #[arg(long, default_value_t = 1e-4)]
    pub epsilon: f32,
    /// Final gather rays of those solves (0: the hierarchy alone, which measures the power
    /// leaving the box as well at a fifth of the time).
    #[arg(long, default_value_t = 0)]
    pub final_rays: u32,
    /// Largest error of the tau table's cross-section (1 - tau) A at check directions,
    /// relative to it: the intercepted power that scattering is predicted from.
    #[arg(long, default_value_t = 0.01)]
    pub tau_target: f32,
    /// Largest side of the grid of incoming directions (side x side suns, one solve each).
    #[arg(long, default_value_t = 16)]
    pub max_side: u32,
    /// Only the originals with these names (repeatable; default: every instanced original).
    #[arg(long = "original", value_name = "NAME")]
    pub originals: Vec<String>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// No progress and no warnings.
    #[arg(long, short)]
    pub quiet: bool,
}

/// The originals that some instance uses, in an order where an original comes after every
/// original it holds instances of.
pub fn instanced_originals(scene: &Scene) -> Vec<usize> {
    fn used(c: &Cluster, out: &mut Vec<bool>) {
        if let Some(i) = &c.instance {
            out[i.original] = true;
        }
        for ch in &c.children {
            used(ch, out);
        }
    }
    let n = scene.originals.len();
    let mut is_used = vec![false; n];
    used(&scene.root, &mut is_used);
    // Nesting depth: how many levels of originals an original holds below it.
    let mut depth = vec![usize::MAX; n];
    fn depth_of(scene: &Scene, o: usize, depth: &mut Vec<usize>, guard: usize) -> usize {
        if depth[o] != usize::MAX || guard > scene.originals.len() {
            return depth[o].min(guard);
        }
        let mut inner = Vec::new();
        fn collect(c: &Cluster, out: &mut Vec<usize>) {
            if let Some(i) = &c.instance {
                out.push(i.original);
            }
            for ch in &c.children {
                collect(ch, out);
            }
        }
        collect(&scene.originals[o].root, &mut inner);
        let d = inner
            .iter()
            .map(|&i| depth_of(scene, i, depth, guard + 1) + 1)
            .max()
            .unwrap_or(0);
        depth[o] = d;
        d
    }
    for o in 0..n {
        depth_of(scene, o, &mut depth, 0);
        let mut inner = vec![false; n];
        used(&scene.originals[o].root, &mut inner);
        for (u, i) in is_used.iter_mut().zip(inner) {
            *u |= i;
        }
    }
    let mut order: Vec<usize> = (0..n).filter(|&o| is_used[o]).collect();
    order.sort_by_key(|&o| (depth[o], o));
    order
}

/// Runs `hirad tables`.
pub fn run(a: Args) -> Result<()> {
    let loaded = files::load_scene(&a.scene)?;
    super::warn_all(&loaded.warnings, loaded.warnings_total, a.quiet);
    let scene = loaded.scene;
    let mut settings = TableSettings::default();
    settings.solve.epsilon = a.epsilon;
    settings.solve.final_rays = a.final_rays;
    settings.max_side = a.max_side;
    settings.tau.target = a.tau_target;
    let mut exec = RayonExecutor::new(a.threads.unwrap_or(0))?;
    let progress = Progress::new(a.quiet);
    let mut tables: Vec<OriginalTables> = Vec::new();
    for name in &a.originals {
        if scene.original_index(name).is_none() {
            return Err(crate::exit::usage(anyhow::anyhow!(
                "--original {name}: {} has no original of that name (it has: {})",
                a.scene.display(),
                scene
                    .originals
                    .iter()
                    .map(|o| o.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        }
    }
    let chosen: Vec<usize> = instanced_originals(&scene)
        .into_iter()
        .filter(|&o| a.originals.is_empty() || a.originals.contains(&scene.originals[o].name))
        .collect();
    for o in chosen {
        let mut last = String::new();
        let t = bake_original(&scene, o, &settings, &mut exec, &mut |what, done, total| {
            if what != last {
                progress.phase_at(what, Some(total), done);
                last = what.to_string();
            } else {
                progress.set(done);
            }
        })?;
        progress.finish();
        super::print_out(&summary(&t))?;
        tables.push(t);
    }
    Ok(())
}

/// One original's line of the report.
fn summary(t: &OriginalTables) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{}: {} polygons, tau grid {} (error {:.4}), phase {} x {} (scattered error {:.2}%, intensity error {:.2}%{}), energy residual {}, {} bytes, {} solves, {:.1} s",
        t.name,
        t.polygons,
        t.tau_grid.side(),
        t.tau_error,
        t.incoming.side(),
        t.outgoing.side(),
        100.0 * t.scattered_error,
        100.0 * t.intensity_error,
        if t.met { "" } else { ", target not met" },
        t.worst_residual()
            .iter()
            .map(|r| format!("{:.2}%", 100.0 * r))
            .collect::<Vec<_>>()
            .join(" "),
        t.bytes(),
        t.solves,
        t.seconds
    );
    for (side, e) in &t.out_tried {
        let _ = writeln!(
            s,
            "  outgoing grid {side}: intensity error {:.2}%",
            100.0 * e
        );
    }
    for (side, se, ie) in &t.tried {
        let _ = writeln!(
            s,
            "  incoming grid {side}: scattered error {:.2}%, intensity error {:.2}%",
            100.0 * se,
            100.0 * ie
        );
    }
    s
}
