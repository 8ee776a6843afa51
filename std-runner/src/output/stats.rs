//! What a solve did and what it cost (design principle 6): the `--stats` JSON object and the
//! summary printed on stderr after every run.

use super::reference::{Comparison, WorstPolygon};
use crate::files::write_atomic;
use serde::{Deserialize, Serialize};
use std::io::{self, Write};
use std::path::Path;

/// Where the power of one band went (W).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BandPower {
    /// The band's name (or its index when the scene names none).
    pub band: String,
    /// Emitted by surfaces.
    pub emitted: f64,
    /// Direct light of suns and sky reaching surfaces.
    pub direct: f64,
    /// Absorbed by the receiving sides of surfaces.
    pub absorbed: f64,
    /// Absorbed by the backs of one-sided polygons (and inside closed objects).
    pub absorbed_backs: f64,
    /// Leaving the scene.
    pub escaped: f64,
    /// `emitted + direct - absorbed - absorbed_backs - escaped`.
    pub imbalance: f64,
    /// The imbalance in percent of what enters (`emitted + direct`).
    pub imbalance_percent: f64,
}

/// Wall-clock time of one phase of a solve.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PhaseTime {
    /// The phase ("setup", "lighting patches", "evaluating links", "refining", "closing",
    /// "solving", "power balance", "final gather: relighting patches", "final gather:
    /// solving again", "final gather: polygons and output").
    pub phase: String,
    /// Seconds spent in it, summed over every time it ran.
    pub seconds: f64,
}

fn yes() -> bool {
    true
}

/// Every setting a solve ran with, as given or chosen (`null` where the method has no such
/// setting), so that a stats file says how to repeat its run.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RunSettings {
    /// `--method`: `hr` or `exact`.
    pub method: String,
    /// `--epsilon` (hr): refinement threshold, dimensionless.
    pub epsilon: Option<f64>,
    /// `--rays` (hr): visibility rays per receiver point and link.
    pub rays: Option<u32>,
    /// `--final-rays` (hr): `"auto"` or rays per receiving side.
    pub final_rays: Option<String>,
    /// `--final-passes` (hr): `"auto"` or a count.
    pub final_passes: Option<String>,
    /// `--min-area` (hr): smallest patch, fraction of the scene's polygon area.
    pub min_area: Option<f64>,
    /// `--tolerance`: convergence tolerance, relative to the largest radiosity.
    pub tolerance: f64,
    /// `--max-iterations` (hr).
    pub max_iterations: Option<u32>,
    /// `--max-imbalance` (hr): largest power imbalance a run may end with and pass (%).
    pub max_imbalance_percent: Option<f64>,
    /// `--memory` (hr): workspace bytes asked; `null` for the planner's suggestion.
    pub memory_bytes: Option<u64>,
    /// `--visibility` (hr): the ray caster, `obvhs` or `core`.
    pub visibility: Option<String>,
    /// `--blocking-polygons` (hi): closed instances of originals of at most this many
    /// polygons block with them, larger ones by `tau`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub blocking_polygons: Option<u32>,
    /// `--own-polygons` (hi) as asked: a level's closed approximate instances block with the
    /// polygons they hold when they hold at most this many together.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub own_polygons: Option<u32>,
    /// `--instancing` (hi): `all` (every level's instances closed, then opened in turn) or
    /// `none` (every instance expanded: hr's solver and results).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub instancing: Option<String>,
    /// `--elements` (exact): element budget.
    pub elements: Option<u64>,
    /// `--threads` asked; `null` for every core.
    pub threads: Option<u32>,
    /// The picture's settings (`null` without `--image`).
    pub image: Option<ImageSettings>,
}

/// How the picture was made.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ImageSettings {
    /// Width and height in pixels.
    pub size: [u32; 2],
    /// The camera used, in `--camera` form (position, target, up, vertical field of view).
    pub camera: String,
    /// Samples per pixel side.
    pub supersample: u32,
    /// `--display-bands` as given (`null`: the default for the scene's bands).
    pub display_bands: Option<String>,
    /// `--display` as given (`map` or `bands`; `null`: the default for the scene's bands).
    #[serde(default)]
    pub display: Option<String>,
    /// `--shading`: `smooth` or `flat`.
    #[serde(default)]
    pub shading: String,
}

/// A file the run wrote.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct OutputFile {
    /// The option that named it (`--results`, `--image`, `--stats`).
    pub option: String,
    /// Its path as given.
    pub path: String,
}

