//! `hirad._hirad`: the compiled half of the Python package. The Python layer (`pysrc/hirad`)
//! checks arguments and shapes, packs arrays into little-endian bytes and turns the bytes
//! that come back into NumPy arrays; this module builds scenes (`builder`) and runs the
//! command line's own solve (`hirad::embed`) with the GIL released, progress and Ctrl-C
//! handled by `watch`. No panic crosses into Python: every entry point catches unwinding.
//!
//! Units: metres, m^2, W/m^2, W.

mod builder;
mod watch;

use builder::{Builder, MaterialValues};
use glam::Vec3;
use hirad::embed::{self, Request, SceneInput};
use hirad::exit::{Exit, class_of};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::{Arc, Mutex};

/// The exception class `name` of `hirad._errors` called with `message`.
fn error(py: Python<'_>, name: &str, message: String) -> PyErr {
    match py
        .import("hirad._errors")
        .and_then(|m| m.getattr(name))
        .and_then(|c| c.call1((message.clone(),)))
    {
        Ok(e) => PyErr::from_value(e),
        Err(_) => pyo3::exceptions::PyRuntimeError::new_err(message),
    }
}

/// The text of a panic's payload.
fn panic_text(p: &(dyn std::any::Any + Send)) -> String {
    p.downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| p.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown".into())
}

/// Runs `f`, a panic becoming `hirad.HiradError` (an internal error: a bug to report).
fn guarded<T>(py: Python<'_>, f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|p| {
        Err(error(
            py,
            "HiradError",
            format!("internal error (please report it): {}", panic_text(&*p)),
        ))
    })
}

/// A `ValueError` with the message of `e`.
fn value_error(e: anyhow::Error) -> PyErr {
    PyValueError::new_err(format!("{e:#}"))
}

/// Little-endian numbers of `width` bytes from `bytes`, refused when not whole.
fn numbers<const W: usize, T>(bytes: &[u8], what: &str, f: fn([u8; W]) -> T) -> PyResult<Vec<T>> {
    if !bytes.len().is_multiple_of(W) {
        return Err(PyValueError::new_err(format!(
            "{what}: {} bytes is not a whole number of {W}-byte values",
            bytes.len()
        )));
    }
    Ok(bytes
        .chunks_exact(W)
        .map(|c| f(c.try_into().unwrap_or([0; W])))
        .collect())
}

/// A scene being built (`hirad.Scene` holds one).
#[pyclass(module = "hirad._hirad")]
struct SceneBuilder {
    inner: Builder,
}

#[pymethods]
impl SceneBuilder {
    #[new]
    fn new(py: Python<'_>, bands: usize, names: Vec<String>) -> PyResult<Self> {
        guarded(py, || {
            Ok(SceneBuilder {
                inner: Builder::new(bands, names).map_err(value_error)?,
            })
        })
    }

