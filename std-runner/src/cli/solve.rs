//! `hirad solve SCENE`: radiosity of every polygon, with a results table, an image, stats and
//! the error against a reference.

use super::instancing;
use super::verdict;
use crate::exact::{self, ExactSettings};
use crate::exit::{input, not_right, usage};
use crate::files;
use crate::output::{self, ImageSink, Outputs, Progress, ReferenceSink, ResultsFile, SolveReport};
use crate::solve::policy::{Decision, Policy};
use crate::solve::{self, VisibilityChoice};
use anyhow::{Context, Result, anyhow};
use hirad_core::hr::Settings;
use std::path::PathBuf;
use std::time::Instant;

/// The solvers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Method {
    /// Hierarchical radiosity with clustering over the expanded scene.
    Hr,
    /// Hierarchical instantiation (the paper's method): the scene solved level by level,
    /// instances closed through their originals' directional tables and opened one at a
    /// time, so that memory holds one path of levels. Needs the tables in the image
    /// (`hirad tables SCENE -o OUT.hirb`); uses the core's own BVH.
    Hi,
    /// Classic full-matrix radiosity on a uniformly subdivided mesh (the reference; scenes
    /// of a few thousand elements).
    Exact,
}

/// Arguments of `hirad solve`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  hirad solve fixtures/chair_room.hir --results room.csv --image room.png\n  hirad solve model.obj --epsilon 1e-4 --stats run.json   # finer and slower\n  hirad solve model.obj --reference ref.csv   # ref.csv: from --method exact"
)]
pub struct Args {
    /// Scene file (.hir, .hirb or .obj).
    pub scene: PathBuf,
    /// Solver.
    #[arg(long, value_enum, default_value_t = Method::Hr)]
    pub method: Method,
    /// Which instances `--method hi` keeps closed: `all` (each level's instances closed
    /// through their tables, then opened one at a time), `every:N` (the instances at
    /// instancing depths 1, N + 1, 2N + 1, ... closed, the others expanded in place in their
    /// parent's level), `auto` (closed, except originals that emit light and, when the scene
    /// has no tables for them, originals of more than 8,000 polygons expanded; what it
    /// chose is printed) or `none` (every instance expanded: `--method hr`, results
    /// identical). Default: `auto` with `--method hi`.
    #[arg(long)]
    pub instancing: Option<Policy>,
    /// Largest side of every direction grid of the tables `--method hi` makes for originals
    /// the scene has none for (4 to 128; default: those of `hirad tables`): coarser tables,
    /// made faster. Tables come from the table cache when it holds them.
    #[arg(long, value_parser = clap::value_parser!(u32).range(4..=128))]
    pub table_max_side: Option<u32>,
    /// Refinement threshold (hr): a link is refined while its transfer exceeds epsilon times
    /// the scene's emitted power. Dimensionless; smaller is finer and slower.
    #[arg(long, default_value_t = 1e-3)]
    pub epsilon: f32,
    /// Worker threads, 1 to 1024 (results are identical for any count). Default: every core.
    #[arg(long, value_parser = clap::value_parser!(u16).range(1..=1024))]
    pub threads: Option<u16>,
    /// Workspace size, e.g. 64M, 2G, 500000000 (bytes; K/M/G are powers of 1024). Default:
    /// the planner's suggestion (for hi its own plan: the top level and room for its closed
    /// instances side by side). A full workspace stops refinement and is reported.
    #[arg(long, value_parser = parse_bytes)]
    pub memory: Option<u64>,
    /// Write one row per input polygon, in global-id order, to this CSV file.
    #[arg(long)]
    pub results: Option<PathBuf>,
    /// Write the run's settings, counts, time, memory and error to this JSON file.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Render radiance (B/pi) from the camera: .exr (linear float) or .png (tone-mapped).
    #[arg(long)]
    pub image: Option<PathBuf>,
    /// Camera "px,py,pz,tx,ty,tz,ux,uy,uz,fovy_deg" (position, target, up, vertical field of
    /// view); default: the scene's first camera, else the view that shows most of the scene:
    /// from around it (its corners and sides, from above and to the side when that shows as
    /// much), or from inside a closed room. A picture that comes out nearly black says why.
    #[arg(long, allow_hyphen_values = true)]
    pub camera: Option<String>,
    /// The scene's up axis for the default view: x, y, z, -x, -y or -z. Default: y for an OBJ
    /// (the convention), else the first camera's up, else the sky's zenith, else z.
    #[arg(long, allow_hyphen_values = true, value_parser = super::parse_up)]
    pub up: Option<crate::scene::Up>,
    /// Image size in pixels, WxH (default 640x480).
    #[arg(long)]
    pub size: Option<String>,
    /// What a PNG shows: `map` is one band (PAR, else the first) as radiosity (W/m^2)
    /// through the viridis colour map with a labelled colour bar; `bands` shows bands as
    /// colours (see --display-bands). Default: `map` for a PAR/NIR scene, else `bands`.
    #[arg(long, value_enum)]
    pub display: Option<output::DisplayMode>,
    /// Bands a PNG shows as colours (implies --display bands): one band (grey) or three as
    /// red,green,blue, by name or index, e.g. `par`, `nir,par,par`. Default: grey for 1
    /// band, `nir,par,par` false colour for 2 (as colour-infrared pictures), the first three
    /// as R,G,B otherwise.
    #[arg(long)]
    pub display_bands: Option<String>,
    /// How an image colours the patches: `smooth` interpolates radiosity across the corners
    /// patches share on one surface (not across creases over 30 degrees or material
    /// boundaries); `flat` shows every element in its own value (the mesh).
    #[arg(long, value_enum, default_value_t = output::Shading::Smooth)]
    pub shading: output::Shading,
    /// Samples per pixel side (N x N per pixel; default 1).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=crate::output::raster::MAX_SUPERSAMPLE as i64))]
    pub supersample: Option<u32>,
    /// Compare with this results table and print the L2 error (area-weighted, in percent of
    /// the reference's largest radiosity) and the five polygons with the largest relative
    /// error (where the reference is at least 0.1% of its largest).
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Compare the picture (--image, an .exr) with this EXR of the same view and size (e.g.
    /// from --method exact) and print its relative L2 error in percent.
    #[arg(long)]
    pub reference_image: Option<PathBuf>,
    /// Ray caster for hr.
    #[arg(long, value_enum, default_value_t = VisibilityChoice::Obvhs)]
    pub visibility: VisibilityChoice,
    /// Visibility rays per receiver point and link.
    #[arg(long, default_value_t = Settings::default().rays,
          value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub rays: u32,
    /// Closed instances (hi) whose original has at most this many polygons, once expanded,
    /// block rays with the original's own polygons (their shadows are the contents' own, at
    /// about 120 bytes of workspace per polygon of each such original); larger ones block as
    /// a medium, by their tables' transmittance. 0: all by transmittance; values above
    /// 1,048,575 count as that.
    #[arg(long, default_value_t = Settings::BLOCKING_POLYGONS)]
    pub blocking_polygons: u32,
    /// A level's closed approximate instances (hi; each its own geometry in the file, its
    /// original standing in for it through the tables) block rays with their own polygons,
    /// each of at most --blocking-polygons, when all of them together hold at most this
    /// many (about 120 bytes of workspace each, per level): a ray meets the leaves really
    /// there. Else they block as their original does. 0: never.
    #[arg(long, default_value_t = Settings::OWN_POLYGONS)]
    pub own_polygons: u32,
    /// Final gather (hr): rays per receiving side of every polygon, from which each polygon
    /// takes its own light; `auto` spreads about a million rays over the scene (64 to 16384
    /// per side), `0` keeps the hierarchy's irradiance (faster, right on average only).
    #[arg(long, default_value = "auto", value_parser = parse_final_rays)]
    pub final_rays: u32,
    /// Final gather passes (1..=4): with 2 or more every patch gathers its own light first
    /// (each such pass costs about half the polygons' gather; the first also solves the
    /// hierarchy again with what it changed); `auto` relights at least
    /// once and again while a pass still moves the leaving light by 0.5% of what enters.
    #[arg(long, default_value = "auto", value_parser = parse_final_passes)]
    pub final_passes: u32,
    /// Smallest patch (hr), as a fraction of the scene's total polygon area.
    #[arg(long, default_value_t = Settings::default().min_area)]
    pub min_area: f32,
    /// Convergence tolerance, relative to the largest radiosity.
    #[arg(long, default_value_t = Settings::default().tolerance)]
    pub tolerance: f32,
    /// Most gather / push-pull iterations per solution (hr). A solution that reaches it
    /// before meeting the tolerance is reported as not converged and the run fails.
    #[arg(long, default_value_t = Settings::default().max_iterations,
          value_parser = clap::value_parser!(u32).range(1..))]
    pub max_iterations: u32,
    /// Largest power imbalance (hr, % of what enters, any band) a solve may end with and
    /// succeed: light the transport lost or made (see the summary's power lines). Above 1% a
    /// warning says so; above this the outputs are written and the run fails.
    #[arg(long, default_value_t = 5.0)]
    pub max_imbalance: f64,
    /// Element budget of the exact solver (its matrix grows as the square).
    #[arg(long, default_value_t = ExactSettings::default().max_elements as u64,
          value_parser = clap::value_parser!(u64).range(1..))]
    pub elements: u64,
    /// No progress bar, warnings or summary.
    #[arg(long, short)]
    pub quiet: bool,
}

