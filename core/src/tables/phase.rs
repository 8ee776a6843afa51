//! An original's phase table (paper section 3.1, DESIGN.md "Directional table"): what its
//! contents scatter out of the box for the light they intercept, as functions of the
//! incoming direction (the albedo: the uniform form, the paper's) and of the incoming and
//! outgoing directions (the response: the bidirectional form).
//!
//! Both are per unit of intercepted power (and the response per unit of the cross-section
//! seen), so that they are smooth in the directions: how much a sun's light the contents intercept changes sharply (a maize plant's
//! leaves stand in one plane, and a sun in that plane meets their edges), and that is the
//! `tau` table's business (the cross-section `(1 - tau) A`), measured by rays alone on a grid
//! as fine as it needs. Directions are unit vectors in the original's frame: incoming ones
//! point towards the source (as a sun's `towards`), outgoing ones towards the observer.

use super::grid::DirectionGrid;
use crate::limits::MAX_BANDS;
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
    /// `[cell_in * bands + band]`: of the power the contents intercept from a sun in that
    /// cell, the fraction that leaves the box scattered, 0..=1.
    albedo: &'a [f32],
    /// `[(cell_in * out_cells + cell_out) * bands + band]`: the radiant intensity (W/sr)
    /// that leaves the box towards the outgoing cell per watt intercepted from a sun in the
    /// incoming cell and per m^2 of the contents' cross-section seen from the outgoing cell:
    /// the mean radiance of what an observer there sees, per watt intercepted
    /// (1/(m^2 sr)). Per unit cross-section for the same reason as the albedo: how much of
    /// the contents an observer sees changes sharply with the direction.
    response: &'a [f32],
}

/// Why storage is not a table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TableError {
    /// No band, or more than the core holds.
    Bands,
    /// A slice's length is not what the grids and bands make.
    Length {
        /// Values expected.
        expected: u64,
        /// Values given.
        given: u64,
    },
    /// A value is not finite or is out of its range (a fraction outside 0..=1 by more than
    /// rounding, a negative intensity).
    Value {
        /// Index of the first bad value in its slice.
        index: u64,
    },
    /// The box is not finite or its corners are not ordered.
    Box,
}

/// Checks `values` against its expected length and its range `[0, max]`.
pub(super) fn check_values(values: &[f32], expected: u64, max: f32) -> Result<(), TableError> {
    if values.len() as u64 != expected {
        return Err(TableError::Length {
            expected,
            given: values.len() as u64,
        });
    }
    match values
        .iter()
        .position(|v| !v.is_finite() || *v < 0.0 || *v > max)
    {
        Some(i) => Err(TableError::Value { index: i as u64 }),
        None => Ok(()),
    }
}

impl<'a> PhaseTable<'a> {
    /// Checks the lengths and values of `albedo` and `response` against the grids.
    pub fn new(
        incoming: DirectionGrid,
        outgoing: DirectionGrid,
        bands: usize,
        albedo: &'a [f32],
        response: &'a [f32],
    ) -> Result<Self, TableError> {
        if bands == 0 || bands > MAX_BANDS {
            return Err(TableError::Bands);
        }
        let n_in = incoming.cells() as u64 * bands as u64;
        check_values(albedo, n_in, 1.0 + 1e-3)?;
        check_values(response, n_in * outgoing.cells() as u64, f32::MAX)?;
        Ok(Self {
            incoming,
            outgoing,
            bands,
            albedo,
            response,
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

    /// The albedo of band `band` for a sun towards `source`, interpolated.
    pub fn albedo(&self, source: Vec3, band: usize) -> f32 {
        self.incoming
            .weights(source)
            .iter()
            .map(|&(c, w)| w * self.albedo_at(c, band))
            .sum()
    }

    /// The response (1/(m^2 sr)) of band `band` towards `observer` for a sun towards `source`,
    /// interpolated linearly in both directions.
    pub fn response(&self, source: Vec3, observer: Vec3, band: usize) -> f32 {
        let out = self.outgoing.weights(observer);
        let mut sum = 0.0;
        for &(ci, wi) in &self.incoming.weights(source) {
            if wi == 0.0 {
                continue;
            }
            for &(co, wo) in &out {
                sum += wi * wo * self.response_at(ci, co, band);
            }
        }
        sum
    }

    /// The albedo at incoming cell `cell` (no interpolation).
    pub fn albedo_at(&self, cell: u32, band: usize) -> f32 {
        self.albedo[cell as usize * self.bands + band]
    }

    /// The response at incoming cell `cell_in`, outgoing cell `cell_out`.
    pub fn response_at(&self, cell_in: u32, cell_out: u32, band: usize) -> f32 {
        let cells = self.outgoing.cells() as usize;
        self.response[(cell_in as usize * cells + cell_out as usize) * self.bands + band]
    }
}