/// Whether the run's numbers are right, and why not.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Verdict {
    /// True when every check passed (the run exits 0).
    pub passed: bool,
    /// Why it failed, or what it passed with (a warning about the power balance), or
    /// "every check passed".
    pub reason: String,
}

/// Hierarchical instantiation's levels (`hirad solve --method hi`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Levels {
    /// Levels solved: the top level and every instance opened.
    pub solved: u64,
    /// The deepest level opened (the top level is 0).
    pub deepest: u32,
    /// Closed instances over all levels.
    pub closed_instances: u64,
    /// `--own-polygons` as solved: as asked, or 0 where a `--memory` budget below hi's
    /// least with them turned them off.
    #[serde(default)]
    pub own_polygons: u32,
    /// `--blocking-polygons` as solved: as asked, or 0 where a `--memory` budget below hi's
    /// least with them turned them off (closed instances then block by their tables'
    /// transmittance).
    #[serde(default)]
    pub blocking_polygons: u32,
    /// Closed approximate instances that blocked rays with the polygons they hold.
    #[serde(default)]
    pub own_blocking_instances: u64,
    /// Levels solved in jobs beside their siblings' (opened together, one per thread).
    #[serde(default)]
    pub levels_together: u64,
    /// Instances opened again alone after their job's part of the workspace proved too
    /// small.
    #[serde(default)]
    pub opened_again: u64,
    /// The most leaf elements (leaf patches and closed instances) one level held.
    #[serde(alias = "largest_level_patches")]
    pub largest_level_leaves: u64,
    /// Levels by their leaf elements (what one local solve holds; the paper's figure 4,
    /// right), in bins doubling in size, empty bins left out.
    #[serde(default)]
    pub leaf_histogram: Vec<LeafBin>,
    /// Per level depth (the top level first), the most workspace in use while a level of
    /// that depth was solved, its ancestors' part below it on the stack included (bytes).
    #[serde(default)]
    pub peak_workspace_bytes_by_depth: Vec<u64>,
    /// The top level's workspace by what it holds (bytes).
    #[serde(default)]
    pub top_level_bytes: TopLevelBytes,
}

/// The top level's workspace by what it holds (bytes; see
/// `hirad_core::hr::WorkspaceRegions`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TopLevelBytes {
    /// Materials, polygons, clusters, sources, the walkers' stacks.
    pub scene: u64,
    /// Closed instances' records, their BVH, their transmittance towards each source.
    pub instances: u64,
    /// The light the closed instances received.
    pub received_light: u64,
    /// The closed originals' tables.
    pub tables: u64,
    /// The originals' own polygons and BVHs, for the instances that block with them.
    pub blocking_geometry: u64,
    /// The light between closed instances: laid out, and written (the rest is never
    /// touched).
    pub exchange_laid_out: u64,
    pub exchange_written: u64,
    /// The radiance closed instances show gather rays.
    pub noted_radiance: u64,
    /// Patches, links and bins.
    pub patches_and_links: u64,
    /// The core's BVH over the level's polygons and the executor's scratch.
    pub bvh_and_scratch: u64,
}

/// The directional tables a `--method hi` run made or read from the cache.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TablesMade {
    /// The originals, by name.
    pub originals: Vec<String>,
    /// How many came from the table cache.
    pub cache_hits: u32,
    /// Those whose tables missed their error targets on the finest grids allowed.
    pub targets_missed: Vec<String>,
    /// Wall-clock seconds, cache reads included.
    pub seconds: f64,
}

/// One bin of [`Levels::leaf_histogram`]: the levels that held from `leaves_from` to
/// `leaves_to` leaf elements (both included).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LeafBin {
    pub leaves_from: u64,
    pub leaves_to: u64,
    pub levels: u64,
}

