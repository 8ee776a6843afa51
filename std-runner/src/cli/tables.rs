//! `hirad tables SCENE`: the directional tables of every instanced original.

use crate::files;
use crate::output::Progress;

use crate::solve::RayonExecutor;
use crate::solve::policy::Policy;
use crate::tables::{
    Cache, CheckReport, OriginalTables, TableSettings, check, instanced_originals, obtain,
    write_bidirectional, write_directions,
};
use anyhow::Result;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Arguments of `hirad tables`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  hirad tables canopy.hirb -o canopy_tables.hirb --export maize.csv\n  hirad tables poplar.hirb --original leaf --check 20 --stats checks.json"
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
    /// Largest error of the tau grid's cross-section (1 - tau) A and scattered
    /// cross-section at check directions, relative to each: the intercepted and scattered
    /// power.
    #[arg(long, default_value_t = 0.01)]
    pub tau_target: f32,
    /// Largest side of the tau grid (rays only; the cells grow fourfold per doubling).
    #[arg(long, default_value_t = 128)]
    pub max_tau_side: u32,
    /// Largest side of the grid of incoming directions (rays only; the phase table holds
    /// its cells times the outgoing grid's).
    #[arg(long, default_value_t = 32)]
    pub max_side: u32,
    /// Write the scene with the tables as a binary image (.hirb), for `solve --method hi`
    /// and for embedded callers.
    #[arg(long, short, value_name = "OUT.hirb")]
    pub output: Option<PathBuf>,
    /// Write one CSV row per original, band and incoming direction cell (tau, areas,
    /// albedo, scattered power); the bidirectional values go to FILE_bidirectional.csv
    /// beside it.
    #[arg(long, value_name = "FILE.csv")]
    pub export: Option<PathBuf>,
    /// Write one PNG per original and band into DIR (created if needed): maps over the
    /// sphere of tau, of the scattered power by sun direction and of the bidirectional
    /// intensity for one sun, each with a colour bar and its unit.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    /// Check every table at N random directions off its grids against direct simulations
    /// of the expanded original (tau by a million rays, scattered power and outgoing
    /// intensity by an hr solve); exit 1 when a check misses its target.
    #[arg(long, value_name = "N")]
    pub check: Option<u32>,
    /// Write the tables' figures (and the checks') as JSON.
    #[arg(long, value_name = "FILE.json")]
    pub stats: Option<PathBuf>,
    /// Only the originals with these names (repeatable; default: the originals `hirad solve
    /// --method hi` closes under `--instancing`).
    #[arg(long = "original", value_name = "NAME")]
    pub originals: Vec<String>,
    /// Without `--original`: the tables of the originals this policy of `hirad solve
    /// --instancing` closes (`all`: every instanced original; `auto`, the default: all but
    /// those that emit light and those of more than 8,000 polygons expanded the scene has no
    /// tables for; `every:N`: those at instancing depths 1, N + 1, ...).
    #[arg(long, conflicts_with = "originals")]
    pub instancing: Option<Policy>,
    /// Without `--original`: originals expanded in place whatever `--instancing` says, as
    /// `hirad solve --expand` (no tables made for them).
    #[arg(
        long,
        value_name = "NAME",
        value_delimiter = ',',
        conflicts_with = "originals"
    )]
    pub expand: Vec<String>,
    /// Largest side of the grid of outgoing directions (side x side suns, one solve each).
    #[arg(long, default_value_t = 32)]
    pub max_out_side: u32,
    /// Largest side of the grid of the polygons' visible fractions, which keep their first
    /// scattering apart from the phase table (for originals whose fractions fit 8 MiB; 0:
    /// the phase table holds all the scattered light).
    #[arg(long, default_value_t = 128)]
    pub max_single_side: u32,
    /// Folder of the table cache (default: $HIRAD_CACHE, else $XDG_CACHE_HOME/hirad/tables,
    /// else ~/.cache/hirad/tables). Tables are looked up by a hash of the original's
    /// geometry, materials and these settings; a damaged entry is recomputed.
    #[arg(long, value_name = "DIR")]
    pub cache: Option<PathBuf>,
    /// Neither read nor write the table cache.
    #[arg(long, conflicts_with = "cache")]
    pub no_cache: bool,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// No progress and no warnings.
    #[arg(long, short)]
    pub quiet: bool,
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
    settings.max_tau_side = a.max_tau_side;
    settings.max_out_side = a.max_out_side;
    settings.max_single_side = a.max_single_side;
    if !(a.epsilon > 0.0 && a.epsilon.is_finite()) {
        return Err(crate::exit::usage(anyhow::anyhow!(
            "--epsilon {} must be a positive number",
            a.epsilon
        )));
    }
    if !(a.tau_target > 0.0 && a.tau_target.is_finite()) {
        return Err(crate::exit::usage(anyhow::anyhow!(
            "--tau-target {} must be a positive number",
            a.tau_target
        )));
    }
    for (flag, side) in [
        ("--max-side", a.max_side),
        ("--max-tau-side", a.max_tau_side),
    ] {
        if !(4..=hirad_core::tables::grid::MAX_SIDE).contains(&side) {
            return Err(crate::exit::usage(anyhow::anyhow!(
                "{flag} {side} must be between 4 and {}",
                hirad_core::tables::grid::MAX_SIDE
            )));
        }
    }
    if a.max_single_side != 0
        && !(4..=hirad_core::tables::grid::MAX_SIDE).contains(&a.max_single_side)
    {
        return Err(crate::exit::usage(anyhow::anyhow!(
            "--max-single-side {} must be 0 (none) or between 4 and {}",
            a.max_single_side,
            hirad_core::tables::grid::MAX_SIDE
        )));
    }
    // The hr solves on every core unless told (0 or 1 would leave them on one thread).
    let threads = a
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let mut exec = RayonExecutor::new(threads)?;
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
    // Without names, the originals the policy closes.
    let closed: Option<Vec<usize>> = if a.originals.is_empty() {
        let d = super::instancing::decide_model(
            &a.scene,
            &scene,
            a.instancing.unwrap_or(Policy::Auto),
            &a.expand,
        )?;
        super::instancing::print(&d, a.quiet);
        Some(d.closed().collect())
    } else {
        None
    };
    let chosen: Vec<usize> = instanced_originals(&scene)
        .into_iter()
        .filter(|&o| match &closed {
            Some(c) => c.contains(&o),
            None => a.originals.contains(&scene.originals[o].name),
        })
        .collect();
    {
        use crate::paths::Output;
        let bidirectional = a.export.as_deref().map(bidirectional_path);
        let mut outputs = Vec::new();
        if let (Some(p), Some(b)) = (&a.export, &bidirectional) {
            outputs.push(Output {
                option: "--export",
                path: p,
            });
            outputs.push(Output {
                option: "--export (its bidirectional file)",
                path: b,
            });
        }
        if let Some(p) = &a.stats {
            outputs.push(Output {
                option: "--stats",
                path: p,
            });
        }
        if let Some(p) = &a.output {
            if files::Format::of(p).map_err(crate::exit::usage)? != files::Format::Binary {
                return Err(crate::exit::usage(anyhow::anyhow!(
                    "-o {}: tables are kept only in a binary image: name it .hirb",
                    p.display()
                )));
            }
            outputs.push(Output {
                option: "--output",
                path: p,
            });
        }
        crate::paths::check_outputs(std::slice::from_ref(&a.scene), &outputs)?;
    }
    let mut checks = Vec::new();
    if chosen.is_empty() {
        eprintln!(
            "note: {} has no instanced original: there is no table to make",
            a.scene.display()
        );
    }
    let cache = if a.no_cache {
        None
    } else {
        Cache::locate(a.cache.as_deref())
    };
    let mut cache_hits = 0u32;
    for o in chosen {
        let mut report = |what: &str, done: u64, total: u64| {
            progress.phase_at(what, Some(total), done);
        };
        let (t, hit) = obtain(&scene, o, &settings, cache.as_ref(), &mut exec, &mut report)?;
        cache_hits += u32::from(hit);
        progress.finish();
        super::print_out(&summary(&t))?;
        if let Some(n) = a.check {
            let r = check(&scene, &t, n, 0xC4EC, &settings, &mut exec, &mut report)?;
            progress.finish();
            super::print_out(&check_line(&t.name, &r))?;
            checks.push(r);
        }
        tables.push(t);
    }
    if let Some(path) = &a.export {
        let names = &scene.band_names;
        files::write_atomic(path, |w| Ok(write_directions(w, &tables, names)?))?;
        files::write_atomic(&bidirectional_path(path), |w| {
            Ok(write_bidirectional(w, &tables, names)?)
        })?;
    }
    if let Some(dir) = &a.plot {
        let written = crate::tables::write_plots(dir, &tables, &scene.band_names)?;
        super::print_out(&format!(
            "plots: {} pictures in {}\n",
            written.len(),
            dir.display()
        ))?;
    }
    if let Some(path) = &a.output {
        let mut with = scene.clone();
        for t in &tables {
            with.tables.retain(|x| x.original != t.index);
            with.tables.push(t.to_scene());
        }
        let bytes = files::compile(&a.scene, &with)?;
        files::write_atomic(path, |w| Ok(w.write_all(&bytes)?))?;
    }
    if let Some(path) = &a.stats {
        files::write_atomic(path, |w| {
            Ok(w.write_all(json(&tables, &checks, cache_hits).as_bytes())?)
        })?;
    }
    let unmet: Vec<&str> = tables
        .iter()
        .filter(|t| !t.met)
        .map(|t| t.name.as_str())
        .collect();
    let missed: Vec<&str> = tables
        .iter()
        .zip(&checks)
        .filter(|(_, r)| !r.within(&CHECK_TARGETS))
        .map(|(t, _)| t.name.as_str())
        .collect();
    if !missed.is_empty() {
        return Err(crate::exit::not_right(anyhow::anyhow!(
            "the checks of {} missed their targets (tau {}, scattered {}%, intensity {}%, energy {}%)",
            missed.join(", "),
            CHECK_TARGETS.tau,
            100.0 * CHECK_TARGETS.scattered,
            100.0 * CHECK_TARGETS.intensity,
            100.0 * CHECK_TARGETS.energy
        )));
    }
    if !unmet.is_empty() {
        return Err(crate::exit::not_right(anyhow::anyhow!(
            "the tables of {} did not meet their error targets on the finest grids allowed (see above; --max-side, --max-out-side, --max-tau-side, --max-single-side)",
            unmet.join(", ")
        )));
    }
    Ok(())
}

