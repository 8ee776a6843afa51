//! An original's phase table, bidirectional form (paper section 3.1, DESIGN.md
//! "Directional table"): how the light its contents scatter out of the box spreads over the
//! outgoing directions, as a function of the incoming and outgoing directions.
//!
//! It is per watt scattered and per unit of the cross-section seen, so that it is smooth in
//! the directions: how much of a sun's light the contents intercept and scatter changes
//! sharply (a maize plant's leaves stand in one plane, and a sun in that plane meets their
//! edges; their two sides reflect differently), and that is the business of the tables on
//! the `tau` grid (the cross-section `(1 - tau) A` and the albedo, see
//! [`super::directional`]), measured by rays alone on a grid as fine as it needs.
//! Directions are unit vectors in the original's frame: incoming ones point towards the
//! source (as a sun's `towards`), outgoing ones towards the observer.

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
    /// `[(cell_in * out_cells + cell_out) * bands + band]`: the radiant intensity (W/sr)
    /// that leaves the box towards the outgoing cell per watt scattered out of it from a sun
    /// in the incoming cell and per m^2 of the contents' cross-section seen from the
    /// outgoing cell: the mean radiance of what an observer there sees, per watt scattered
    /// (1/(m^2 sr)). Over the sphere, response x cross-section integrates to about 1.
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
    /// Checks the length and values of `response` against the grids.
    pub fn new(
        incoming: DirectionGrid,
        outgoing: DirectionGrid,
        bands: usize,
        response: &'a [f32],
    ) -> Result<Self, TableError> {
        if bands == 0 || bands > MAX_BANDS {
            return Err(TableError::Bands);
        }
        let n_in = incoming.cells() as u64 * bands as u64;
        check_values(response, n_in * outgoing.cells() as u64, f32::MAX)?;
        Ok(Self {
            incoming,
            outgoing,
            bands,
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

    /// The response at incoming cell `cell_in`, outgoing cell `cell_out`.
    pub fn response_at(&self, cell_in: u32, cell_out: u32, band: usize) -> f32 {
        let cells = self.outgoing.cells() as usize;
        self.response[(cell_in as usize * cells + cell_out as usize) * self.bands + band]
    }
}
