//! The material table of an import: materials of every MTL file read, in definition order,
//! plus the built-in `default` for faces that come before any `usemtl`.

use super::diag::Warnings;
use super::mtl::{DEFAULT_REFLECTANCE, MtlMaterial, OBJ_BANDS};
use crate::scene::{Material, MaterialData};
use std::collections::{BTreeSet, HashMap};

/// Name of the material of faces before any `usemtl` (grey, reflectance
/// [`DEFAULT_REFLECTANCE`] in every band, unless an MTL file defines a material of that name).
pub const DEFAULT_MATERIAL: &str = "default";

/// Materials by name and in order.
#[derive(Debug, Default)]
pub(crate) struct Materials {
    list: Vec<Material>,
    index: HashMap<String, u32>,
    /// MTL files already read (as named in `mtllib`): naming one again reads nothing.
    files: BTreeSet<String>,
}

impl Materials {
    /// Whether the MTL file `file` has already been read.
    pub fn has_file(&self, file: &str) -> bool {
        self.files.contains(file)
    }

    /// Adds the materials of the MTL file `file`. A name defined before keeps its first
    /// definition (faces may already use it), with a warning.
    pub fn add_file(&mut self, file: &str, materials: Vec<MtlMaterial>, warnings: &mut Warnings) {
        self.files.insert(file.to_string());
        for m in materials {
            if self.index.contains_key(&m.name) {
                warnings.add(
                    file,
                    m.pos,
                    format!(
                        "material '{}' is defined again; the first definition is kept",
                        m.name
                    ),
                );
                continue;
            }
            self.push(m.name, m.data);
        }
    }

    fn push(&mut self, name: String, data: MaterialData) -> u32 {
        // More than u32::MAX materials cannot be read into memory; saturate rather than wrap.
        let i = u32::try_from(self.list.len()).unwrap_or(u32::MAX);
        self.index.insert(name.clone(), i);
        self.list.push(Material { name, data });
        i
    }

    /// Index of the material called `name`.
    pub fn lookup(&self, name: &str) -> Option<u32> {
        self.index.get(name).copied()
    }

    /// Index of [`DEFAULT_MATERIAL`], adding the built-in grey the first time if no MTL file
    /// defined one.
    pub fn default_material(&mut self) -> u32 {
        if let Some(i) = self.lookup(DEFAULT_MATERIAL) {
            return i;
        }
        let mut data = MaterialData::black(OBJ_BANDS);
        data.rho_front[..OBJ_BANDS as usize].fill(DEFAULT_REFLECTANCE);
        self.push(DEFAULT_MATERIAL.to_string(), data)
    }

    /// The materials, in order.
    pub fn finish(self) -> Vec<Material> {
        self.list
    }
}