/// What `--check` holds a table to (issue 17's acceptance).
pub const CHECK_TARGETS: CheckReport = CheckReport {
    directions: 0,
    tau: 0.01,
    scattered: 0.02,
    intensity: 0.05,
    uniform_intensity: f32::INFINITY,
    hotspot: f32::INFINITY,
    worst: (glam::Vec3::ZERO, glam::Vec3::ZERO),
    energy: 0.005,
};

/// `tables.csv` -> `tables_bidirectional.csv`.
fn bidirectional_path(path: &std::path::Path) -> PathBuf {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!("{stem}_bidirectional.csv"))
}

fn check_line(name: &str, r: &CheckReport) -> String {
    format!(
        "{name}: checked at {} directions: tau off by {:.4}, scattered {:.2}%, intensity {:.2}% (worst towards the sun {:.3} {:.3} {:.3}, the observer {:.3} {:.3} {:.3}; uniform form {:.2}%; at the hot spot {:.2}%), energy {:.3}%\n",
        r.directions,
        r.tau,
        100.0 * r.scattered,
        100.0 * r.intensity,
        r.worst.0.x,
        r.worst.0.y,
        r.worst.0.z,
        r.worst.1.x,
        r.worst.1.y,
        r.worst.1.z,
        100.0 * r.uniform_intensity,
        100.0 * r.hotspot,
        100.0 * r.energy
    )
}

