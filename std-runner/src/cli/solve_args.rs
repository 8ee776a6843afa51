//! The arguments of `hirad solve` and their parsers, and the warnings about arguments that
//! change nothing.

use crate::exact::ExactSettings;
use crate::output;
use crate::solve::VisibilityChoice;
use crate::solve::policy::Policy;
use hirad_core::hr::Settings;
use std::path::PathBuf;

/// The solvers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Method {
    /// Hierarchical radiosity with clustering over the expanded scene.
    Hr,
    /// Hierarchical instantiation (the paper's method): the scene solved level by level,
    /// instances closed through their originals' directional tables and opened one at a
    /// time, so that memory holds one path of levels. Tables the file lacks come from the
    /// table cache or are made first (`hirad tables SCENE -o OUT.hirb` keeps them in a
    /// file); uses the core's own BVH.
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
    /// Solver. Default: `hi` where `--instancing auto` closes an original whose tables the
    /// scene carries, or one whose instances hold more than 1,000,000 polygons expanded;
    /// else `hr` (a scene without instances, or one that would first need tables made: a
    /// note says so).
    #[arg(long = "method", value_name = "METHOD", value_enum)]
    pub method_given: Option<Method>,
    /// The solver the run uses: `method_given`, or the default `run` chose for the scene.
    #[arg(skip = Method::Hr)]
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
    /// Originals `--method hi` expands in place whatever `--instancing` says (repeatable, or
    /// names separated by commas): their contents join their parent's level, their own
    /// instances closed there. For originals whose instances' boxes their siblings' polygons
    /// fill (the printout says so): tables measured on an original alone count the light
    /// between such neighbours twice.
    #[arg(long, value_name = "NAME", value_delimiter = ',')]
    pub expand: Vec<String>,
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
    /// Ray caster for hr (default: obvhs; hi always casts with the core's own BVH).
    #[arg(long, value_enum)]
    pub visibility: Option<VisibilityChoice>,
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

/// The image size without `--size`.
pub(super) const DEFAULT_SIZE: &str = "640x480";

/// Warns about settings that change nothing: image options without `--image`, and a
/// refinement threshold or smallest patch that leaves nothing to refine.
pub(super) fn warn_unused(a: &Args) {
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
    if a.method == Method::Hi && a.visibility.is_some_and(|v| v != VisibilityChoice::Core) {
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

impl Args {
    /// The ray caster the run uses: the core's BVH for hi, else `--visibility` (obvhs by
    /// default).
    pub fn ray_caster(&self) -> VisibilityChoice {
        match self.method {
            Method::Hi => VisibilityChoice::Core,
            _ => self.visibility.unwrap_or(VisibilityChoice::Obvhs),
        }
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
