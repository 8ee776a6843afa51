//! Suns and skies as directional sources.
//!
//! A sky is a set of weighted directions over the upper hemisphere (z up): rings of equal
//! solid angle, each direction carrying the share of the diffuse irradiance its patch of sky
//! sends onto a horizontal plane. The radiance distribution is uniform (UOC) or the standard
//! overcast sky (SOC, radiance proportional to 1 + 2 sin(elevation)).

use crate::scene::{LightData, light};
use glam::Vec3;

/// How sky radiance varies with elevation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SkyModel {
    /// Uniform overcast.
    Uniform,
    /// Standard overcast (CIE): brighter towards the zenith.
    StandardOvercast,
}

/// A sun at `elevation_deg` above the horizon and `azimuth_deg` from +x towards +y, with
/// direct normal irradiance `irradiance` per band (W/m^2).
pub fn sun(elevation_deg: f32, azimuth_deg: f32, irradiance: &[f32]) -> LightData {
    let (e, a) = (elevation_deg.to_radians(), azimuth_deg.to_radians());
    light(
        Vec3::new(e.cos() * a.cos(), e.cos() * a.sin(), e.sin()).normalize(),
        irradiance,
    )
}

/// A sky of `rings` x about `4 rings` directions whose irradiance on a horizontal plane sums
/// to `horizontal` per band (W/m^2).
pub fn sky(rings: u32, model: SkyModel, horizontal: &[f32]) -> Vec<LightData> {
    let rings = rings.max(1);
    let mut dirs: Vec<(Vec3, f32)> = Vec::new();
    for r in 0..rings {
        // Equal solid angle: cos(zenith) spaced evenly; direction at the ring's centre.
        let (c0, c1) = (
            1.0 - r as f32 / rings as f32,
            1.0 - (r + 1) as f32 / rings as f32,
        );
        let cz = 0.5 * (c0 + c1);
        let sz = (1.0 - cz * cz).max(0.0).sqrt();
        let n = (4 * (r + 1)).min(64);
        for k in 0..n {
            let phi = (k as f32 + 0.5 * (r % 2) as f32) / n as f32 * std::f32::consts::TAU;
            let d = Vec3::new(sz * phi.cos(), sz * phi.sin(), cz).normalize();
            let radiance = match model {
                SkyModel::Uniform => 1.0,
                SkyModel::StandardOvercast => 1.0 + 2.0 * cz,
            };
            // Solid angle of each direction: 2 pi / rings / n; its horizontal irradiance
            // share is radiance x solid angle x cos(zenith).
            dirs.push((
                d,
                radiance * (std::f32::consts::TAU / rings as f32 / n as f32) * cz,
            ));
        }
    }
    let total: f32 = dirs.iter().map(|(_, w)| w).sum();
    dirs.into_iter()
        .map(|(d, w)| {
            let share = w / total;
            // Irradiance on a plane facing the direction: the horizontal share / cos(zenith).
            let irr: Vec<f32> = horizontal
                .iter()
                .map(|h| h * share / d.z.max(1e-3))
                .collect();
            light(d, &irr)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sky_irradiance_sums_on_the_horizontal() {
        for model in [SkyModel::Uniform, SkyModel::StandardOvercast] {
            let s = sky(6, model, &[100.0, 80.0]);
            let h: f32 = s.iter().map(|l| l.irradiance[0] * l.towards.z).sum();
            assert!((h - 100.0).abs() < 1e-2, "{h}");
            assert!(
                s.iter()
                    .all(|l| l.towards.z > 0.0 && (l.towards.length() - 1.0).abs() < 1e-5)
            );
        }
        let s = sun(30.0, 90.0, &[500.0]);
        assert!((s.towards.z - 0.5).abs() < 1e-6 && s.towards.y > 0.86);
    }
}
