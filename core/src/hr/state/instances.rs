//! The closed instances' side of the state (hierarchical instantiation): their leaves, their
//! originals' table slots and blocking polygons, their tables placed, and the light each
//! received (all of it as floats, kept from one gather to the next, and what each kind of
//! beam handed it so far, so that a gather adds only the change).

use super::State;
use crate::hr::exchange::CELLS;
use crate::hr::pool::{floats, floats_mut, read, write};
use crate::hr::records::{InstanceLeaf, TableSlot};

/// Floats of a closed instance's received light, all its parts (see
/// [`State::received_at`], [`Handed`]), for tables of `bands` bands, `scatterers` polygons
/// kept apart and `incoming_cells` incoming cells: all the light, then the power its direct
/// light brought (intercepted and scattered, per band) and per part of [`Handed`] and
/// direction cell of the exchange's grid what it holds, per band.
pub(crate) const fn received_parts_floats(
    bands: usize,
    scatterers: usize,
    incoming_cells: usize,
) -> usize {
    let n = crate::tables::closed::received_floats(bands, scatterers, incoming_cells);
    n + 2 * bands + 3 * CELLS * bands
}

/// What a closed instance's light was handed so far by each kind of beam, per direction
/// cell of the exchange's grid and band: a gather adds to its light only the change since
/// (`Received::change`), so that no copy of its direct light is kept to start again from
/// (half its light's storage: 7.5 MB of the paper stand's top level).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Handed {
    /// Its links' light, binned by direction towards the emitter (W/m^2 on a plane
    /// facing it).
    Links = 0,
    /// The exchange's beams from the other closed instances (W, as the exchange's gather
    /// hands them: see `exchange::receive`).
    Exchange = 1,
    /// As an emitter of the exchange, its escaping power per cell last landed on its
    /// receivers' polygons (W: see `exchange::land`).
    Sent = 2,
}

impl State {
    pub(crate) fn instance(&self, ws: &[u8], i: u32) -> InstanceLeaf {
        read(
            ws,
            self.lay.instances + i as usize * self.lay.strides.instance,
        )
    }

    pub(crate) fn set_instance(&self, ws: &mut [u8], i: u32, c: &InstanceLeaf) {
        write(
            ws,
            self.lay.instances + i as usize * self.lay.strides.instance,
            c,
        )
    }

    /// The table slot `k` (see [`TableSlot`]).
    pub(crate) fn slot(&self, ws: &[u8], k: u32) -> TableSlot {
        read(
            ws,
            self.lay.slots + k as usize * core::mem::size_of::<TableSlot>(),
        )
    }

