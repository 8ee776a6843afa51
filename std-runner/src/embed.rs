//! hirad in-process: `hirad solve` as a library call that keeps every polygon's results in
//! memory (the Python package's solve). The run is the command line's own
//! (`cli::solve::solve`): the method chosen as the CLI chooses it (hi where `--instancing
//! auto` closes an instance, else hr), the same settings and defaults, the same report; only
//! nothing is printed and the results come back as arrays.
//!
//! Units: m^2 for areas, W/m^2 for radiosity and irradiance, W for absorbed power.

use crate::cli::solve::{self as cli_solve, Solved};
use crate::cli::solve_args::Args;
/// `--memory`'s parser: `64M`, `2G`, `500000000` -> bytes (K, M, G, T are powers of 1024).
pub use crate::cli::solve_args::parse_bytes;
use crate::files::{Format, Loaded};
use crate::output::{Progress, RowLabels};
use crate::scene::{Scene, Up};
use anyhow::{Result, anyhow};
use hirad_core::sink::{PolygonResult, Sink};
use std::path::PathBuf;

/// The scene of a solve.
pub enum SceneInput {
    /// A `.hir`, `.hirb` or `.obj` file.
    File(PathBuf),
    /// A scene built in memory, called `name` in messages.
    Model {
        /// What messages call it (e.g. `hirad.Scene`).
        name: String,
        /// The model (checked before the solve, as a loaded file's is).
        scene: Box<Scene>,
    },
}

/// A solve's settings, as `hirad solve` takes them; `None` is the command line's default.
#[derive(Clone, Debug, Default)]
pub struct Request {
    /// `--method`: `hi`, `hr` or `exact`.
    pub method: Option<String>,
    /// `--instancing`: `auto`, `all`, `every:N` or `none`.
    pub instancing: Option<String>,
    /// `--epsilon` (dimensionless).
    pub epsilon: Option<f64>,
    /// `--threads` (1 to 1024).
    pub threads: Option<u64>,
    /// `--memory`: bytes, or a size such as `64M` (K, M, G, T are powers of 1024).
    pub memory: Option<String>,
}

impl Request {
    /// The words of a `hirad solve` command line for `scene` with these settings (quiet).
    pub fn words(&self, scene: &std::path::Path) -> Vec<std::ffi::OsString> {
        let mut w: Vec<std::ffi::OsString> = vec![scene.into(), "--quiet".into()];
        let mut opt = |name: &str, v: Option<String>| {
            if let Some(v) = v {
                w.push(format!("--{name}={v}").into());
            }
        };
        opt("method", self.method.clone());
        opt("instancing", self.instancing.clone());
        opt("epsilon", self.epsilon.map(|e| e.to_string()));
        opt("threads", self.threads.map(|t| t.to_string()));
        opt("memory", self.memory.clone());
        w
    }

    /// The parsed arguments, refused as the command line refuses them (a usage error with
    /// clap's message, without its usage lines).
    pub fn args(&self, scene: &std::path::Path) -> Result<Args> {
        crate::generate::args_from_words::<Args, _, _>("hirad solve", self.words(scene)).map_err(
            |e| {
                let text = e.to_string();
                let first = text.lines().next().unwrap_or("").trim();
                let first = first.strip_prefix("error: ").unwrap_or(first);
                crate::exit::usage(anyhow!("{first}"))
            },
        )
    }
}

/// Every polygon's results in global-id order, kept as the solve streams them.
#[derive(Clone, Debug, Default)]
pub struct Rows {
    /// Spectral bands.
    pub bands: usize,
    /// Global ids.
    pub ids: Vec<u64>,
    /// Areas (m^2).
    pub area: Vec<f32>,
    /// Whether each polygon is two-sided.
    pub two_sided: Vec<bool>,
    /// Front radiosity, `bands` per polygon (W/m^2).
    pub radiosity: Vec<f32>,
    /// Front irradiance, `bands` per polygon (W/m^2).
    pub irradiance: Vec<f32>,
    /// Back radiosity, `bands` per polygon, NaN for one-sided polygons (W/m^2).
    pub radiosity_back: Vec<f32>,
    /// Back irradiance, `bands` per polygon, NaN for one-sided polygons (W/m^2).
    pub irradiance_back: Vec<f32>,
}

