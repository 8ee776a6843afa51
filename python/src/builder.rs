//! `hirad.Scene`'s compiled half: the runner's scene model (`hirad::scene::Scene`) built
//! from the arrays the Python layer checked and packed (little-endian bytes), with the
//! core's own checks on materials, lights and triangles as they are added.
//!
//! Layout: triangles without a group are the root cluster's own polygons; each group id is
//! a child cluster of the root named by the id (`scene/17` in the results' group column),
//! in order of first appearance. Global ids follow the expansion (the root's own polygons,
//! then each group's), so the builder remembers which input triangle each row is.
//!
//! Units: metres, W/m^2.

use anyhow::{Result, anyhow, bail};
use glam::Vec3;
use hirad::scene::{self, Cluster, Material, MaterialData, Scene};
use hirad_core::geometry::{ShapeError, UNIT_TOLERANCE, polygon_shape};
use hirad_core::limits::{MAX_BANDS, MAX_NAME_BYTES};
use std::collections::HashMap;

/// A scene being built, with the input triangle behind every polygon.
#[derive(Clone, Debug)]
pub struct Builder {
    /// The model.
    pub scene: Scene,
    /// Child index of the cluster of each group id.
    groups: HashMap<u64, usize>,
    /// Input triangle indices of the root's own polygons (`[0]`) and of each group's
    /// (`[k + 1]`), in polygon order.
    triangles: Vec<Vec<u64>>,
    /// Triangles added so far.
    added: u64,
}

/// Per-band values of a material, checked by the Python layer to hold `bands` finite
/// numbers each.
pub struct MaterialValues {
    /// Front reflectance (0..=1).
    pub reflectance: Vec<f32>,
    /// Transmittance, both sides (0..=1); makes the material two-sided.
    pub transmittance: Option<Vec<f32>>,
    /// Front emitted exitance (W/m^2).
    pub emission: Option<Vec<f32>>,
    /// Back reflectance (0..=1); makes the material two-sided. Default: the front's.
    pub back_reflectance: Option<Vec<f32>>,
    /// Back emitted exitance (W/m^2); makes the material two-sided.
    pub back_emission: Option<Vec<f32>>,
}

fn bands_array(v: &[f32]) -> [f32; MAX_BANDS] {
    let mut a = [0.0; MAX_BANDS];
    for (d, s) in a.iter_mut().zip(v) {
        *d = *s;
    }
    a
}

/// A direction as the `.hir` reader keeps it: unit within the core's tolerance as given,
/// else normalised (scaled by its largest component first); `None` when zero or not finite.
pub fn unit_direction(v: Vec3) -> Option<Vec3> {
    if !v.is_finite() {
        return None;
    }
    if (v.length_squared() - 1.0).abs() <= UNIT_TOLERANCE {
        return Some(v);
    }
    let m = v.abs().max_element();
    if m <= 0.0 {
        return None;
    }
    (v / m).try_normalize()
}

impl Builder {
    /// An empty scene of `bands` bands named `names` (empty: unnamed).
    pub fn new(bands: usize, names: Vec<String>) -> Result<Builder> {
        if !(1..=MAX_BANDS).contains(&bands) {
            bail!("{bands} bands; 1 to {MAX_BANDS} are supported");
        }
        if !names.is_empty() && names.len() != bands {
            bail!("{} band names for {bands} bands", names.len());
        }
        if let Some(n) = names.iter().find(|n| n.len() > MAX_NAME_BYTES) {
            bail!("band name '{n}' is longer than {MAX_NAME_BYTES} bytes");
        }
        let mut scene = Scene::new(bands as u8);
        scene.band_names = names;
        scene.root = Cluster::named("scene");
        Ok(Builder {
            scene,
            groups: HashMap::new(),
            triangles: vec![Vec::new()],
            added: 0,
        })
    }

    /// Adds material `name`: two-sided (a leaf) when it has a transmittance, a back
    /// reflectance or a back emission, as in the `.hir` format.
    pub fn add_material(&mut self, name: &str, v: MaterialValues) -> Result<usize> {
        if self.scene.material_index(name).is_some() {
            bail!("material '{name}' is defined twice");
        }
        let two_sided =
            v.transmittance.is_some() || v.back_reflectance.is_some() || v.back_emission.is_some();
        let zero = vec![0.0; self.scene.bands as usize];
        let data = MaterialData {
            bands: self.scene.bands,
            two_sided,
            rho_front: bands_array(&v.reflectance),
            emit_front: bands_array(v.emission.as_ref().unwrap_or(&zero)),
            rho_back: if two_sided {
                bands_array(v.back_reflectance.as_ref().unwrap_or(&v.reflectance))
            } else {
                [0.0; MAX_BANDS]
            },
            tau: bands_array(v.transmittance.as_ref().unwrap_or(&zero)),
            emit_back: bands_array(v.back_emission.as_ref().unwrap_or(&zero)),
        };
        data.check()
            .map_err(|e| anyhow!("material '{name}': {e}"))?;
        if name.len() > MAX_NAME_BYTES {
            bail!(
                "material '{name}': its name is longer than {} bytes",
                MAX_NAME_BYTES
            );
        }
        self.scene.materials.push(Material {
            name: name.to_string(),
            data,
        });
        Ok(self.scene.materials.len() - 1)
    }