/// The tables' figures and checks as one JSON object.
fn json(tables: &[OriginalTables], checks: &[CheckReport], cache_hits: u32) -> String {
    let mut s = format!("{{\n  \"cache_hits\": {cache_hits},\n  \"originals\": [");
    for (i, t) in tables.iter().enumerate() {
        let check = checks.get(i).map_or("null".to_string(), |r| {
            format!(
                "{{\"directions\": {}, \"tau\": {}, \"scattered\": {}, \"intensity\": {}, \"uniform_intensity\": {}, \"hotspot\": {}, \"energy\": {}}}",
                r.directions, r.tau, r.scattered, r.intensity, r.uniform_intensity, r.hotspot, r.energy
            )
        });
        let _ = write!(
            s,
            "{}\n    {{\"name\": {}, \"polygons\": {}, \"tau_side\": {}, \"tau_error\": {}, \"incoming_side\": {}, \"outgoing_side\": {}, \"scatterers\": {}, \"single_side\": {}, \"single_error\": {}, \"scattered_error\": {}, \"intensity_error\": {}, \"met\": {}, \"energy_residual\": [{}], \"bytes\": {}, \"solves\": {}, \"rays\": {}, \"seconds\": {:.3}, \"check\": {}}}",
            if i == 0 { "" } else { "," },
            super::info::json_str(&t.name),
            t.polygons,
            t.tau_grid.side(),
            t.tau_error,
            t.incoming.side(),
            t.outgoing.side(),
            t.single.as_ref().map_or(0, |x| x.polygons),
            t.single.as_ref().map_or(0, |x| x.grid.side()),
            t.single
                .as_ref()
                .and_then(|x| x.tried.last())
                .map_or("null".to_string(), |e| e.1.to_string()),
            t.scattered_error,
            t.intensity_error,
            t.met,
            t.worst_residual()
                .iter()
                .map(|r| r.to_string())
                .collect::<Vec<_>>()
                .join(", "),
            t.bytes(),
            t.solves,
            t.rays,
            t.seconds,
            check
        );
    }
    s.push_str("\n  ]\n}\n");
    s
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
    if t.solves == 0 {
        s.insert_str(s.len() - 1, " (from the cache)");
    }
    if let Some(x) = &t.single {
        let _ = writeln!(
            s,
            "  first scattering of its {} polygons kept apart on grid {}",
            x.polygons,
            x.grid.side()
        );
        for (side, e) in &x.tried {
            let _ = writeln!(s, "  first scattering grid {side}: error {:.2}%", 100.0 * e);
        }
    }
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