impl Rows {
    /// Rows of `bands` bands.
    pub fn new(bands: usize) -> Self {
        Rows {
            bands,
            ..Rows::default()
        }
    }

    /// Polygons kept.
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    /// True when no polygon is kept.
    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }

    /// True when some polygon is two-sided (the back arrays then mean something).
    pub fn any_two_sided(&self) -> bool {
        self.two_sided.iter().any(|&t| t)
    }
}

impl Sink for Rows {
    type Error = anyhow::Error;

    fn polygon(&mut self, p: &PolygonResult<'_>) -> Result<()> {
        if self.ids.is_empty() && self.bands == 0 {
            self.bands = p.radiosity[0].len();
        }
        let n = self.bands;
        let band = |s: &[f32], b: usize| s.get(b).copied().unwrap_or(f32::NAN);
        self.ids.push(p.id);
        self.area.push(p.area);
        self.two_sided.push(p.two_sided);
        for b in 0..n {
            self.radiosity.push(band(p.radiosity[0], b));
            self.irradiance.push(band(p.irradiance[0], b));
            self.radiosity_back.push(band(p.radiosity[1], b));
            self.irradiance_back.push(band(p.irradiance[1], b));
        }
        Ok(())
    }
}

/// Sums over the groups of a scene: the path of named clusters from the root that holds
/// each polygon (the results table's `group` column).
#[derive(Clone, Debug, Default)]
pub struct Groups {
    /// Group paths, in order of first appearance (e.g. `scene/plant_3/leaves`).
    pub names: Vec<String>,
    /// The group (index into `names`) of every row.
    pub of_row: Vec<u32>,
    /// Material name of every row.
    pub materials: Vec<String>,
    /// Area per group (m^2).
    pub area: Vec<f64>,
    /// Absorbed power per group and band, `bands` per group (W): the balance's `absorbed`,
    /// `area (1 - rho - tau) E` summed over the receiving sides of every polygon (front;
    /// back too where two-sided).
    pub absorbed: Vec<f64>,
}

/// Power absorbed by one polygon, per band (W): `area (1 - rho - tau) E` on each receiving
/// side, as the core's balance counts it (`hr::balance`; the backs of one-sided polygons
/// are not receiving sides: what reaches them counts under `absorbed_backs`).
pub fn absorbed(scene: &Scene, material: usize, rows: &Rows, row: usize, out: &mut [f64]) {
    let Some(m) = scene.materials.get(material).map(|m| &m.data) else {
        return;
    };
    let area = rows.area[row] as f64;
    let n = rows.bands;
    for (b, o) in out.iter_mut().enumerate().take(n) {
        let tau = m.tau[b] as f64;
        let front = (1.0 - m.rho_front[b] as f64 - tau) * rows.irradiance[row * n + b] as f64;
        let back = if rows.two_sided[row] {
            (1.0 - m.rho_back[b] as f64 - tau) * rows.irradiance_back[row * n + b] as f64
        } else {
            0.0
        };
        *o = area * (front + back);
    }
}