    /// Index of material `name`.
    pub fn material(&self, name: &str) -> Result<u32> {
        self.scene
            .material_index(name)
            .map(|i| i as u32)
            .ok_or_else(|| {
                let known: Vec<&str> = self
                    .scene
                    .materials
                    .iter()
                    .map(|m| m.name.as_str())
                    .collect();
                anyhow!(
                    "unknown material '{name}' (add it with add_material first; known: {})",
                    if known.is_empty() {
                        "none".to_string()
                    } else {
                        known.join(", ")
                    }
                )
            })
    }

    /// Adds triangles: `vertices` (m) indexed by `indices` (3 per triangle, each below
    /// `vertices.len()`), `materials` one index per triangle, `groups` one id per triangle
    /// or none. Every triangle is checked as the core checks polygons (finite, not
    /// degenerate, not too small for single precision); nothing is added when one fails.
    pub fn add_triangles(
        &mut self,
        vertices: &[Vec3],
        indices: &[[u32; 3]],
        materials: &[u32],
        groups: Option<&[u64]>,
    ) -> Result<()> {
        let first = self.added;
        for (t, tri) in indices.iter().enumerate() {
            if let Some(&i) = tri.iter().find(|&&i| i as usize >= vertices.len()) {
                bail!(
                    "triangle {t}: vertex index {i} is out of range ({} vertices)",
                    vertices.len()
                );
            }
            let corners = tri.map(|i| vertices[i as usize]);
            match polygon_shape(&corners) {
                Ok(_) => {}
                Err(ShapeError::TooSmall) => {
                    bail!(
                        "{}",
                        scene::too_small_message(&format!("triangle {t}"), &corners)
                    )
                }
                Err(e) => bail!(
                    "triangle {t} (corners {:?}, {:?}, {:?}): {e}",
                    corners[0].to_array(),
                    corners[1].to_array(),
                    corners[2].to_array()
                ),
            }
            if materials[t] as usize >= self.scene.materials.len() {
                bail!("triangle {t}: no material {}", materials[t]);
            }
        }
        // Vertices copied into each cluster they are used in, once each.
        let mut remap: HashMap<(usize, u32), u32> = HashMap::new();
        for (t, tri) in indices.iter().enumerate() {
            let slot = match groups.map(|g| g[t]) {
                None => 0,
                Some(g) => {
                    let next = self.scene.root.children.len();
                    let k = *self.groups.entry(g).or_insert(next);
                    if k == next {
                        self.scene
                            .root
                            .children
                            .push(Cluster::named(&g.to_string()));
                        self.triangles.push(Vec::new());
                    }
                    k + 1
                }
            };
            let cluster = if slot == 0 {
                &mut self.scene.root
            } else {
                &mut self.scene.root.children[slot - 1]
            };
            let c = tri.map(|i| {
                *remap
                    .entry((slot, i))
                    .or_insert_with(|| cluster.vertex(vertices[i as usize]))
            });
            cluster
                .polygons
                .push(scene::triangle(c[0], c[1], c[2], materials[t]));
            self.triangles[slot].push(first + t as u64);
        }
        self.added += indices.len() as u64;
        Ok(())
    }

    /// Adds a sun: `towards` the sun (the `.hir` format's `sun from`), `irradiance` per band
    /// on a plane facing it (W/m^2).
    pub fn add_sun(&mut self, towards: Vec3, irradiance: &[f32]) -> Result<()> {
        let d = unit_direction(towards)
            .ok_or_else(|| anyhow!("the sun's direction {:?} is zero", towards.to_array()))?;
        self.scene.suns.push(scene::light(d, irradiance));
        Ok(())
    }

    /// Adds one direction of the sky (the `.hir` format's `sky from`): `towards` that patch
    /// of sky, `irradiance` per band on a plane facing it (W/m^2).
    pub fn add_sky(&mut self, towards: Vec3, irradiance: &[f32]) -> Result<()> {
        let d = unit_direction(towards)
            .ok_or_else(|| anyhow!("the sky direction {:?} is zero", towards.to_array()))?;
        self.scene.sky.push(scene::light(d, irradiance));
        Ok(())
    }

    /// Input triangle of every row of the results (global-id order).
    pub fn row_triangles(&self) -> Vec<u64> {
        self.triangles.iter().flatten().copied().collect()
    }

    /// Triangles added.
    pub fn triangles(&self) -> u64 {
        self.added
    }
}
