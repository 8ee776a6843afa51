//! An original's phase table (paper section 3.1, DESIGN.md "Directional table"): the light
//! its contents scatter out of the box for light that comes in, per unit irradiance, as
//! functions of the incoming direction (the uniform form, the paper's) and of the incoming
//! and the outgoing directions (the bidirectional form). Directions are unit vectors in the
//! original's frame: incoming ones point towards the source (as a sun's `towards`), outgoing
//! ones towards the observer.

use super::grid::DirectionGrid;
use glam::Vec3;

/// A phase table over caller storage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhaseTable<'a> {
    /// Grid of incoming directions.
    incoming: DirectionGrid,
    /// Grid of outgoing directions (bidirectional form).
    outgoing: DirectionGrid,
    /// Bands, 1..=MAX_BANDS.
    bands: usize,
    /// `[cell_in * bands + band]`: the fraction of the power the box intercepts from a sun
    /// in that cell (irradiance x projected area `A(dir)`) that leaves it scattered, 0..=1.
    scattered: &'a [f32],
    /// `[(cell_in * out_cells + cell_out) * bands + band]`: the radiant intensity (W/sr) that
    /// leaves the box towards the outgoing cell for a sun of 1 W/m^2 in the incoming cell:
    /// m^2/sr.
    intensity: &'a [f32],
}

/// Why storage is not a phase table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhaseError {
    /// No band, or more than the core holds.
    Bands,
    /// A slice's length is not what the grids and bands make.
    Length {
        /// Values expected.
        expected: u64,
        /// Values given.
        given: u64,
    },
    /// A value is not finite or is negative (or, for a fraction, above 1 by more than
    /// rounding).
    Value {
        /// Index of the first bad value in its slice.
        index: u64,
    },
}

impl<'a> PhaseTable<'a> {
    /// Checks the lengths and values of `scattered` and `intensity` against the grids.
    pub fn new(
        incoming: DirectionGrid,
        outgoing: DirectionGrid,
        bands: usize,
        scattered: &'a [f32],
        intensity: &'a [f32],
    ) -> Result<Self, PhaseError> {
        if bands == 0 || bands > crate::limits::MAX_BANDS {
            return Err(PhaseError::Bands);
        }
        let n_in = incoming.cells() as u64 * bands as u64;
        let n_bi = n_in * outgoing.cells() as u64;
        for (expected, s) in [(n_in, scattered), (n_bi, intensity)] {
            if s.len() as u64 != expected {
                return Err(PhaseError::Length {
                    expected,
                    given: s.len() as u64,
                });
            }
        }
        if let Some(i) = scattered
            .iter()
            .position(|v| !v.is_finite() || *v < 0.0 || *v > 1.0 + 1e-3)
        {
            return Err(PhaseError::Value { index: i as u64 });
        }
        if let Some(i) = intensity.iter().position(|v| !v.is_finite() || *v < 0.0) {
            return Err(PhaseError::Value { index: i as u64 });
        }
        Ok(Self {
            incoming,
            outgoing,
            bands,
            scattered,
            intensity,
        })
    }

    /// The grid of incoming directions.
    pub fn incoming(&self) -> DirectionGrid {
        self.incoming
    }

    /// The grid of outgoing directions.
    pub fn outgoing(&self) -> DirectionGrid {
        self.outgoing
    }

    /// Bands.
    pub fn bands(&self) -> usize {
        self.bands
    }

    /// The scattered fraction of band `band` for a sun towards `source`, interpolated.
    pub fn scattered(&self, source: Vec3, band: usize) -> f32 {
        self.incoming
            .weights(source)
            .iter()
            .map(|&(c, w)| w * self.scattered[c as usize * self.bands + band])
            .sum()
    }

    /// The intensity (m^2/sr: W/sr per W/m^2) of band `band` towards `observer` for a sun
    /// towards `source`, interpolated bilinearly in both directions.
    pub fn intensity(&self, source: Vec3, observer: Vec3, band: usize) -> f32 {
        let out = self.outgoing.weights(observer);
        let cells = self.outgoing.cells() as usize;
        let mut sum = 0.0;
        for &(ci, wi) in &self.incoming.weights(source) {
            for &(co, wo) in &out {
                sum += wi * wo * self.intensity[(ci as usize * cells + co as usize) * self.bands + band];
            }
        }
        sum
    }

    /// The table's scattered fraction at incoming cell `cell` (no interpolation).
    pub fn scattered_at(&self, cell: u32, band: usize) -> f32 {
        self.scattered[cell as usize * self.bands + band]
    }

    /// The table's intensity at incoming cell `cell_in`, outgoing cell `cell_out`.
    pub fn intensity_at(&self, cell_in: u32, cell_out: u32, band: usize) -> f32 {
        self.intensity
            [(cell_in as usize * self.outgoing.cells() as usize + cell_out as usize) * self.bands + band]
    }
}
