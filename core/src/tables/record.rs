//! An original's tables as a scene image stores them: a [`TableRecord`], its values in the
//! record's order and its scatterers' visible fractions, read into caller storage (the
//! workspace of a solve with closed instances) and checked into [`DirectionalTables`].

use super::directional::DirectionalTables;
use super::grid::DirectionGrid;
use super::phase::{PhaseTable, TableError};
use super::single::SingleScatter;
use crate::image::TableRecord;
use glam::Vec3;

impl<'a> DirectionalTables<'a> {
    /// The tables of `record` over `values` (the record's [`TableRecord::values`] floats, in
    /// the order of [`TableRecord::lengths`]) and `visible` (its
    /// [`TableRecord::visible_bytes`]); every length, grid, range and the box checked.
    pub fn from_record(
        record: &TableRecord,
        values: &'a [f32],
        visible: &'a [u8],
    ) -> Result<Self, TableError> {
        let lengths = record.lengths();
        let total: u64 = lengths.iter().sum();
        if values.len() as u64 != total {
            return Err(TableError::Length {
                expected: total,
                given: values.len() as u64,
            });
        }
        if visible.len() as u64 != record.visible_bytes() {
            return Err(TableError::Length {
                expected: record.visible_bytes(),
                given: visible.len() as u64,
            });
        }
        let grid = |side: u32| DirectionGrid::new(side).map_err(|_| TableError::Grid);
        let mut rest = values;
        let mut take = |n: u64| {
            let (head, tail) = rest.split_at(n as usize);
            rest = tail;
            head
        };
        let [tau, albedo, shares, response, shape] = lengths.map(&mut take);
        let bands = record.bands as usize;
        let phase = PhaseTable::new(
            grid(record.incoming_side)?,
            grid(record.outgoing_side)?,
            bands,
            shares,
            response,
        )?;
        let tables = DirectionalTables::new(
            Vec3::from(record.lo),
            Vec3::from(record.hi),
            grid(record.tau_side)?,
            tau,
            albedo,
            phase,
        )?;
        if record.scatterers == 0 {
            return Ok(tables);
        }
        let single = SingleScatter::new(
            grid(record.single_side)?,
            bands,
            record.scatterers as usize,
            shape,
            visible,
        )?;
        tables.with_single(single)
    }
}
