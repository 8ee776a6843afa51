//! `hirad solve SCENE`: radiosity of every polygon, with a results table, an image, stats and
//! the error against a reference.

use super::instancing;
use super::solve_args::{Args, Method, warn_unused};
use super::verdict;
use crate::exact::{self, ExactSettings};
use crate::exit::{input, not_right, usage};
use crate::files;
use crate::output::{self, ImageSink, Outputs, Progress, ReferenceSink, ResultsFile, SolveReport};
use crate::scene::Scene;
use crate::solve;
use crate::solve::policy::{Decision, Policy};
use anyhow::{Context, Result, anyhow};
use hirad_core::hr::Settings;
use hirad_core::sink::{PatchResult, PolygonResult, Sink};
use std::sync::Arc;
use std::time::Instant;

/// Runs `hirad solve`.
pub fn run(a: Args) -> Result<()> {
    let solved = solve(a, None, None, &mut NoExtra)?;
    match solved.failure {
        Some(why) => Err(not_right(anyhow!(why))),
        None => Ok(()),
    }
}

/// What a solve hands back besides the files it wrote: what a library caller (the Python
/// package, through `crate::embed`) reads instead of the summary on stderr.
pub struct Solved {
    /// The stats report, as `--stats` writes it (its verdict included).
    pub report: SolveReport,
    /// The scene model as solved (row labels: material and group of every polygon). A
    /// `.hirb` solved by hi from the file has no vertices left in it.
    pub scene: Arc<Scene>,
    /// For an OBJ scene, the face number (1-based) of every polygon, in global-id order.
    pub faces: Option<Vec<u64>>,
    /// The loader's warnings and the run's own (an image nearly black, a power balance off
    /// by more than 1%), as the CLI prints them after `warning: `.
    pub warnings: Vec<String>,
    /// Why the numbers are not right (the CLI then exits 1 after writing its outputs).
    pub failure: Option<String>,
}

/// The CLI's extra sink: its results go to the files only.
struct NoExtra;

impl Sink for NoExtra {
    type Error = anyhow::Error;

    fn polygon(&mut self, _: &PolygonResult<'_>) -> Result<()> {
        Ok(())
    }
}

/// Every result of a solve to the outputs the arguments name and to the caller's `extra`
/// sink.
struct Tee<'a> {
    outputs: &'a mut Outputs,
    extra: &'a mut (dyn Sink<Error = anyhow::Error> + Send),
}

impl Sink for Tee<'_> {
    type Error = anyhow::Error;

    fn patch(&mut self, patch: &PatchResult<'_>) -> Result<()> {
        self.outputs.patch(patch)?;
        self.extra.patch(patch)
    }

    fn polygon(&mut self, polygon: &PolygonResult<'_>) -> Result<()> {
        self.outputs.polygon(polygon)?;
        self.extra.polygon(polygon)
    }
}