impl Levels {
    /// The levels of a solve's statistics.
    /// `own_polygons`, `blocking_polygons`: the settings as solved.
    pub fn of(s: &hirad_core::hr::Stats, own_polygons: u32, blocking_polygons: u32) -> Levels {
        let leaf_histogram = s
            .leaf_histogram
            .iter()
            .enumerate()
            .filter(|&(_, &n)| n > 0)
            .map(|(k, &levels)| LeafBin {
                leaves_from: if k == 0 { 0 } else { 1 << k },
                leaves_to: (1u64 << (k + 1)) - 1,
                levels,
            })
            .collect();
        let depths = (s.level_depth as usize + 1).min(s.peak_bytes_by_depth.len());
        Levels {
            solved: s.levels,
            deepest: s.level_depth,
            closed_instances: s.closed_instances,
            own_polygons,
            blocking_polygons,
            own_blocking_instances: s.own_blocking_instances,
            levels_together: s.levels_together,
            opened_again: s.opened_again,
            largest_level_leaves: s.largest_level,
            leaf_histogram,
            peak_workspace_bytes_by_depth: s.peak_bytes_by_depth[..depths].to_vec(),
            top_level_bytes: {
                let r = &s.top_regions;
                TopLevelBytes {
                    scene: r.scene,
                    instances: r.instances,
                    received_light: r.received,
                    tables: r.tables,
                    blocking_geometry: r.blocking,
                    exchange_laid_out: r.exchange,
                    exchange_written: r.exchange_written,
                    noted_radiance: r.radiance,
                    patches_and_links: r.blocks,
                    bvh_and_scratch: r.bvh_scratch,
                }
            },
        }
    }
}

/// Settings, counts, time, memory and error of one solve.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SolveReport {
    /// The hirad version that ran.
    #[serde(default)]
    pub hirad_version: String,
    /// The scene file as given.
    #[serde(default)]
    pub scene: String,
    /// Every setting of the run.
    #[serde(default)]
    pub settings: Option<RunSettings>,
    /// The files written (this stats file included).
    #[serde(default)]
    pub outputs: Vec<OutputFile>,
    /// Whether the numbers are right (`null` in files from before verdicts).
    #[serde(default)]
    pub verdict: Option<Verdict>,
    /// Solver: `hr` (hierarchical radiosity, the scene expanded), `hi` (hierarchical
    /// instantiation) or `exact`.
    pub method: String,
    /// Refinement threshold epsilon (dimensionless: a link is refined while its transfer
    /// exceeds epsilon times the scene's emitted power); `null` for the exact solver, which
    /// has none.
    pub epsilon: Option<f64>,
    /// Worker threads.
    pub threads: u32,
    /// Polygons of the expanded scene (rows of the results table).
    pub polygons: u64,
    /// Elements (clusters, polygons and sub-patches) created, summed over all levels.
    pub elements: u64,
    /// Links created, summed over all levels.
    pub links: u64,
    /// Gather / push-pull iterations, summed over all levels.
    pub iterations: u64,
    /// Refinement passes, summed over all levels.
    pub refinement_passes: u64,
    /// Wall-clock time of the solve (s).
    pub seconds: f64,
    /// Most bytes of the workspace in use at once.
    pub peak_workspace_bytes: u64,
    /// Size of the workspace the solve was given (bytes).
    pub workspace_bytes: u64,
    /// True when a full pool stopped refinement: the result is coarser than epsilon asked.
    pub budget_limited: bool,
    /// Error against the reference (percent of its largest radiosity; see
    /// [`super::reference`]); `null` without a reference.
    pub error_percent: Option<f64>,
    /// The same error per band; empty without a reference.
    #[serde(default)]
    pub error_per_band_percent: Vec<f64>,
    /// Largest absolute radiosity difference from the reference (W/m^2); `null` without one.
    #[serde(default)]
    pub max_abs_difference: Option<f64>,
    /// The polygons with the largest relative radiosity error against the reference, largest
    /// first (see [`super::reference`]: only columns whose reference value is at least 0.1%
    /// of its largest count); empty without a reference.
    #[serde(default)]
    pub worst_polygons: Vec<WorstPolygon>,
    /// True when the solution met its tolerance; false when it stopped at the iteration cap
    /// (the run then ends with an error after writing its outputs).
    #[serde(default = "yes")]
    pub converged: bool,
    /// True when a radiosity grew without bound (hr): the solution means nothing and the run
    /// fails.
    #[serde(default)]
    pub diverged: bool,
    /// The estimated change still to come, relative to the largest radiosity (hr); `null`
    /// when not estimated.
    #[serde(default)]
    pub remaining_change: Option<f64>,
    /// Where the power went, per band (both solvers; the exact solver's escaped and
    /// back-absorbed light come from rays, see `exact::balance`).
    #[serde(default)]
    pub power: Vec<BandPower>,
    /// Seconds per phase, in the order the phases first ran (hr; empty for the exact
    /// solver). Phases that run every round (refining, evaluating links) add up.
    #[serde(default)]
    pub phases: Vec<PhaseTime>,
    /// Rays cast (hr: direct light and exposure, link visibility, final gather; the power
    /// balance's own rays are not counted).
    #[serde(default)]
    pub rays: u64,
    /// Of `rays`, those of each phase (hr; `null` for the exact solver).
    #[serde(default)]
    pub rays_by_phase: Option<RaysByPhase>,
    /// Hierarchical instantiation's levels (`null` for the other methods).
    #[serde(default)]
    pub levels: Option<Levels>,
    /// The directional tables this run took from the table cache or made (`--method hi` on
    /// a scene without them; `null` otherwise). Their time is not in `phases`' solve.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tables: Option<TablesMade>,
    /// Final gather passes made, the polygons' own included (hr; 0 without the gather;
    /// `null` for the exact solver).
    #[serde(default)]
    pub final_passes: Option<u32>,
    /// How much the gather's last relighting pass moved the light leaving the surfaces, in
    /// percent of what enters (largest band; `null` with fewer than two passes). The passes
    /// stop, when their number is automatic, once a pass moves it by less than 0.5%.
    #[serde(default)]
    pub final_change_percent: Option<f64>,
    /// Relative L2 error of the picture against `--reference-image`, in percent (see
    /// `output::image_compare`); `null` without one.
    #[serde(default)]
    pub image_error_percent: Option<f64>,
}