    /// Adds a material; values are per band (the Python layer broadcasts scalars).
    #[pyo3(signature = (name, reflectance, transmittance=None, emission=None, back_reflectance=None, back_emission=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_material(
        &mut self,
        py: Python<'_>,
        name: &str,
        reflectance: Vec<f32>,
        transmittance: Option<Vec<f32>>,
        emission: Option<Vec<f32>>,
        back_reflectance: Option<Vec<f32>>,
        back_emission: Option<Vec<f32>>,
    ) -> PyResult<usize> {
        guarded(py, || {
            self.inner
                .add_material(
                    name,
                    MaterialValues {
                        reflectance,
                        transmittance,
                        emission,
                        back_reflectance,
                        back_emission,
                    },
                )
                .map_err(value_error)
        })
    }

    /// The index of material `name` (ValueError when unknown).
    fn material_index(&self, py: Python<'_>, name: &str) -> PyResult<u32> {
        guarded(py, || self.inner.material(name).map_err(value_error))
    }

    /// Adds triangles from packed arrays: `vertices` f64 x 3 per vertex, `indices` i64 x 3
    /// per triangle, `materials` i64 per triangle, `groups` i64 per triangle or None.
    #[pyo3(signature = (vertices, indices, materials, groups=None))]
    fn add_triangles(
        &mut self,
        py: Python<'_>,
        vertices: &[u8],
        indices: &[u8],
        materials: &[u8],
        groups: Option<&[u8]>,
    ) -> PyResult<()> {
        guarded(py, || {
            let v = numbers::<8, f64>(vertices, "vertices", f64::from_le_bytes)?;
            let i = numbers::<8, i64>(indices, "indices", i64::from_le_bytes)?;
            let m = numbers::<8, i64>(materials, "materials", i64::from_le_bytes)?;
            let g = match groups {
                Some(g) => Some(numbers::<8, i64>(g, "groups", i64::from_le_bytes)?),
                None => None,
            };
            let vertices: Vec<Vec3> = v
                .chunks_exact(3)
                .map(|c| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32))
                .collect();
            let n = vertices.len();
            let mut tris = Vec::with_capacity(i.len() / 3);
            for (t, c) in i.chunks_exact(3).enumerate() {
                let mut tri = [0u32; 3];
                for (d, &s) in tri.iter_mut().zip(c) {
                    if s < 0 || s as u64 >= n as u64 {
                        return Err(PyValueError::new_err(format!(
                            "triangle {t}: vertex index {s} is out of range ({n} vertices)"
                        )));
                    }
                    *d = s as u32;
                }
                tris.push(tri);
            }
            let count = tris.len();
            if m.len() != count || g.as_ref().is_some_and(|g| g.len() != count) {
                return Err(PyValueError::new_err(
                    "one material and one group per triangle",
                ));
            }
            let materials: Vec<u32> = m
                .iter()
                .map(|&x| x.clamp(0, u32::MAX as i64) as u32)
                .collect();
            let groups: Option<Vec<u64>> = match g {
                Some(g) => Some(
                    g.iter()
                        .enumerate()
                        .map(|(t, &x)| {
                            u64::try_from(x).map_err(|_| {
                                PyValueError::new_err(format!(
                                    "triangle {t}: group id {x} is negative (ids are 0 or more)"
                                ))
                            })
                        })
                        .collect::<PyResult<_>>()?,
                ),
                None => None,
            };
            self.inner
                .add_triangles(&vertices, &tris, &materials, groups.as_deref())
                .map_err(value_error)
        })
    }

    /// Adds a sun (direction towards it; irradiance per band on a plane facing it, W/m^2).
    fn add_sun(
        &mut self,
        py: Python<'_>,
        direction: [f64; 3],
        irradiance: Vec<f32>,
    ) -> PyResult<()> {
        guarded(py, || {
            let d = Vec3::new(
                direction[0] as f32,
                direction[1] as f32,
                direction[2] as f32,
            );
            self.inner.add_sun(d, &irradiance).map_err(value_error)
        })
    }

    /// Adds a direction of the sky (towards that patch of sky; irradiance per band on a
    /// plane facing it, W/m^2).
    fn add_sky(
        &mut self,
        py: Python<'_>,
        direction: [f64; 3],
        irradiance: Vec<f32>,
    ) -> PyResult<()> {
        guarded(py, || {
            let d = Vec3::new(
                direction[0] as f32,
                direction[1] as f32,
                direction[2] as f32,
            );
            self.inner.add_sky(d, &irradiance).map_err(value_error)
        })
    }

    /// The weighted directions of a generated sky (`hirad gen`'s): `rings` rings of equal
    /// solid angle over the upper hemisphere (z up), uniform or standard overcast, their
    /// irradiance on a horizontal plane summing to `horizontal` per band (W/m^2). Returns
    /// (directions, irradiance) as flat lists.
    #[staticmethod]
    fn sky_directions(
        py: Python<'_>,
        rings: u32,
        standard_overcast: bool,
        horizontal: Vec<f32>,
    ) -> PyResult<(Vec<f32>, Vec<f32>)> {
        guarded(py, || {
            use hirad::generate::sky::{SkyModel, sky};
            let model = if standard_overcast {
                SkyModel::StandardOvercast
            } else {
                SkyModel::Uniform
            };
            let n = horizontal.len();
            let lights = sky(rings, model, &horizontal);
            let dirs = lights.iter().flat_map(|l| l.towards.to_array()).collect();
            let irr = lights
                .iter()
                .flat_map(|l| l.irradiance[..n].to_vec())
                .collect();
            Ok((dirs, irr))
        })
    }

    /// The input triangle of every row of the results, as u64 bytes.
    fn row_triangles<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        let rows: Vec<u8> = self
            .inner
            .row_triangles()
            .iter()
            .flat_map(|t| t.to_le_bytes())
            .collect();
        PyBytes::new(py, &rows)
    }

    /// Writes the scene as `.hir` (text) or `.hirb` (binary image) by the path's extension,
    /// checked as a solve checks it, through a temporary file renamed into place.
    fn save(&self, py: Python<'_>, path: &str) -> PyResult<u64> {
        guarded(py, || {
            hirad::generate::write(&self.inner.scene, std::path::Path::new(path))
                .map_err(|e| error(py, class_name(&e), format!("{e:#}")))
        })
    }

    /// Triangles added.
    #[getter]
    fn triangles(&self) -> u64 {
        self.inner.triangles()
    }

    /// Band count.
    #[getter]
    fn bands(&self) -> usize {
        self.inner.scene.bands as usize
    }

    /// Material names, in order.
    #[getter]
    fn materials(&self) -> Vec<String> {
        self.inner
            .scene
            .materials
            .iter()
            .map(|m| m.name.clone())
            .collect()
    }

    /// Suns and sky directions.
    #[getter]
    fn lights(&self) -> (usize, usize) {
        (self.inner.scene.suns.len(), self.inner.scene.sky.len())
    }
}