impl Groups {
    /// The groups of `rows` in `scene`, with their areas and absorbed powers.
    pub fn of(scene: std::sync::Arc<Scene>, rows: &Rows) -> Groups {
        let n = rows.bands;
        let mut labels = RowLabels::shared(std::sync::Arc::clone(&scene));
        let mut g = Groups::default();
        let mut index: std::collections::HashMap<String, u32> = Default::default();
        let mut per = vec![0.0; n];
        for (row, &id) in rows.ids.iter().enumerate() {
            let (material, group) = labels.label(id).unwrap_or(("", ""));
            let k = match index.get(group) {
                Some(&k) => k,
                None => {
                    let k = g.names.len() as u32;
                    index.insert(group.to_string(), k);
                    g.names.push(group.to_string());
                    g.area.push(0.0);
                    g.absorbed.extend(std::iter::repeat_n(0.0, n));
                    k
                }
            };
            g.of_row.push(k);
            g.materials.push(material.to_string());
            let m = scene.material_index(material).unwrap_or(usize::MAX);
            per.iter_mut().for_each(|v| *v = 0.0);
            absorbed(&scene, m, rows, row, &mut per);
            let k = k as usize;
            g.area[k] += rows.area[row] as f64;
            for (s, v) in g.absorbed[k * n..(k + 1) * n].iter_mut().zip(&per) {
                *s += v;
            }
        }
        g
    }
}

/// What a solve gives back.
pub struct Embedded {
    /// Every polygon's results.
    pub rows: Rows,
    /// Band names (the scene's, else `0`, `1`, ...).
    pub band_names: Vec<String>,
    /// The stats JSON, as `hirad solve --stats` writes it.
    pub stats_json: String,
    /// Groups and their sums.
    pub groups: Groups,
    /// For an OBJ scene, every row's face number (1-based).
    pub faces: Option<Vec<u64>>,
    /// Warnings, as the CLI prints them after `warning: `.
    pub warnings: Vec<String>,
    /// Why the numbers are not right (the CLI exits 1), if so.
    pub failure: Option<String>,
}

