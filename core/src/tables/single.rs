//! The first scattering of a sun by each polygon of an original, as an observer sees it: the
//! sharp part of its bidirectional light, kept polygon by polygon.
//!
//! Light that a polygon scatters once, straight from the sun to the observer, changes as
//! fast with the two directions as the polygons' own visibility does: a sun near the
//! horizon lights a few steep leaf parts, and which of those an observer sees changes
//! within a few degrees. Tabulated over incoming x outgoing cells it would need grids far
//! finer than the light scattered more than once, which is smooth. So it is kept per
//! polygon: each polygon's normal, area and material, and the fraction of it visible from
//! each direction cell (the same fraction a sun reaches), interpolated per polygon. The
//! intensity towards `o` for a sun of 1 W/m^2 towards `d` is then
//! `sum_p A_p |n.d| |n.o| V_p(d) V_p(o) k_p / pi` (m^2/sr), with `k_p` the reflectance of
//! the side lit when the observer sees that side and the transmittance when it sees the
//! other. What the phase table holds is the rest: the light scattered more than once.

use super::grid::DirectionGrid;
use super::phase::TableError;
use crate::limits::MAX_BANDS;
use glam::Vec3;

/// Values per polygon in the shape slice before its material: normal x y z, area.
const GEOMETRY: usize = 4;

/// Values per polygon in the shape slice for `bands` bands: normal, area, then per band the
/// front reflectance, the back reflectance and the transmittance.
pub const fn shape_stride(bands: usize) -> usize {
    GEOMETRY + 3 * bands
}

/// Largest visible fraction stored: a byte's 255 is the whole polygon.
pub const VISIBLE_ONE: u8 = 255;

/// The intensity (m^2/sr per W/m^2) one polygon sends towards `observer` from its first
/// scattering of a sun towards `source`, both unit, for a polygon of unit `normal`, `area`
/// (m^2), front and back reflectance and transmittance `rho_front`, `rho_back`, `tau`,
/// without its visibility (multiply by the fractions the sun and the observer reach).
pub fn first_scatter(
    normal: Vec3,
    area: f32,
    [rho_front, rho_back, tau]: [f32; 3],
    source: Vec3,
    observer: Vec3,
) -> f32 {
    let (cd, co) = (normal.dot(source), normal.dot(observer));
    if cd == 0.0 || co == 0.0 {
        return 0.0;
    }
    let k = match (cd > 0.0, co > 0.0) {
        (true, true) => rho_front,
        (false, false) => rho_back,
        _ => tau,
    };
    area * (cd * co).abs() * k / core::f32::consts::PI
}

/// The polygons of an original with their visible fractions, over caller storage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SingleScatter<'a> {
    /// Grid of the visible fractions.
    grid: DirectionGrid,
    /// Bands, 1..=MAX_BANDS.
    bands: usize,
    /// Polygons.
    polygons: usize,
    /// `[p * shape_stride(bands) + k]`: normal x y z (unit, the original's frame), area
    /// (m^2), then per band `rho_front`, `rho_back`, `tau` (0..=1).
    shape: &'a [f32],
    /// `[cell * polygons + p]`: the fraction of polygon `p` from which a ray towards the
    /// cell's centre leaves the box unblocked, in 1/255 steps.
    visible: &'a [u8],
}

impl<'a> SingleScatter<'a> {
    /// Checks the lengths and ranges: `polygons` at least 1, unit normals, finite
    /// non-negative areas, materials within 0..=1.
    pub fn new(
        grid: DirectionGrid,
        bands: usize,
        polygons: usize,
        shape: &'a [f32],
        visible: &'a [u8],
    ) -> Result<Self, TableError> {
        if bands == 0 || bands > MAX_BANDS {
            return Err(TableError::Bands);
        }
        let stride = shape_stride(bands);
        let expected = polygons as u64 * stride as u64;
        if polygons == 0 || shape.len() as u64 != expected {
            return Err(TableError::Length {
                expected,
                given: shape.len() as u64,
            });
        }
        let cells = grid.cells() as u64 * polygons as u64;
        if visible.len() as u64 != cells {
            return Err(TableError::Length {
                expected: cells,
                given: visible.len() as u64,
            });
        }
        for (p, s) in shape.chunks_exact(stride).enumerate() {
            if let Some(k) = shape_fault(s) {
                return Err(TableError::Value {
                    index: (p * stride + k) as u64,
                });
            }
        }
        Ok(Self {
            grid,
            bands,
            polygons,
            shape,
            visible,
        })
    }

