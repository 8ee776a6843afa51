//! `hirad._hirad.SceneBuilder`: the Python face of `builder::Builder`. Arrays arrive as
//! little-endian bytes the Python layer packed after checking their shapes; what is wrong
//! with them beyond shapes (indices out of range, degenerate triangles, materials that
//! create energy) is a `ValueError` naming the triangle or value.

use crate::builder::{Builder, MaterialValues};
use crate::{class_name, error, guarded, value_error};
use glam::Vec3;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyBytes;

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
pub struct SceneBuilder {
    pub(crate) inner: Builder,
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
            let d = vec3(direction);
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
            let d = vec3(direction);
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
    pub(crate) fn row_triangles<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
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

/// A direction given as three doubles, as the scene model holds it (f32).
fn vec3(d: [f64; 3]) -> Vec3 {
    Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32)
}
