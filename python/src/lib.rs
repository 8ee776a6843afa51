//! `hirad._hirad`: the compiled half of the Python package. The Python layer (`pysrc/hirad`)
//! checks arguments and shapes, packs arrays into little-endian bytes and turns the bytes
//! that come back into NumPy arrays; this module builds scenes (`builder`) and runs the
//! command line's own solve (`hirad::embed`) with the GIL released, progress and Ctrl-C
//! handled by `watch`. No panic crosses into Python: every entry point catches unwinding.
//!
//! Units: metres, m^2, W/m^2, W.

mod builder;
mod scene_py;
mod watch;

use hirad::embed::{self, Request, SceneInput};
use hirad::exit::{Exit, class_of};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use scene_py::SceneBuilder;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::{Arc, Mutex};

/// The exception class `name` of `hirad._errors` called with `message`.
pub(crate) fn error(py: Python<'_>, name: &str, message: String) -> PyErr {
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
pub(crate) fn guarded<T>(py: Python<'_>, f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|p| {
        Err(error(
            py,
            "HiradError",
            format!("internal error (please report it): {}", panic_text(&*p)),
        ))
    })
}

/// A `ValueError` with the message of `e`.
pub(crate) fn value_error(e: anyhow::Error) -> PyErr {
    PyValueError::new_err(format!("{e:#}"))
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
pub(crate) fn class_name(e: &anyhow::Error) -> &'static str {
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
