//! The closed instances' side of the state (hierarchical instantiation): their leaves, their
//! originals' table slots and blocking polygons, their tables placed, and the light each
//! received (all of it as floats, the direct light of suns and sky as half floats).

use super::State;
use crate::hr::pool::{floats, floats_mut, read, write};
use crate::hr::records::{InstanceLeaf, TableSlot};

/// Floats of a closed instance's received light, all its parts (see
/// [`State::received_at`], [`State::direct_at`]), for tables of `bands` bands, `scatterers`
/// polygons kept apart and `incoming_cells` incoming cells: all the light as floats, the
/// direct light as half floats and their scale.
pub(crate) const fn received_parts_floats(
    bands: usize,
    scatterers: usize,
    incoming_cells: usize,
) -> usize {
    let n = crate::tables::closed::received_floats(bands, scatterers, incoming_cells);
    n + n.div_ceil(2) + 1
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

    /// Where closed instance `i`'s direct light of suns and sky lies, fixed once lit (see
    /// [`Self::note_direct`]): the byte offset of its half floats (as many as the light's
    /// floats, each over the scale) and that of its scale (a float, the largest value).
    /// Half floats keep 0.05% of each value; the whole light starts again from them at
    /// every gather.
    pub(crate) fn direct_at(&self, ws: &[u8], i: u32) -> (usize, usize, usize) {
        let (at, n) = self.received_at(ws, i);
        let halves = at + 4 * n;
        (halves, n, halves + 4 * n.div_ceil(2))
    }

    /// Notes closed instance `i`'s light as its direct light (see [`Self::direct_at`]):
    /// called once it was lit by the suns and sky alone.
    pub(crate) fn note_direct(&self, ws: &mut [u8], i: u32) {
        let (at, n) = self.received_at(ws, i);
        let (halves, _, scale_at) = self.direct_at(ws, i);
        let scale = floats(ws, at, n)
            .iter()
            .filter(|v| v.is_finite())
            .fold(0.0f32, |m, v| m.max(v.abs()));
        write(ws, scale_at, &scale);
        for k in 0..n {
            let v: f32 = read(ws, at + 4 * k);
            let h = if scale > 0.0 { v / scale } else { 0.0 };
            let bits = half::f16::from_f32(h).to_bits().to_le_bytes();
            ws[halves + 2 * k..halves + 2 * k + 2].copy_from_slice(&bits);
        }
    }

    /// Value `k` of closed instance `i`'s direct light (in the order of its whole light).
    pub(crate) fn direct_value(&self, ws: &[u8], i: u32, k: usize) -> f32 {
        let (halves, n, scale_at) = self.direct_at(ws, i);
        if k >= n {
            return 0.0;
        }
        let scale: f32 = read(ws, scale_at);
        let bits = u16::from_le_bytes([ws[halves + 2 * k], ws[halves + 2 * k + 1]]);
        scale * half::f16::from_bits(bits).to_f32()
    }

    /// Starts closed instance `i`'s whole light again from its direct light.
    pub(crate) fn restart_from_direct(&self, ws: &mut [u8], i: u32) {
        let (at, n) = self.received_at(ws, i);
        for k in 0..n {
            let v = self.direct_value(ws, i, k);
            write(ws, at + 4 * k, &v);
        }
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
        let leaf = self.instance(ws, i);
        let (at, n) = self.received_at(ws, i);
        let split = self.lay.slots;
        let (head, tail) = ws.split_at_mut(split);
        let placed = self.placed_in(&leaf, tail, split);
        let values = floats_mut(head, at, n);
        let mut received = crate::tables::closed::Received::over(&placed, values).ok()?;
        Some(f(&placed, &mut received))
    }
}
