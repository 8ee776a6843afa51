//! Spectral bands and the materials of tree scenes: bark, leaves (two-sided, translucent),
//! soil, and emitters; the sun and sky irradiance in each band set.
//!
//! Values per band (dimensionless reflectance and transmittance; W/m^2 for exitance and
//! irradiance). PAR/NIR values are typical of poplar leaves, bark and dry soil; RGB values
//! give a natural-looking picture.

use super::axis::TreeMaterials;
use crate::scene::{Material, MaterialData, Scene};

/// The band set of a generated scene.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bands {
    /// Two bands, `par nir`: photosynthetically active radiation (400-700 nm) and near
    /// infrared (700-2500 nm), as plant-canopy models use.
    ParNir,
    /// Three bands, `red green blue`, for natural-looking pictures.
    Rgb,
}

impl Bands {
    /// Number of bands.
    pub fn count(self) -> u8 {
        match self {
            Bands::ParNir => 2,
            Bands::Rgb => 3,
        }
    }

    /// Band names.
    pub fn names(self) -> Vec<String> {
        let n: &[&str] = match self {
            Bands::ParNir => &["par", "nir"],
            Bands::Rgb => &["red", "green", "blue"],
        };
        n.iter().map(|s| s.to_string()).collect()
    }

    /// The values of this band set.
    pub fn pick(self, par_nir: [f32; 2], rgb: [f32; 3]) -> Vec<f32> {
        match self {
            Bands::ParNir => par_nir.to_vec(),
            Bands::Rgb => rgb.to_vec(),
        }
    }

    /// A scene with these bands and no content.
    pub fn scene(self) -> Scene {
        let mut s = Scene::new(self.count());
        s.band_names = self.names();
        s
    }

    /// Direct normal irradiance of a clear-sky sun (W/m^2 per band).
    pub fn sun(self) -> Vec<f32> {
        self.pick([400.0, 450.0], [150.0, 145.0, 135.0])
    }

    /// Diffuse sky irradiance on a horizontal plane (W/m^2 per band).
    pub fn sky(self) -> Vec<f32> {
        self.pick([80.0, 50.0], [22.0, 28.0, 38.0])
    }
}

/// Adds a one-sided diffuse material; returns its index.
pub fn add_diffuse(scene: &mut Scene, name: &str, rho: &[f32]) -> u32 {
    let mut d = MaterialData::black(scene.bands);
    d.rho_front[..rho.len()].copy_from_slice(rho);
    push(scene, name, d)
}

/// Adds a one-sided emitter of exitance `emit` (W/m^2 per band) and reflectance `rho`.
pub fn add_emitter(scene: &mut Scene, name: &str, rho: &[f32], emit: &[f32]) -> u32 {
    let mut d = MaterialData::black(scene.bands);
    d.rho_front[..rho.len()].copy_from_slice(rho);
    d.emit_front[..emit.len()].copy_from_slice(emit);
    push(scene, name, d)
}

/// Adds a two-sided translucent material (the same reflectance on both sides).
pub fn add_leaf(scene: &mut Scene, name: &str, rho: &[f32], tau: &[f32]) -> u32 {
    let mut d = MaterialData::black(scene.bands);
    d.two_sided = true;
    d.rho_front[..rho.len()].copy_from_slice(rho);
    d.rho_back[..rho.len()].copy_from_slice(rho);
    d.tau[..tau.len()].copy_from_slice(tau);
    push(scene, name, d)
}

fn push(scene: &mut Scene, name: &str, data: MaterialData) -> u32 {
    scene.materials.push(Material {
        name: name.to_string(),
        data,
    });
    (scene.materials.len() - 1) as u32
}

/// Adds `bark` and `leaf`; returns their indices.
pub fn add_tree_materials(scene: &mut Scene, bands: Bands) -> TreeMaterials {
    let bark = add_diffuse(scene, "bark", &bands.pick([0.15, 0.35], [0.16, 0.15, 0.13]));
    let leaf = add_leaf(
        scene,
        "leaf",
        &bands.pick([0.08, 0.45], [0.05, 0.12, 0.03]),
        &bands.pick([0.05, 0.45], [0.03, 0.10, 0.02]),
    );
    TreeMaterials { bark, leaf }
}

/// Adds `soil`; returns its index.
pub fn add_soil(scene: &mut Scene, bands: Bands) -> u32 {
    add_diffuse(scene, "soil", &bands.pick([0.10, 0.25], [0.17, 0.14, 0.10]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn materials_pass_the_core_checks() {
        for b in [Bands::ParNir, Bands::Rgb] {
            let mut s = b.scene();
            let m = add_tree_materials(&mut s, b);
            add_soil(&mut s, b);
            add_emitter(&mut s, "lamp", &b.pick([0.8; 2], [0.8; 3]), &b.sun());
            assert!(s.materials.iter().all(|m| m.data.check().is_ok()));
            assert!(s.materials[m.leaf as usize].data.two_sided);
            assert!(!s.materials[m.bark as usize].data.two_sided);
            assert_eq!(s.band_names.len(), b.count() as usize);
        }
    }
}
