//! Materials for the generators: each is added to the scene once, by name, and polygons refer
//! to it by the index returned. Values are per band: reflectance and transmittance
//! dimensionless, emitted exitance in W/m^2.

use crate::scene::{Material, MaterialData, Scene};

/// Copies `values` into the first bands of a per-band array.
fn fill(dst: &mut [f32], values: &[f32]) {
    for (d, v) in dst.iter_mut().zip(values) {
        *d = *v;
    }
}

/// Adds `data` under `name` and returns its index.
fn add(scene: &mut Scene, name: &str, data: MaterialData) -> u32 {
    scene.materials.push(Material {
        name: name.to_string(),
        data,
    });
    (scene.materials.len() - 1) as u32
}

/// A one-sided diffuse reflector (walls, wood, soil): its back absorbs everything.
pub fn diffuse(scene: &mut Scene, name: &str, rho: &[f32]) -> u32 {
    let mut m = MaterialData::black(scene.bands);
    fill(&mut m.rho_front, rho);
    add(scene, name, m)
}

/// A one-sided emitter (lamp panel, window pane) with reflectance `rho` and exitance `emit`.
pub fn emitter(scene: &mut Scene, name: &str, rho: &[f32], emit: &[f32]) -> u32 {
    let mut m = MaterialData::black(scene.bands);
    fill(&mut m.rho_front, rho);
    fill(&mut m.emit_front, emit);
    add(scene, name, m)
}

/// A two-sided translucent material (leaves, petals): front and back reflectance and a
/// diffuse transmittance shared by both sides.
pub fn two_sided(scene: &mut Scene, name: &str, rho: &[f32], back_rho: &[f32], tau: &[f32]) -> u32 {
    let mut m = MaterialData::black(scene.bands);
    m.two_sided = true;
    fill(&mut m.rho_front, rho);
    fill(&mut m.rho_back, back_rho);
    fill(&mut m.tau, tau);
    add(scene, name, m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn materials_pass_the_core_checks() {
        let mut s = Scene::new(2);
        let a = diffuse(&mut s, "soil", &[0.1, 0.25]);
        let b = emitter(&mut s, "lamp", &[0.8, 0.8], &[100.0, 50.0]);
        let c = two_sided(&mut s, "leaf", &[0.08, 0.45], &[0.1, 0.45], &[0.05, 0.45]);
        assert_eq!((a, b, c), (0, 1, 2));
        assert!(s.materials.iter().all(|m| m.data.check().is_ok()));
        assert!(s.materials[2].data.two_sided && !s.materials[0].data.two_sided);
        assert_eq!(s.materials[1].data.emit_front[0], 100.0);
    }
}