/// `123`, `64K`, `64M`, `2G`, `1.5GiB` -> bytes (K, M, G, T are powers of 1024).
pub fn parse_bytes(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let value: f64 = num.parse().map_err(|_| {
        format!("'{s}' is not a size: expected a number with an optional K, M, G or T")
    })?;
    let mult: f64 = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 1.0,
        "k" | "kb" | "kib" => 1024.0,
        "m" | "mb" | "mib" => 1024.0 * 1024.0,
        "g" | "gb" | "gib" => 1024.0 * 1024.0 * 1024.0,
        "t" | "tb" | "tib" => 1024.0 * 1024.0 * 1024.0 * 1024.0,
        u => return Err(format!("'{s}': unknown unit '{u}' (use K, M, G or T)")),
    };
    let bytes = value * mult;
    if !bytes.is_finite() || !(1.0..=9.0e18).contains(&bytes) {
        return Err(format!("'{s}' is not a usable size"));
    }
    Ok(bytes as u64)
}

/// Runs `hirad solve`.
pub fn run(a: Args) -> Result<()> {
    let start = Instant::now();
    let refuse = |m: String| Err(usage(anyhow!(m)));
    if a.instancing.is_some() && a.method != Method::Hi {
        return refuse(format!(
            "--instancing chooses which instances --method hi keeps closed; --method {} expands every instance",
            if a.method == Method::Hr {
                "hr"
            } else {
                "exact"
            }
        ));
    }
    // `hi` with every instance expanded is hierarchical radiosity over the whole scene: the
    // same solver, and the same results, as `--method hr`.
    let instancing = (a.method == Method::Hi).then(|| a.instancing.unwrap_or(Policy::Auto));
    let a = Args {
        method: if instancing == Some(Policy::None) {
            Method::Hr
        } else {
            a.method
        },
        ..a
    };
    if !(a.epsilon.is_finite() && a.epsilon > 0.0) {
        return refuse(format!(
            "--epsilon must be a positive number, got {}",
            a.epsilon
        ));
    }
    if !(a.min_area.is_finite() && (0.0..1.0).contains(&a.min_area)) {
        return refuse(format!("--min-area must lie in [0, 1), got {}", a.min_area));
    }
    if !(a.tolerance.is_finite() && a.tolerance > 0.0) {
        return refuse(format!(
            "--tolerance must be a positive number, got {}",
            a.tolerance
        ));
    }
    if !(a.max_imbalance.is_finite() && a.max_imbalance >= 0.0) {
        return refuse(format!(
            "--max-imbalance must be a percentage of at least 0, got {}",
            a.max_imbalance
        ));
    }
    // Counts are range-checked as clap parses them (1..=1024 threads: 100,000 aborted the
    // process setting up their stacks).
    let threads = match a.threads {
        Some(n) => n as usize,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    warn_unused(&a);
    // Hierarchical instantiation from a `.hirb` that holds every table it needs reads the
    // file on demand: its tables go into the workspace once, and the model keeps only their
    // records (a canopy's are 20 MB a copy: loading them twice over was the run's peak).
    let binary_hi = a.method == Method::Hi
        && files::Format::of(&a.scene).is_ok_and(|f| f == files::Format::Binary);
    // Which originals hi closes (`--instancing`), decided on the file's image where there is
    // one, else on the loaded scene's.
    let mut decision: Option<Decision> = match instancing {
        Some(p) if binary_hi => Some(instancing::decide(
            &a.scene,
            &files::open_image(&a.scene)?,
            p,
        )?),
        _ => None,
    };
    let mut loaded = if binary_hi {
        let lean = files::load_scene_records(&a.scene)?;
        let closed: Vec<usize> = decision.iter().flat_map(|d| d.closed()).collect();
        if crate::tables::missing_of(&lean.scene, &closed).is_empty() {
            lean
        } else {
            files::load_scene(&a.scene)?
        }
    } else {
        files::load_scene(&a.scene)?
    };
    super::warn_all(&loaded.warnings, loaded.warnings_total, a.quiet);
    if let (Some(p), None) = (instancing, &decision)
        && p != Policy::None
    {
        decision = Some(instancing::decide_model(&a.scene, &loaded.scene, p)?);
    }
    if let Some(d) = &decision {
        instancing::print(d, a.quiet);
        instancing::refuse_closed_emitter(d)?;
    }
    let progress = Progress::new(a.quiet);
    let closed: Vec<usize> = decision.iter().flat_map(|d| d.closed()).collect();
    let tables_made =
        super::solve_tables::complete(&a, &mut loaded.scene, &closed, threads, &progress)?;
    let up = a.up.unwrap_or(loaded.up);
    let image = if binary_hi && tables_made.is_none() {
        Some(files::open_image(&a.scene)?)
    } else {
        None
    };
    let info = match &image {
        Some(view) => {
            loaded.scene.tables = Vec::new();
            *view.info()
        }
        None => {
            let bytes = files::compile(&a.scene, &loaded.scene)?;
            *crate::scene::read_image(&bytes)
                .map_err(|e| input(anyhow!("{}: {e}", a.scene.display())))?
                .info()
        }
    };
    if info.expanded_polygons == 0 {
        if loaded.skipped_faces > 0 {
            return Err(input(anyhow!(
                "{}: no usable polygons ({} face{} skipped: see the warnings)",
                a.scene.display(),
                loaded.skipped_faces,
                if loaded.skipped_faces == 1 { "" } else { "s" }
            )));
        }
        return Err(input(anyhow!(
            "{}: the scene has no polygons",
            a.scene.display()
        )));
    }
    // The image's size and camera, chosen on the model's geometry; a solve that reads the
    // file as it goes needs no more of it than the model's structure (the row labels, the
    // materials): its vertices go (10 MB of the paper stand's 15).
    let chosen_view = match &a.image {
        Some(_) => Some(super::solve_view::image_view(&a, &loaded.scene, up)?),
        None => None,
    };
    if image.is_some() {
        loaded.scene.drop_vertices();
    }
    // Shared with the results' row labels, which read it as the rows go by.
    let shared = std::sync::Arc::new(loaded.scene);
    let scene = &*shared;
    let bands = scene.bands as usize;
    // Material and group of every row; back-side columns only when a polygon is two-sided.
    let labels = output::RowLabels::shared(std::sync::Arc::clone(&shared));
    let two_sided = labels.uses_material(|m| scene.materials[m].data.two_sided);

    // Outputs, checked before the (possibly long) solve: writable, none of them a file the
    // run reads, no two the same.
    let mut inputs = loaded.inputs.clone();
    inputs.extend(a.reference.iter().cloned());
    inputs.extend(a.reference_image.iter().cloned());
    if a.reference_image.is_some()
        && a.image
            .as_ref()
            .and_then(|p| output::ImageFormat::of(p).ok())
            != Some(output::ImageFormat::Exr)
    {
        return refuse(
            "--reference-image compares linear pictures: give --image OUT.exr".to_string(),
        );
    }
    let named: Vec<crate::paths::Output<'_>> = [
        ("--results", &a.results),
        ("--stats", &a.stats),
        ("--image", &a.image),
    ]
    .into_iter()
    .filter_map(|(option, p)| {
        p.as_deref()
            .map(|path| crate::paths::Output { option, path })
    })
    .collect();
    crate::paths::check_outputs(&inputs, &named)?;
    crate::interrupt::expect(&named.iter().map(|o| o.path).collect::<Vec<_>>());
    let mut outputs = Outputs::default();
    let mut image_settings = None;
    if let Some(path) = &a.reference {
        let table = output::read_results_file(path)?;
        if table.len() as u64 != info.expanded_polygons {
            return Err(input(anyhow!(
                "{}: the reference has {} polygons but {} has {}",
                path.display(),
                table.len(),
                a.scene.display(),
                info.expanded_polygons
            )));
        }
        outputs.reference = Some(
            ReferenceSink::new(table, bands, two_sided)
                .map_err(|e| input(anyhow!("{}: {e}", path.display())))?,
        );
    }
    if let (Some(path), Some((size, camera))) = (&a.image, chosen_view) {
        image_settings = Some(output::ImageSettings {
            size: [size.width, size.height],
            camera: output::camera_arg(&camera),
            supersample: a.supersample.unwrap_or(1),
            display_bands: a.display_bands.clone(),
            display: a.display.map(|d| format!("{d:?}").to_lowercase()),
            shading: format!("{:?}", a.shading).to_lowercase(),
        });
        let mut sink = ImageSink::new(
            path,
            &camera,
            size,
            a.supersample.unwrap_or(1),
            bands,
            &scene.band_names,
        )
        .map_err(usage)?
        .with_shading(a.shading);
        if a.method == Method::Hi {
            // Memory that does not grow with the scene: smooth shading batch by batch.
            sink = sink.with_batch(HI_IMAGE_BATCH);
        }
        if sink.is_png() {
            let display = output::Display::choose(
                a.display,
                a.display_bands.as_deref(),
                bands,
                &scene.band_names,
            )
            .map_err(|e| usage(anyhow!("{e}")))?;
            let chosen = a.display_bands.is_some();
            if !a.quiet
                && let Some(what) = display.note(bands, &scene.band_names, chosen)
            {
                eprintln!("note: {} shows {what}", path.display());
            }
            sink = sink.with_display(display);
        } else if (a.display_bands.is_some() || a.display.is_some()) && !a.quiet {
            eprintln!(
                "warning: --display and --display-bands have no effect on an EXR image (it keeps every band)"
            );
        }
        outputs.image = Some(sink);
    }
    if let Some(path) = &a.results {
        outputs.results = Some(
            ResultsFile::create_with_layout(
                path,
                output::TableLayout {
                    labels: output::columns::band_labels(bands, &scene.band_names),
                    two_sided,
                    faces: loaded.faces.clone(),
                    rows: Some(labels),
                },
            )
            .map_err(usage)?,
        );
    }

    let method = match (a.method, instancing) {
        (Method::Hr, None) => "hr",
        (Method::Hi | Method::Hr, Some(_)) => "hi",
        (_, _) => "exact",
    };
    let hr = a.method != Method::Exact;
    // f32 settings as the decimal given, not its f32 widening (1e-3, not 0.0010000000474).
    let decimal = |v: f32| v.to_string().parse().unwrap_or(v as f64);
    let count = |v: u32| {
        if v == Settings::AUTO {
            "auto".to_string()
        } else {
            v.to_string()
        }
    };
    let mut report = SolveReport {
        hirad_version: env!("CARGO_PKG_VERSION").into(),
        scene: a.scene.display().to_string(),
        settings: Some(output::RunSettings {
            method: method.into(),
            epsilon: hr.then(|| decimal(a.epsilon)),
            rays: hr.then_some(a.rays),
            final_rays: hr.then(|| count(a.final_rays)),
            final_passes: hr.then(|| count(a.final_passes)),
            min_area: hr.then(|| decimal(a.min_area)),
            tolerance: decimal(a.tolerance),
            max_iterations: hr.then_some(a.max_iterations),
            max_imbalance_percent: Some(a.max_imbalance),
            memory_bytes: if hr { a.memory } else { None },
            visibility: hr.then(|| format!("{:?}", a.visibility).to_lowercase()),
            blocking_polygons: (a.method == Method::Hi).then_some(a.blocking_polygons),
            own_polygons: (a.method == Method::Hi).then_some(a.own_polygons),
            instancing: instancing.map(|p| p.to_string()),
            elements: (!hr).then_some(a.elements),
            threads: a.threads.map(u32::from),
            image: image_settings,
        }),
        method: method.into(),
        epsilon: hr.then(|| decimal(a.epsilon)),
        threads: threads as u32,
        polygons: info.expanded_polygons,
        elements: 0,
        links: 0,
        iterations: 0,
        refinement_passes: 0,
        seconds: 0.0,
        peak_workspace_bytes: 0,
        workspace_bytes: 0,
        budget_limited: false,
        error_percent: None,
        error_per_band_percent: Vec::new(),
        max_abs_difference: None,
        worst_polygons: Vec::new(),
        ..SolveReport::default()
    };
    match a.method {
        Method::Hr | Method::Hi => {
            let settings = Settings {
                epsilon: a.epsilon,
                rays: a.rays,
                final_rays: a.final_rays,
                final_passes: a.final_passes,
                min_area: a.min_area,
                tolerance: a.tolerance,
                max_iterations: a.max_iterations,
                blocking_polygons: a.blocking_polygons,
                own_polygons: a.own_polygons,
                ..Settings::default()
            };
            let run = if a.method == Method::Hi {
                let inline = decision
                    .as_ref()
                    .map_or(hirad_core::hr::Inline::NONE, |d| d.inline());
                match &image {
                    Some(view) => solve::solve_hi_image(
                        view,
                        &settings,
                        inline,
                        threads,
                        a.memory,
                        &progress,
                        &mut outputs,
                    ),
                    None => solve::solve_hi(
                        scene,
                        &settings,
                        inline,
                        threads,
                        a.memory,
                        &progress,
                        &mut outputs,
                    ),
                }
            } else {
                solve::solve_hr(
                    scene,
                    &settings,
                    threads,
                    a.memory,
                    a.visibility,
                    &progress,
                    &mut outputs,
                )
            }
            .with_context(|| format!("{}", a.scene.display()))?;
            let s = run.stats;
            report.threads = run.threads as u32;
            report.rays = s.rays;
            report.rays_by_phase = Some(crate::output::RaysByPhase {
                lighting: s.rays_by_phase.lighting,
                links: s.rays_by_phase.links,
                final_gather: s.rays_by_phase.final_gather,
            });
            report.final_passes = Some(s.final_passes);
            report.levels =
                (a.method == Method::Hi).then(|| crate::output::Levels::of(&s, run.own_polygons));
            report.final_change_percent =
                Some(100.0 * s.final_change as f64).filter(|_| s.final_passes > 1);
            report.phases = tables_made
                .iter()
                .map(|t| crate::output::PhaseTime {
                    phase: "tables".into(),
                    seconds: t.seconds,
                })
                .chain(
                    run.phases
                        .iter()
                        .map(|(phase, seconds)| crate::output::PhaseTime {
                            phase: phase.clone(),
                            seconds: *seconds,
                        }),
                )
                .collect();
            report.tables = tables_made.as_ref().map(|t| crate::output::TablesMade {
                originals: t.originals.clone(),
                cache_hits: t.cache_hits,
                targets_missed: t.unmet.clone(),
                seconds: t.seconds,
            });
            report.elements = s.clusters + s.patches;
            report.links = s.links;
            report.iterations = s.iterations;
            report.refinement_passes = s.refinement_passes;
            report.peak_workspace_bytes = s.peak_bytes;
            report.workspace_bytes = s.workspace_bytes;
            report.budget_limited = s.budget_limited;
            report.converged = s.converged;
            report.diverged = s.diverged;
            report.remaining_change = Some(s.remaining_change as f64).filter(|r| r.is_finite());
            report.power = verdict::powers(&s.balance, bands, &scene.band_names);
        }
        Method::Exact => {
            let settings = ExactSettings {
                max_elements: usize::try_from(a.elements).unwrap_or(usize::MAX),
                tolerance: (a.tolerance as f64 * 1e-3).max(1e-12),
                ..ExactSettings::default()
            };
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()?;
            let r = pool
                .install(|| {
                    exact::solve_exact_obvhs_with(scene, &settings, &mut outputs, &progress)
                })
                .map_err(|e| {
                    let error = anyhow!("{}: {e}", a.scene.display());
                    match e {
                        exact::ExactError::Scene(_) | exact::ExactError::Visibility(_) => {
                            input(error)
                        }
                        exact::ExactError::Settings(_) | exact::ExactError::TooLarge { .. } => {
                            usage(error)
                        }
                        exact::ExactError::NotConverged { .. } => not_right(error),
                        exact::ExactError::Sink(_) => error,
                    }
                })?;
            progress.finish();
            report.elements = r.elements as u64;
            report.links = r.form_factors;
            report.iterations = r.iterations as u64;
            report.workspace_bytes = r.matrix_bytes;
            report.peak_workspace_bytes = r.matrix_bytes;
            // The exact solver fails rather than return an unconverged solution.
            report.converged = true;
            report.remaining_change = Some(r.error).filter(|e| e.is_finite());
            report.rays = r.rays;
            report.power = verdict::powers(&r.balance, bands, &scene.band_names);
        }
    }
    report.seconds = start.elapsed().as_secs_f64();
    let mut warnings = Vec::new();
    if let Some(why) = outputs.image.as_ref().and_then(|i| i.nearly_black()) {
        warnings.push(why);
    }
    let written_rows = outputs.results.as_ref().map(|_| info.expanded_polygons);
    let comparison = outputs.finish()?;
    if let Some(c) = &comparison {
        report.set_comparison(c);
        super::print_out(&format!(
            "error {:.4} % (L2, area-weighted, of the reference's largest radiosity {:.6} W/m^2) over {} polygons\n",
            c.error_percent, c.reference_max, c.polygons
        ))?;
        super::print_out(&c.worst_lines(&scene.band_names))?;
    }
    if let (Some(reference), Some(image)) = (&a.reference_image, &a.image) {
        let r = output::read_exr(reference)
            .map_err(|e| input(e.context(format!("{}", reference.display()))))?;
        let i = output::read_exr(image)?;
        let e = output::image_compare::image_error_percent(&i, &r)
            .map_err(|e| input(anyhow!("{}: {e}", reference.display())))?;
        report.image_error_percent = Some(e);
        super::print_out(&format!(
            "image error {e:.3} % (relative L2 against {})\n",
            reference.display()
        ))?;
    }
    // The verdict, before the stats that record it: why the numbers are not right, if so.
    let failure = verdict::failure(&report, a.max_iterations, a.max_imbalance);
    let balance_warning = verdict::balance_warning(&report, a.max_imbalance);
    warnings.extend(balance_warning.clone());
    report.verdict = Some(output::Verdict {
        passed: failure.is_none(),
        reason: match (&failure, &balance_warning) {
            (Some(f), _) => f.clone(),
            (None, Some(w)) => format!("passed with a warning: {w}"),
            (None, None) => "every check passed".into(),
        },
    });
    for (option, path) in [
        ("--results", &a.results),
        ("--image", &a.image),
        ("--stats", &a.stats),
    ] {
        if let Some(p) = path {
            report.outputs.push(output::OutputFile {
                option: option.into(),
                path: p.display().to_string(),
            });
        }
    }
    if let Some(path) = &a.stats {
        report.write_json(path)?;
    }
    if !a.quiet {
        report.print_summary(&mut std::io::stderr())?;
        if report.budget_limited {
            eprintln!(
                "note: the workspace budget limited refinement; give more --memory for the full accuracy of this epsilon"
            );
        }
        for w in &warnings {
            eprintln!("warning: {w}");
        }
        let wrote: Vec<String> = [
            (&a.results, written_rows.map(|n| format!(" ({n} rows)"))),
            (&a.image, None),
            (&a.stats, None),
        ]
        .into_iter()
        .filter_map(|(p, what)| {
            p.as_ref()
                .map(|p| format!("{}{}", p.display(), what.unwrap_or_default()))
        })
        .collect();
        if !wrote.is_empty() {
            eprintln!("wrote {}", wrote.join(", "));
        }
    }
    match failure {
        Some(why) => Err(not_right(anyhow!(why))),
        None => Ok(()),
    }
}

