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

/// Of the power scattered from a sun, the least share that light falling on one side of the
/// polygons must scatter for that side to count as lit (its response is defined there).
pub const LIT_SHARE: f32 = 0.01;

/// True when the power `by_side` scattered from one side of the polygons is a share of the
/// `total` that makes that side lit (see [`LIT_SHARE`]).
pub fn side_lit(by_side: f32, total: f32) -> bool {
    by_side > 0.0 && by_side >= LIT_SHARE * total
}

/// A phase table over caller storage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhaseTable<'a> {
    /// Grid of incoming directions.
    incoming: DirectionGrid,
    /// Grid of outgoing directions (bidirectional form).
    outgoing: DirectionGrid,
    /// Bands, 1..=MAX_BANDS.
    bands: usize,
    /// `[(cell_in * 2 + side) * bands + band]`: of the power scattered out for a sun in the
    /// incoming cell, the share that fell on side `side` of the polygons first (0..=1); the
    /// side's response is defined where this is at least [`LIT_SHARE`].
    shares: &'a [f32],
    /// `[((cell_in * out_cells + cell_out) * 2 + side) * bands + band]`: the radiant
    /// intensity (W/sr) that leaves the box towards the outgoing cell per watt scattered out
    /// of it after a sun in the incoming cell lit side `side` of the polygons (0 fronts,
    /// 1 backs), and per m^2 of the contents' cross-section seen from the outgoing cell: the
    /// mean radiance of what an observer there sees, per watt scattered (1/(m^2 sr)); 0
    /// where that side is not lit (see `shares`). Over the sphere, response x cross-section integrates to
    /// about 1. Apart by side lit because the two sides of a leaf reflect differently and
    /// glow towards opposite observers: a sun that crosses a leaf's plane moves its light
    /// from one to the other.
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
    /// A grid's side is 0 or above [`super::grid::MAX_SIDE`].
    Grid,
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
    /// Checks the lengths and values of `shares` and `response` against the grids.
    pub fn new(
        incoming: DirectionGrid,
        outgoing: DirectionGrid,
        bands: usize,
        shares: &'a [f32],
        response: &'a [f32],
    ) -> Result<Self, TableError> {
        if bands == 0 || bands > MAX_BANDS {
            return Err(TableError::Bands);
        }
        let n_in = incoming.cells() as u64 * 2 * bands as u64;
        check_values(shares, n_in, 1.0 + 1e-3)?;
        check_values(response, n_in * outgoing.cells() as u64, f32::MAX)?;
        Ok(Self {
            incoming,
            outgoing,
            bands,
            shares,
            response,
        })
    }

    /// A table over storage checked before (see `DirectionalTables::trusted`).
    pub(crate) fn trusted(
        incoming: DirectionGrid,
        outgoing: DirectionGrid,
        bands: usize,
        shares: &'a [f32],
        response: &'a [f32],
    ) -> Self {
        Self {
            incoming,
            outgoing,
            bands,
            shares,
            response,
        }
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

    /// The response (1/(m^2 sr)) of band `band` towards `observer` for a sun towards
    /// `source` that lights side `side`, interpolated in both directions; over the incoming
    /// cells around `source` where that side is lit only (weights renormalised), 0 when
    /// there is none.
    pub fn response(&self, source: Vec3, observer: Vec3, side: usize, band: usize) -> f32 {
        let out = self.outgoing.weights(observer);
        let (mut sum, mut weight) = (0.0, 0.0);
        for &(ci, wi) in &self.incoming.weights(source) {
            if wi == 0.0 || self.share_at(ci, side, band) < LIT_SHARE {
                continue;
            }
            weight += wi;
            for &(co, wo) in &out {
                sum += wi * wo * self.response_at(ci, co, side, band);
            }
        }
        if weight > 0.0 { sum / weight } else { 0.0 }
    }

    /// At incoming cell `cell_in`, the share of the scattered power of band `band` that fell
    /// on side `side` first.
    pub fn share_at(&self, cell_in: u32, side: usize, band: usize) -> f32 {
        self.shares[(cell_in as usize * 2 + side) * self.bands + band]
    }

    /// The response at incoming cell `cell_in`, outgoing cell `cell_out`, side lit `side`.
    pub fn response_at(&self, cell_in: u32, cell_out: u32, side: usize, band: usize) -> f32 {
        let cells = self.outgoing.cells() as usize;
        self.response
            [((cell_in as usize * cells + cell_out as usize) * 2 + side) * self.bands + band]
    }
}