/// Rays cast per phase of a hierarchical solve.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RaysByPhase {
    /// Direct light of suns and sky on every patch and its buried points.
    pub lighting: u64,
    /// Visibility of links.
    pub links: u64,
    /// The final gather: relighting passes and the polygons' own gather.
    pub final_gather: u64,
}

impl SolveReport {
    /// Records a comparison against a reference.
    pub fn set_comparison(&mut self, c: &Comparison) {
        self.error_percent = Some(c.error_percent);
        self.error_per_band_percent = c.per_band_percent.clone();
        self.max_abs_difference = Some(c.max_abs_difference);
        self.worst_polygons = c.worst.clone();
    }

    /// The report as one pretty-printed JSON object.
    pub fn to_json(&self) -> String {
        // Serialising plain numbers, strings and options cannot fail; non-finite numbers
        // become null.
        serde_json::to_string_pretty(self).unwrap_or_else(|e| format!("{{\"error\":\"{e}\"}}"))
    }

    /// Parses a report written by [`SolveReport::to_json`].
    pub fn from_json(text: &str) -> serde_json::Result<Self> {
        serde_json::from_str(text)
    }

    /// Writes the JSON object (and a final newline) to `path` atomically.
    pub fn write_json(&self, path: &Path) -> anyhow::Result<()> {
        let json = self.to_json();
        write_atomic(path, |w| {
            w.write_all(json.as_bytes())?;
            w.write_all(b"\n")?;
            Ok(())
        })
    }