    /// Fractions over storage checked before (see `DirectionalTables::trusted`).
    pub(crate) fn trusted(
        grid: DirectionGrid,
        bands: usize,
        polygons: usize,
        shape: &'a [f32],
        visible: &'a [u8],
    ) -> Self {
        Self {
            grid,
            bands,
            polygons,
            shape,
            visible,
        }
    }

    /// The grid of the visible fractions.
    pub fn grid(&self) -> DirectionGrid {
        self.grid
    }

    /// Polygons.
    pub fn polygons(&self) -> usize {
        self.polygons
    }

    /// The shape values (see [`shape_stride`]).
    pub fn shape(&self) -> &'a [f32] {
        self.shape
    }

    /// The visible fractions, `[cell * polygons + p]` in 1/255 steps.
    pub fn visible(&self) -> &'a [u8] {
        self.visible
    }

    /// Polygon `p`'s visible fraction towards `d`, interpolated (0..=1) over the weights
    /// `w` of `d` on the grid.
    pub(crate) fn fraction(&self, w: &[(u32, f32); 4], p: usize) -> f32 {
        let mut v = 0.0;
        for &(c, x) in w {
            v += x * self.visible[c as usize * self.polygons + p] as f32;
        }
        v / VISIBLE_ONE as f32
    }

    /// Polygon `p`'s unit normal and area (m^2) in the original's frame.
    pub fn normal_area(&self, p: usize) -> (Vec3, f32) {
        let s = &self.shape[p * shape_stride(self.bands)..];
        (Vec3::new(s[0], s[1], s[2]), s[3])
    }

    /// Polygon `p`'s front reflectance, back reflectance and transmittance in band `band`.
    pub fn optics(&self, p: usize, band: usize) -> [f32; 3] {
        let s = &self.shape[p * shape_stride(self.bands) + GEOMETRY + 3 * band..];
        [s[0], s[1], s[2]]
    }

    /// Polygon `p`'s unit normal and area (m^2) in the original's frame, and its front
    /// reflectance, back reflectance and transmittance in band `band`.
    pub fn polygon(&self, p: usize, band: usize) -> (Vec3, f32, [f32; 3]) {
        let s = &self.shape[p * shape_stride(self.bands)..];
        let m = GEOMETRY + 3 * band;
        (
            Vec3::new(s[0], s[1], s[2]),
            s[3],
            [s[m], s[m + 1], s[m + 2]],
        )
    }

    /// Intensity (m^2/sr) towards `observer` in band `band` of the light the polygons
    /// scatter once from a sun of 1 W/m^2 towards `source` (both in the original's frame).
    pub fn intensity(&self, source: Vec3, observer: Vec3, band: usize) -> f32 {
        let (d, o) = (source.normalize_or_zero(), observer.normalize_or_zero());
        let (wd, wo) = (self.grid.weights(d), self.grid.weights(o));
        let stride = shape_stride(self.bands);
        let mut sum = 0.0f32;
        for (p, s) in self.shape.chunks_exact(stride).enumerate() {
            let m = GEOMETRY + 3 * band;
            let f = first_scatter(
                Vec3::new(s[0], s[1], s[2]),
                s[3],
                [s[m], s[m + 1], s[m + 2]],
                d,
                o,
            );
            if f > 0.0 {
                sum += f * self.fraction(&wd, p) * self.fraction(&wo, p);
            }
        }
        sum
    }
}

/// The index within one polygon's shape values of the first that is out of range, if any.
fn shape_fault(s: &[f32]) -> Option<usize> {
    if let Some(k) = s.iter().position(|v| !v.is_finite()) {
        return Some(k);
    }
    let n = Vec3::new(s[0], s[1], s[2]);
    if (n.length() - 1.0).abs() > 1e-3 {
        return Some(0);
    }
    if s[3] < 0.0 {
        return Some(3);
    }
    s[GEOMETRY..]
        .iter()
        .position(|v| !(0.0..=1.0).contains(v))
        .map(|k| k + GEOMETRY)
}