/// Solves `input` as `hirad solve` would with the settings of `request`, reporting progress
/// to `progress` (default: nothing shown). Errors carry the CLI's message (`{:#}`) and its
/// exit class (`crate::exit::class_of`).
pub fn solve(input: SceneInput, request: &Request, progress: Option<Progress>) -> Result<Embedded> {
    let (path, model) = match input {
        SceneInput::File(p) => (p, None),
        SceneInput::Model { name, scene } => {
            let path = PathBuf::from(&name);
            scene
                .check()
                .map_err(|e| crate::exit::input(anyhow!("{name}: {e}")))?;
            let up = Up::of_scene(&scene);
            let loaded = Loaded {
                scene: *scene,
                format: Format::Binary,
                warnings: Vec::new(),
                warnings_total: 0,
                skipped_faces: 0,
                inputs: Vec::new(),
                faces: None,
                up,
            };
            (path, Some(loaded))
        }
    };
    let args = request.args(&path)?;
    // The bands are the scene's: the first polygon's results say how many.
    let mut rows = Rows::new(0);
    let progress = progress.unwrap_or_else(|| Progress::new(true));
    let Solved {
        report,
        scene,
        faces,
        warnings,
        failure,
    } = cli_solve::solve(args, model, Some(progress), &mut rows)?;
    let bands = scene.bands as usize;
    rows.bands = bands;
    let band_names = (0..bands)
        .map(|b| {
            scene
                .band_names
                .get(b)
                .cloned()
                .unwrap_or_else(|| b.to_string())
        })
        .collect();
    let groups = Groups::of(scene, &rows);
    Ok(Embedded {
        rows,
        band_names,
        stats_json: report.to_json(),
        groups,
        faces,
        warnings,
        failure,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Material, MaterialData, light, triangle};
    use glam::Vec3;

    /// A lit floor triangle (one-sided) under a two-sided leaf, each in its own named
    /// cluster.
    fn floor_and_leaf() -> Scene {
        let mut s = Scene::new(1);
        let material = |rho: f32, tau: f32, two_sided: bool| MaterialData {
            bands: 1,
            two_sided,
            rho_front: [rho, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            emit_front: [0.0; 8],
            rho_back: [
                if two_sided { rho } else { 0.0 },
                0.0,
                0.0,
                0.0,
                0.0,
                0.0,
                0.0,
                0.0,
            ],
            tau: [tau, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            emit_back: [0.0; 8],
        };
        s.materials.push(Material {
            name: "floor".into(),
            data: material(0.3, 0.0, false),
        });
        s.materials.push(Material {
            name: "leaf".into(),
            data: material(0.2, 0.3, true),
        });
        s.root = crate::scene::Cluster::named("scene");
        for (name, z, m) in [("floor", 0.0, 0), ("leaf", 0.5, 1)] {
            let mut c = crate::scene::Cluster::named(name);
            let a = c.vertex(Vec3::new(0.0, 0.0, z));
            let b = c.vertex(Vec3::new(1.0, 0.0, z));
            let d = c.vertex(Vec3::new(0.0, 1.0, z));
            c.polygons.push(triangle(a, b, d, m));
            s.root.children.push(c);
        }
        s.suns
            .push(light(Vec3::new(0.2, 0.1, 1.0).normalize(), &[100.0]));
        s
    }

    #[test]
    fn settings_become_the_command_line_and_bad_ones_are_usage_errors() {
        let r = Request {
            method: Some("hr".into()),
            epsilon: Some(0.01),
            threads: Some(1),
            memory: Some("64M".into()),
            ..Request::default()
        };
        let a = r.args(std::path::Path::new("x.hir")).unwrap();
        assert_eq!(a.epsilon, 0.01);
        assert_eq!(a.threads, Some(1));
        assert_eq!(a.memory, Some(64 << 20));
        assert!(a.quiet);
        for bad in [
            Request {
                threads: Some(0),
                ..Request::default()
            },
            Request {
                memory: Some("lots".into()),
                ..Request::default()
            },
            Request {
                method: Some("fastest".into()),
                ..Request::default()
            },
        ] {
            let e = bad.args(std::path::Path::new("x.hir")).unwrap_err();
            assert_eq!(crate::exit::class_of(&e), crate::exit::Exit::Usage);
            assert!(!e.to_string().starts_with("error:"), "{e}");
        }
    }

    #[test]
    fn a_model_solves_and_its_groups_sum_the_balance() {
        let scene = floor_and_leaf();
        let input = SceneInput::Model {
            name: "test scene".into(),
            scene: Box::new(scene),
        };
        let e = solve(input, &Request::default(), None).unwrap();
        assert_eq!(e.rows.len(), 2);
        assert_eq!(e.rows.bands, 1);
        assert_eq!(e.band_names, ["0"]);
        assert_eq!(e.groups.names, ["scene/floor", "scene/leaf"]);
        assert_eq!(e.groups.materials, ["floor", "leaf"]);
        assert!(e.rows.any_two_sided());
        assert!(e.rows.radiosity_back[0].is_nan());
        assert!(e.rows.irradiance[0] > 0.0 && e.rows.irradiance[1] > 0.0);
        let stats: serde_json::Value = serde_json::from_str(&e.stats_json).unwrap();
        assert_eq!(stats["scene"], "test scene");
        let absorbed = stats["power"][0]["absorbed"].as_f64().unwrap();
        let sum: f64 = e.groups.absorbed.iter().sum();
        assert!(
            (sum - absorbed).abs() <= 1e-6 * absorbed,
            "{sum} {absorbed}"
        );
        // The floor absorbs 70% of what reaches its front.
        let floor = (1.0 - 0.3f32 as f64) * e.rows.area[0] as f64 * e.rows.irradiance[0] as f64;
        assert!((e.groups.absorbed[0] - floor).abs() <= 1e-9 * floor);
    }

    #[test]
    fn a_bad_model_is_an_input_error_named_as_given() {
        let mut scene = floor_and_leaf();
        scene.suns.clear();
        let input = SceneInput::Model {
            name: "my scene".into(),
            scene: Box::new(scene),
        };
        let e = solve(input, &Request::default(), None).err().unwrap();
        assert_eq!(crate::exit::class_of(&e), crate::exit::Exit::Input);
        assert!(format!("{e:#}").starts_with("my scene: "), "{e:#}");
    }
}