/// Patches a `--method hi` image keeps for smooth shading at once (about 2 MB; corners are
/// shared within a batch: the patches of a level arrive together).
const HI_IMAGE_BATCH: usize = 1 << 12;

/// The image size without `--size`.
pub(super) const DEFAULT_SIZE: &str = "640x480";

/// Warns about settings that change nothing: image options without `--image`, and a
/// refinement threshold or smallest patch that leaves nothing to refine.
fn warn_unused(a: &Args) {
    if a.quiet {
        return;
    }
    if a.image.is_none() {
        for (given, name) in [
            (a.size.is_some(), "--size"),
            (a.camera.is_some(), "--camera"),
            (a.supersample.is_some(), "--supersample"),
            (a.display_bands.is_some(), "--display-bands"),
            (a.display.is_some(), "--display"),
            (a.up.is_some(), "--up"),
        ] {
            if given {
                eprintln!("warning: {name} has no effect without --image");
            }
        }
    }
    if a.image.is_some() && a.up.is_some() && a.camera.is_some() {
        eprintln!("warning: --up has no effect with --camera (the camera gives its own up)");
    }
    let hr = a.method != Method::Exact;
    if a.method == Method::Hi && a.visibility != VisibilityChoice::Core {
        eprintln!(
            "note: --method hi casts its rays with the core's own BVH, level by level (--visibility has no effect)"
        );
    }
    if hr && a.epsilon >= 1.0 {
        eprintln!(
            "warning: --epsilon {} is at least 1: no link carries that much of the scene's light, so nothing is refined (the coarsest solution; the default is 1e-3, smaller is finer)",
            a.epsilon
        );
    }
    if hr && a.min_area >= 0.25 {
        eprintln!(
            "warning: --min-area {} leaves no patch room to split (a quarter of a polygon is less than that fraction of the scene's area)",
            a.min_area
        );
    }
    if a.method == Method::Exact && a.epsilon != 1e-3 {
        eprintln!("warning: --epsilon has no effect with --method exact (see --elements)");
    }
}

/// `--final-passes`: `auto` or a count in 1..=4.
fn parse_final_passes(s: &str) -> Result<u32, String> {
    if s.eq_ignore_ascii_case("auto") {
        return Ok(Settings::AUTO);
    }
    match s.parse::<u32>() {
        Ok(n) if (1..=hirad_core::hr::MAX_FINAL_PASSES).contains(&n) => Ok(n),
        _ => Err(format!(
            "expected `auto` or a whole number of passes from 1 to {}",
            hirad_core::hr::MAX_FINAL_PASSES
        )),
    }
}

/// `--final-rays`: `auto` or a count in 0..=1048576.
fn parse_final_rays(s: &str) -> Result<u32, String> {
    if s.eq_ignore_ascii_case("auto") {
        return Ok(Settings::AUTO);
    }
    match s.parse::<u32>() {
        Ok(n) if n <= Settings::MAX_FINAL_RAYS => Ok(n),
        _ => Err(format!(
            "expected `auto` or a whole number of rays from 0 to {}",
            Settings::MAX_FINAL_RAYS
        )),
    }
}