fn le_bytes<'py, T: Copy, const W: usize>(
    py: Python<'py>,
    v: &[T],
    f: fn(T) -> [u8; W],
) -> Bound<'py, PyBytes> {
    let bytes: Vec<u8> = v.iter().flat_map(|&x| f(x)).collect();
    PyBytes::new(py, &bytes)
}

/// The exception class of an error the solve ended with (see `hirad::exit`).
fn class_name(e: &anyhow::Error) -> &'static str {
    match class_of(e) {
        Exit::Usage => "UsageError",
        Exit::Input => "InputError",
        Exit::NotRight | Exit::Failed => "HiradError",
    }
}

/// Solves `scene` (a path as str, or a `SceneBuilder`) as `hirad solve` would; returns a
/// dict of packed arrays and lists for the Python layer.
#[pyfunction]
#[pyo3(signature = (scene, method=None, instancing=None, epsilon=None, threads=None, memory=None, progress=None, cancelled=None))]
#[allow(clippy::too_many_arguments)]
fn solve<'py>(
    py: Python<'py>,
    scene: &Bound<'py, PyAny>,
    method: Option<String>,
    instancing: Option<String>,
    epsilon: Option<f64>,
    threads: Option<u64>,
    memory: Option<String>,
    progress: Option<Py<PyAny>>,
    cancelled: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let (input, triangles) = if let Ok(b) = scene.cast::<SceneBuilder>() {
        let b = b.borrow();
        (
            SceneInput::Model {
                name: "hirad.Scene".into(),
                scene: Box::new(b.inner.scene.clone()),
            },
            Some(b.row_triangles(py)),
        )
    } else {
        let path: String = scene.extract()?;
        (SceneInput::File(path.into()), None)
    };
    let request = Request {
        method,
        instancing,
        epsilon,
        threads,
        memory,
    };
    let cancelled = match cancelled {
        Some(c) => c,
        None => py.import("hirad._errors")?.getattr("Cancelled")?.unbind(),
    };
    let stop = Arc::new(Mutex::new(watch::Stop::default()));
    let reporter = watch::progress(progress, cancelled, Arc::clone(&stop));
    let run = py.detach(|| {
        catch_unwind(AssertUnwindSafe(|| {
            embed::solve(input, &request, Some(reporter))
        }))
    });
    let solved = match run {
        Ok(Ok(s)) => s,
        Ok(Err(e)) => return Err(error(py, class_name(&e), format!("{e:#}"))),
        Err(p) => {
            if p.downcast_ref::<watch::Cancelled>().is_some()
                && let Some(e) = stop.lock().unwrap_or_else(|e| e.into_inner()).error.take()
            {
                return Err(e);
            }
            return Err(error(
                py,
                "HiradError",
                format!("internal error (please report it): {}", panic_text(&*p)),
            ));
        }
    };
    guarded(py, || {
        let d = PyDict::new(py);
        let r = &solved.rows;
        d.set_item("bands", r.bands)?;
        d.set_item("count", r.len())?;
        d.set_item("ids", le_bytes(py, &r.ids, u64::to_le_bytes))?;
        d.set_item("area", le_bytes(py, &r.area, f32::to_le_bytes))?;
        d.set_item("radiosity", le_bytes(py, &r.radiosity, f32::to_le_bytes))?;
        d.set_item("irradiance", le_bytes(py, &r.irradiance, f32::to_le_bytes))?;
        if r.any_two_sided() {
            d.set_item(
                "radiosity_back",
                le_bytes(py, &r.radiosity_back, f32::to_le_bytes),
            )?;
            d.set_item(
                "irradiance_back",
                le_bytes(py, &r.irradiance_back, f32::to_le_bytes),
            )?;
        } else {
            d.set_item("radiosity_back", py.None())?;
            d.set_item("irradiance_back", py.None())?;
        }
        d.set_item("band_names", solved.band_names.clone())?;
        d.set_item("stats_json", solved.stats_json.clone())?;
        let g = &solved.groups;
        d.set_item("group_names", g.names.clone())?;
        d.set_item("group_of_row", le_bytes(py, &g.of_row, u32::to_le_bytes))?;
        d.set_item("group_area", le_bytes(py, &g.area, f64::to_le_bytes))?;
        d.set_item(
            "group_absorbed",
            le_bytes(py, &g.absorbed, f64::to_le_bytes),
        )?;
        let mut names: Vec<String> = Vec::new();
        let mut index = std::collections::HashMap::new();
        let of_row: Vec<u32> = g
            .materials
            .iter()
            .map(|m| {
                *index.entry(m.as_str()).or_insert_with(|| {
                    names.push(m.clone());
                    names.len() as u32 - 1
                })
            })
            .collect();
        d.set_item("material_names", names)?;
        d.set_item("material_of_row", le_bytes(py, &of_row, u32::to_le_bytes))?;
        match &solved.faces {
            Some(f) => d.set_item("faces", le_bytes(py, f, u64::to_le_bytes))?,
            None => d.set_item("faces", py.None())?,
        }
        match &triangles {
            Some(t) => d.set_item("triangles", t)?,
            None => d.set_item("triangles", py.None())?,
        }
        d.set_item("warnings", solved.warnings.clone())?;
        d.set_item("failure", solved.failure.clone())?;
        Ok(d)
    })
}

/// Parses a size as `--memory` does (`64M`, `2G`, `500000000`): bytes.
#[pyfunction]
fn parse_bytes(text: &str) -> PyResult<u64> {
    embed::parse_bytes(text).map_err(PyValueError::new_err)
}

/// The compiled module.
#[pymodule]
fn _hirad(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<SceneBuilder>()?;
    m.add_function(wrap_pyfunction!(solve, m)?)?;
    m.add_function(wrap_pyfunction!(parse_bytes, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
