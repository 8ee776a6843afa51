//! Where finished results go. The core never holds a complete solution: it hands each
//! polygon to a sink as soon as its final value exists, in global-id order, first its leaf
//! patches (for images), then the polygon's area-weighted means (for tables).

use glam::Vec3;

/// One leaf patch of a finished polygon (the polygon itself when it was never subdivided).
#[derive(Clone, Copy, Debug)]
pub struct PatchResult<'a> {
    /// Global id of the polygon the patch belongs to.
    pub id: u64,
    /// Corners in world space (m), 3 or 4, counter-clockwise seen from the front.
    pub corners: &'a [Vec3],
    /// Unit normal of the front side.
    pub normal: Vec3,
    /// Index of the polygon's material in the scene's material list (`MaterialId`), so that
    /// images can tell material boundaries from continuous surfaces.
    pub material: u32,
    /// Radiosity per band (W/m^2): `[front, back]`; the back slice is empty for one-sided
    /// materials (their back emits nothing).
    pub radiosity: [&'a [f32]; 2],
}

/// A finished input polygon: area-weighted means over its leaf patches.
#[derive(Clone, Copy, Debug)]
pub struct PolygonResult<'a> {
    /// Global id: the polygon's index in the depth-first expansion of the scene.
    pub id: u64,
    /// Area (m^2).
    pub area: f32,
    /// True when the material is two-sided (then the back slices hold values).
    pub two_sided: bool,
    /// Radiosity per band (W/m^2): `[front, back]`; back is empty when one-sided.
    pub radiosity: [&'a [f32]; 2],
    /// Irradiance per band (W/m^2): `[front, back]`; back is empty when one-sided.
    pub irradiance: [&'a [f32]; 2],
}

/// Receives finished results. Errors stop the solve and are handed back to the caller.
pub trait Sink {
    /// The caller's error type.
    type Error;

    /// A leaf patch; called for every leaf of a polygon before [`Sink::polygon`].
    fn patch(&mut self, patch: &PatchResult<'_>) -> Result<(), Self::Error> {
        let _ = patch;
        Ok(())
    }

    /// A finished polygon, in global-id order.
    fn polygon(&mut self, polygon: &PolygonResult<'_>) -> Result<(), Self::Error>;
}

/// A sink that keeps nothing (for planning runs and benchmarks).
#[derive(Clone, Copy, Debug, Default)]
pub struct Discard;

impl Sink for Discard {
    type Error = core::convert::Infallible;

    fn polygon(&mut self, _: &PolygonResult<'_>) -> Result<(), Self::Error> {
        Ok(())
    }
}