/// The whole of `hirad solve` but its exit status: the method chosen as the CLI chooses it,
/// the scene loaded (or `model`, a scene built in memory and named `a.scene` in messages),
/// tables made where hi needs them, the solve, the files the arguments name, and the
/// report. Every result also goes to `extra`, in global-id order. `progress`: the reporter
/// (default: on stderr unless `a.quiet`).
pub fn solve(
    a: Args,
    model: Option<files::Loaded>,
    progress: Option<Progress>,
    extra: &mut (dyn Sink<Error = anyhow::Error> + Send),
) -> Result<Solved> {
    let start = Instant::now();
    let refuse = |m: String| Err(usage(anyhow!(m)));
    if let (Some(_), Some(m @ (Method::Hr | Method::Exact))) = (a.instancing, a.method_given) {
        return refuse(format!(
            "--instancing chooses which instances --method hi keeps closed; --method {} expands every instance",
            if m == Method::Hr { "hr" } else { "exact" }
        ));
    }
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
    // The policy `hi` would follow (the method given, or the default, which is `hi` where
    // that policy closes some instance). `hi` with every instance expanded is hierarchical
    // radiosity over the whole scene: the same solver, and the same results, as `hr`.
    let policy = matches!(a.method_given, None | Some(Method::Hi))
        .then(|| a.instancing.unwrap_or(Policy::Auto))
        .filter(|&p| p != Policy::None);
    let binary =
        model.is_none() && files::Format::of(&a.scene).is_ok_and(|f| f == files::Format::Binary);
    // Which originals hi closes, decided on the file's image where there is one, else on the
    // loaded scene's.
    let mut decision: Option<Decision> = match policy {
        Some(p) if binary => Some(instancing::decide(
            &a.scene,
            &files::open_image(&a.scene)?,
            p,
            &a.expand,
        )?),
        _ => None,
    };
    let hi_by_default = |d: &Option<Decision>| d.as_ref().is_some_and(|d| d.hi_by_default());
    let mut method = match (a.method_given, policy) {
        (Some(Method::Hi), None) => Some(Method::Hr),
        (Some(m), _) => Some(m),
        (None, None) => Some(Method::Hr),
        // A policy given asks for hi.
        (None, Some(_)) if a.instancing.is_some() => Some(Method::Hi),
        (None, Some(_)) if binary => Some(if hi_by_default(&decision) {
            Method::Hi
        } else {
            Method::Hr
        }),
        (None, Some(_)) => None,
    };
    // Hierarchical instantiation from a `.hirb` that holds every table it needs reads the
    // file on demand: its tables go into the workspace once, and the model keeps only their
    // records (a canopy's are 20 MB a copy: loading them twice over was the run's peak).
    let binary_hi = binary && method == Some(Method::Hi);
    let mut loaded = if let Some(m) = model {
        m
    } else if binary_hi {
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
    let loader_warnings = loaded.warnings.clone();
    if let (Some(p), None, Some(Method::Hi) | None) = (policy, &decision, method)
        && !loaded.scene.originals.is_empty()
    {
        decision = Some(instancing::decide_model(
            &a.scene,
            &loaded.scene,
            p,
            &a.expand,
        )?);
    }
    let method = method.get_or_insert(if hi_by_default(&decision) {
        Method::Hi
    } else {
        Method::Hr
    });
    if *method != Method::Hi {
        if a.method_given.is_none()
            && !a.quiet
            && decision
                .as_ref()
                .is_some_and(|d| d.closed().next().is_some())
        {
            eprintln!(
                "note: solving with --method hr, every instance expanded: the scene carries no directional tables (`hirad tables SCENE -o OUT.hirb` makes them; --method hi solves level by level, making them first)"
            );
        }
        decision = None;
    }
    // The policy the report names: hi's, including `--instancing none` (hi expanding every
    // instance, solved as hr).
    let instancing = match (a.method_given, *method) {
        (_, Method::Hi) => Some(a.instancing.unwrap_or(Policy::Auto)),
        (Some(Method::Hi) | None, _) => a.instancing.filter(|&p| p == Policy::None),
        _ => None,
    };
    if let Some(d) = &decision {
        if a.method_given.is_none() && !a.quiet {
            eprintln!(
                "note: solving with --method hi, the default for a scene that carries its tables or whose instances are too many to expand (--method hr expands every instance)"
            );
        }
        instancing::print(d, a.quiet);
        instancing::refuse_closed_emitter(d)?;
    }
    let a = Args {
        method: *method,
        ..a
    };
    warn_unused(&a);
    let progress = progress.unwrap_or_else(|| Progress::new(a.quiet));
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
    let faces = loaded.faces.clone();
    let shared = Arc::new(loaded.scene);
    let scene = &*shared;
    let bands = scene.bands as usize;
    // Material and group of every row; back-side columns only when a polygon is two-sided.
    let labels = output::RowLabels::shared(Arc::clone(&shared));
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
                    faces: faces.clone(),
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
            visibility: hr.then(|| format!("{:?}", a.ray_caster()).to_lowercase()),
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
    let mut tee = Tee {
        outputs: &mut outputs,
        extra,
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
                        view, &settings, inline, threads, a.memory, &progress, &mut tee,
                    ),
                    None => solve::solve_hi(
                        scene, &settings, inline, threads, a.memory, &progress, &mut tee,
                    ),
                }
            } else {
                solve::solve_hr(
                    scene,
                    &settings,
                    threads,
                    a.memory,
                    a.ray_caster(),
                    &progress,
                    &mut tee,
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
            report.levels = (a.method == Method::Hi)
                .then(|| crate::output::Levels::of(&s, run.own_polygons, run.blocking_polygons));
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
                .install(|| exact::solve_exact_obvhs_with(scene, &settings, &mut tee, &progress))
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
    Ok(Solved {
        report,
        scene: shared,
        faces,
        warnings: loader_warnings.into_iter().chain(warnings).collect(),
        failure,
    })
}

/// Patches a `--method hi` image keeps for smooth shading at once (about 2 MB; corners are
/// shared within a batch: the patches of a level arrive together).
const HI_IMAGE_BATCH: usize = 1 << 12;