    /// Closed instance `i`'s original's own polygons, when it blocks with them (see
    /// `original_geometry`).
    pub(crate) fn original_geometry<'a>(
        &self,
        ws: &'a [u8],
        slot: u32,
    ) -> Option<crate::hr::original_geometry::OriginalGeometry<'a>> {
        let s = self.slot(ws, slot);
        if s.blocking_polygons == 0 {
            return None;
        }
        crate::hr::original_geometry::OriginalGeometry::over(
            ws.get(s.blocking as usize..self.lay.blocking_end)?,
            s.blocking_polygons,
        )
    }

    /// Closed instance `i`'s own polygons, when it blocks with them (an approximate
    /// instance, see `original_geometry::own_blocking_polygons`), in its contents' frame.
    pub(crate) fn own_geometry<'a>(
        &self,
        ws: &'a [u8],
        i: u32,
    ) -> Option<crate::hr::original_geometry::OriginalGeometry<'a>> {
        let leaf = self.instance(ws, i);
        if leaf.own_polygons == 0 {
            return None;
        }
        crate::hr::original_geometry::OriginalGeometry::over(
            ws.get(self.lay.blocking + leaf.own_at as usize..self.lay.blocking_end)?,
            leaf.own_polygons,
        )
    }

    /// The polygons closed instance `i` blocks rays with, if any: its own (see
    /// [`Self::own_geometry`]), else its original's placed where it stands (see
    /// [`Self::original_geometry`]).
    pub(crate) fn blocking_geometry<'a>(
        &self,
        ws: &'a [u8],
        i: u32,
    ) -> Option<crate::hr::original_geometry::OriginalGeometry<'a>> {
        self.own_geometry(ws, i)
            .or_else(|| self.original_geometry(ws, self.instance(ws, i).slot))
    }

    /// Closed instance `i`'s original's tables, placed by its transform.
    pub(crate) fn placed<'a>(&self, ws: &'a [u8], i: u32) -> crate::tables::closed::Placed<'a> {
        let leaf = self.instance(ws, i);
        self.placed_in(&leaf, &ws[self.lay.slots..], self.lay.slots)
    }

    /// The tables of `leaf` placed, read from `part`, the workspace from byte `base` on
    /// (the table slots and values lie there).
    fn placed_in<'a>(
        &self,
        leaf: &InstanceLeaf,
        part: &'a [u8],
        base: usize,
    ) -> crate::tables::closed::Placed<'a> {
        let slot: TableSlot = read(
            part,
            self.lay.slots - base + leaf.slot as usize * core::mem::size_of::<TableSlot>(),
        );
        let r = &slot.record;
        let values = floats(part, slot.values as usize - base, r.values() as usize);
        let v0 = slot.visible as usize - base;
        let visible = &part[v0..v0 + r.visible_bytes() as usize];
        let tables = crate::tables::directional::DirectionalTables::trusted(r, values, visible);
        let place = leaf.place();
        crate::tables::closed::Placed::new(tables, place)
    }

    /// Where closed instance `i`'s light lies, all it received, direct and through links
    /// (laid out as [`crate::tables::closed::Received`]): its byte offset and length in
    /// floats.
    pub(crate) fn received_at(&self, ws: &[u8], i: u32) -> (usize, usize) {
        let leaf = self.instance(ws, i);
        let n = self.placed(ws, i).received_len();
        (self.lay.received + 4 * leaf.received as usize, n)
    }

    /// The power closed instance `i`'s direct light brought it (see [`Self::note_direct`]):
    /// value `k` of its light's first `2 * bands` (intercepted per band, then scattered).
    pub(crate) fn direct_value(&self, ws: &[u8], i: u32, k: usize) -> f32 {
        let (at, n) = self.received_at(ws, i);
        if k >= 2 * self.bands {
            return 0.0;
        }
        read(ws, at + 4 * (n + k))
    }

    /// Where closed instance `i`'s light handed by `part` lies: the byte offset of its
    /// `CELLS * bands` floats (cell by cell, band by band).
    fn handed_at(&self, ws: &[u8], i: u32, part: Handed) -> usize {
        let (at, n) = self.received_at(ws, i);
        at + 4 * (n + 2 * self.bands + part as usize * CELLS * self.bands)
    }

    /// What `part` handed closed instance `i` so far (see [`Handed`]).
    pub(crate) fn handed<'a>(&self, ws: &'a [u8], i: u32, part: Handed) -> &'a [f32] {
        floats(ws, self.handed_at(ws, i, part), CELLS * self.bands)
    }

    /// [`Self::handed`], to change.
    pub(crate) fn handed_mut<'a>(&self, ws: &'a mut [u8], i: u32, part: Handed) -> &'a mut [f32] {
        let at = self.handed_at(ws, i, part);
        floats_mut(ws, at, CELLS * self.bands)
    }

    /// Notes closed instance `i`'s light, lit by the suns, sky and emitting polygons alone,
    /// as its direct light: the power it brought is kept, and nothing was handed by links or
    /// the exchange yet. Called once it was lit.
    pub(crate) fn note_direct(&self, ws: &mut [u8], i: u32) {
        let (at, n) = self.received_at(ws, i);
        let nb = self.bands;
        for k in 0..2 * nb {
            let v: f32 = read(ws, at + 4 * k);
            write(ws, at + 4 * (n + k), &v);
        }
        let handed = self.handed_at(ws, i, Handed::Links);
        ws[handed..handed + 4 * 3 * CELLS * nb].fill(0);
    }

    /// All the light closed instance `i` received (see `received_at`).
    pub(crate) fn received<'a>(&self, ws: &'a [u8], i: u32) -> &'a [f32] {
        let (at, n) = self.received_at(ws, i);
        floats(ws, at, n)
    }

    /// Calls `f` with closed instance `i`'s tables placed and a mutable view of its whole
    /// light (see `received_at`).
    pub(crate) fn with_received<R>(
        &self,
        ws: &mut [u8],
        i: u32,
        f: impl FnOnce(
            &crate::tables::closed::Placed<'_>,
            &mut crate::tables::closed::Received<&mut [f32]>,
        ) -> R,
    ) -> Option<R> {
        self.with_handed(ws, i, Handed::Links, |placed, received, _| {
            f(placed, received)
        })
    }

    /// [`Self::with_received`], with a mutable view of what `part` handed it too (see
    /// [`Self::handed`]).
    pub(crate) fn with_handed<R>(
        &self,
        ws: &mut [u8],
        i: u32,
        part: Handed,
        f: impl FnOnce(
            &crate::tables::closed::Placed<'_>,
            &mut crate::tables::closed::Received<&mut [f32]>,
            &mut [f32],
        ) -> R,
    ) -> Option<R> {
        let leaf = self.instance(ws, i);
        let (at, n) = self.received_at(ws, i);
        let split = self.lay.slots;
        let (head, tail) = ws.split_at_mut(split);
        let placed = self.placed_in(&leaf, tail, split);
        let from = 2 * self.bands + part as usize * CELLS * self.bands;
        let block = floats_mut(head, at, n + from + CELLS * self.bands);
        let (values, rest) = block.split_at_mut(n);
        let mut received = crate::tables::closed::Received::over(&placed, values).ok()?;
        Some(f(&placed, &mut received, &mut rest[from..]))
    }
}