    /// The human summary: settings, time, peak memory, links, elements and error.
    pub fn print_summary(&self, out: &mut dyn Write) -> io::Result<()> {
        let epsilon = self
            .epsilon
            .map(|e| format!(", epsilon {e}"))
            .unwrap_or_default();
        let memory = if self.method == "exact" {
            "form factor matrix"
        } else {
            "workspace"
        };
        writeln!(
            out,
            "solve: method {}{epsilon}, {} thread{}, {memory} {}",
            self.method,
            self.threads,
            if self.threads == 1 { "" } else { "s" },
            bytes(self.workspace_bytes)
        )?;
        if self.method == "exact" {
            writeln!(out, "  time {:.3} s", self.seconds)?;
        } else {
            writeln!(
                out,
                "  time {:.3} s, peak memory {} of the workspace",
                self.seconds,
                bytes(self.peak_workspace_bytes)
            )?;
        }
        if !self.phases.is_empty() {
            let parts: Vec<String> = self
                .phases
                .iter()
                .map(|p| format!("{} {:.3} s", p.phase, p.seconds))
                .collect();
            write!(out, "  phases: {}; {} rays", parts.join(", "), self.rays)?;
            match self.rays_by_phase {
                Some(r) => writeln!(
                    out,
                    " (lighting {}, links {}, final gather {})",
                    r.lighting, r.links, r.final_gather
                )?,
                None => writeln!(out)?,
            }
        }
        match (self.final_passes, self.final_change_percent) {
            (Some(n), Some(moved)) if n > 1 => writeln!(
                out,
                "  final gather: {n} passes (the last relighting pass moved the leaving light by {moved:.2}% of what enters)"
            )?,
            (Some(1), _) => writeln!(out, "  final gather: 1 pass")?,
            _ => {}
        }
        writeln!(
            out,
            "  {} polygons, {} elements, {} links, {} iterations, {} refinement passes",
            self.polygons, self.elements, self.links, self.iterations, self.refinement_passes
        )?;
        if let Some(t) = &self.tables {
            writeln!(
                out,
                "  tables: {} original{} ({}) in {:.3} s, {} from the table cache{}",
                t.originals.len(),
                if t.originals.len() == 1 { "" } else { "s" },
                t.originals.join(", "),
                t.seconds,
                t.cache_hits,
                if t.targets_missed.is_empty() {
                    String::new()
                } else {
                    format!("; targets missed: {}", t.targets_missed.join(", "))
                }
            )?;
        }
        if let Some(l) = &self.levels {
            let bins: Vec<String> = l
                .leaf_histogram
                .iter()
                .map(|b| format!("{}-{}: {}", b.leaves_from, b.leaves_to, b.levels))
                .collect();
            let peaks: Vec<String> = l
                .peak_workspace_bytes_by_depth
                .iter()
                .map(|&b| bytes(b))
                .collect();
            writeln!(
                out,
                "  levels: {} solved (deepest {}; {} of them beside their siblings', {} opened again alone), {} closed instances ({} blocking with their own polygons); levels by leaf elements {}; peak workspace by depth {}",
                l.solved,
                l.deepest,
                l.levels_together,
                l.opened_again,
                l.closed_instances,
                l.own_blocking_instances,
                bins.join(", "),
                peaks.join(", ")
            )?;
        }
        if self.budget_limited {
            writeln!(
                out,
                "  the memory budget limited refinement: the result is coarser than epsilon asked"
            )?;
        }
        match self.error_percent {
            Some(e) => {
                write!(out, "  error {e:.4} % of the reference's largest radiosity")?;
                if self.error_per_band_percent.len() > 1 {
                    let bands: Vec<String> = self
                        .error_per_band_percent
                        .iter()
                        .map(|b| format!("{b:.4}"))
                        .collect();
                    write!(out, " (per band {} %)", bands.join(", "))?;
                }
                if let Some(m) = self.max_abs_difference {
                    write!(out, "; largest difference {m} W/m^2")?;
                }
                writeln!(out)
            }
            // Not an error: nothing to compare with (a line starting "error:" means one).
            None => writeln!(
                out,
                "  accuracy: not measured (--reference REF.csv compares with a results table)"
            ),
        }?;
        if !self.power.is_empty() {
            writeln!(
                out,
                "  power (W): in = emitted + direct light; out = absorbed (+ by backs) + escaped"
            )?;
            for p in &self.power {
                writeln!(
                    out,
                    "    {}: in {:.6} (emitted {:.6}, direct {:.6}), absorbed {:.6} + {:.6} by backs, escaped {:.6}, imbalance {:+.3} %",
                    p.band,
                    p.emitted + p.direct,
                    p.emitted,
                    p.direct,
                    p.absorbed,
                    p.absorbed_backs,
                    p.escaped,
                    p.imbalance_percent
                )?;
            }
        }
        if self.diverged {
            return writeln!(out, "  DIVERGED: a radiosity grew without bound");
        }
        match (self.converged, self.remaining_change) {
            (true, Some(r)) => writeln!(
                out,
                "  converged (estimated change still to come {r:.1e} of the largest radiosity)"
            ),
            (true, None) => Ok(()),
            (false, r) => writeln!(
                out,
                "  NOT converged: the solution stopped at the iteration cap{}",
                r.map(|r| format!(
                    " (estimated change still to come {r:.1e} of the largest radiosity)"
                ))
                .unwrap_or_default()
            ),
        }
    }
}

/// A byte count for people: B, KiB, MiB or GiB.
pub fn bytes(n: u64) -> String {
    const UNITS: [&str; 4] = ["B", "KiB", "MiB", "GiB"];
    let mut value = n as f64;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < UNITS.len() {
        value /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{n} B")
    } else {
        format!("{value:.1} {}", UNITS[unit])
    }
}
