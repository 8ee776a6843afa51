//! Closed instances as a level loads them (see `load`): one leaf per instance below the
//! level's root, its transform, world box and reference area, and its original's tables
//! read from the image into the workspace and checked the first time they are needed.

use super::error::HrError;
use super::ids::{Elem, Kind};
use super::pool::{read, write};
use super::records::*;
use super::settings::Instancing;
use super::state::State;
use crate::NodeId;
use crate::geometry::{Aabb, Similarity};
use crate::image::{SceneSource, SceneView};
use crate::limits::NONE;

/// True when node `rec`, a child of a loaded node, is an instance that stays closed.
pub(super) fn closes(s: &State, rec: &crate::image::NodeRecord) -> bool {
    s.instancing == Instancing::Top && rec.instance().is_some()
}

/// Makes the leaf of closed instance node `node` under transform `t` (its parent's), its
/// original's tables read into the workspace and checked the first time they are needed.
pub(super) fn add_instance<S: SceneSource>(
    view: &SceneView<S>,
    s: &mut State,
    ws: &mut [u8],
    node: u32,
    t: &Similarity,
) -> Result<Elem, HrError> {
    let lay = s.lay;
    let rec = view.node(NodeId(node))?;
    let id = rec.instance().ok_or(HrError::SceneTooLarge)?;
    let inst = view.instance(id)?;
    let original = inst.original();
    let place = t.compose(&inst.transform());
    let slot = table_slot(view, s, ws, original.0)?;
    let record = s.slot(ws, slot).record;
    let i = s.instances;
    if i >= lay.n_instances {
        return Err(HrError::SceneTooLarge);
    }
    s.instances += 1;
    // The direct light, all the light, the exchange's (see `State::received_at`).
    let received = received_floats(&record);
    if s.received_floats + received > lay.n_received_floats() {
        return Err(HrError::SceneTooLarge);
    }
    let bbox = place.aabb(&Aabb::new(record.lo.into(), record.hi.into()));
    if !bbox.is_finite_nonempty() && bbox.min != bbox.max {
        return Err(HrError::BadGeometry {
            polygon: s.polygons as u64,
        });
    }
    let leaf = InstanceLeaf {
        rotation: place.rotation.to_array(),
        translation: place.translation.to_array(),
        scale: place.scale,
        bbox_min: bbox.min.to_array(),
        bbox_max: bbox.max.to_array(),
        parent: NONE,
        links: NONE,
        slot,
        received: s.received_floats as u32,
        node,
        area_ref: 0.0,
    };
    let at = lay.received + 4 * s.received_floats;
    ws[at..at + 4 * received].fill(0);
    s.received_floats += received;
    s.set_instance(ws, i, &leaf);
    // The mean cross-section over the sphere, times 4: the integral over pi.
    let integral = s.placed(ws, i).tables().shadow_integral();
    let mut leaf = leaf;
    leaf.area_ref = place.scale * place.scale * integral / core::f32::consts::PI;
    s.set_instance(ws, i, &leaf);
    Ok(Elem::new(Kind::Instance, i))
}

/// Floats of the light an instance of the original of `record` receives.
fn received_floats(record: &crate::image::TableRecord) -> usize {
    super::state::received_parts_floats(
        record.bands as usize,
        record.scatterers as usize,
        record.incoming_side as usize * record.incoming_side as usize,
    )
}

/// The table slot of `original`: read from the image into the workspace and checked the
/// first time.
fn table_slot<S: SceneSource>(
    view: &SceneView<S>,
    s: &mut State,
    ws: &mut [u8],
    original: u32,
) -> Result<u32, HrError> {
    let lay = s.lay;
    let map_at = lay.slot_map + 4 * original as usize;
    let known: u32 = read(ws, map_at);
    if known != NONE {
        return Ok(known);
    }
    let record = view
        .table_of(crate::OriginalId(original))?
        .ok_or(HrError::NoTables { original })?;
    let (floats, bytes) = (record.values() as usize, record.visible_bytes() as usize);
    let values_at = lay.table_values + 4 * s.table_floats;
    let visible_at = lay.table_visible + s.table_bytes;
    if s.slots >= lay.n_slots()
        || s.table_floats + floats > lay.n_table_floats()
        || s.table_bytes + bytes > lay.n_table_bytes()
    {
        return Err(HrError::SceneTooLarge);
    }
    {
        let values: &mut [f32] =
            bytemuck::cast_slice_mut(&mut ws[values_at..values_at + 4 * floats]);
        view.table_values(record.first, values)?;
    }
    view.table_visibility(
        record.first_visible,
        &mut ws[visible_at..visible_at + bytes],
    )?;
    {
        let values: &[f32] = bytemuck::cast_slice(&ws[values_at..values_at + 4 * floats]);
        let visible = &ws[visible_at..visible_at + bytes];
        crate::tables::directional::DirectionalTables::from_record(&record, values, visible)
            .map_err(|_| HrError::NoTables { original })?;
    }
    // Its own polygons, when its instances block with them.
    let blocking_at = lay.blocking + s.blocking_bytes;
    let blocking_polygons = match super::original_geometry::blocking_polygons(
        view,
        original,
        s.settings.blocking_polygons,
    )? {
        Some(n) => {
            let bytes = super::original_geometry::bytes_needed(n);
            if blocking_at + bytes > lay.blocking_end {
                return Err(HrError::SceneTooLarge);
            }
            let region = &mut ws[blocking_at..blocking_at + bytes];
            super::original_geometry::load(view, region, original, n)?;
            s.blocking_bytes += bytes;
            n
        }
        None => 0,
    };
    let slot = s.slots;
    s.slots += 1;
    s.table_floats += floats;
    s.table_bytes += bytes;
    write(
        ws,
        lay.slots + slot as usize * core::mem::size_of::<TableSlot>(),
        &TableSlot {
            record,
            values: values_at as u64,
            visible: visible_at as u64,
            blocking: blocking_at as u64,
            blocking_polygons,
            polygons_kept: u32::from(
                blocking_polygons > 0 && record.scatterers == blocking_polygons,
            ),
        },
    );
    write(ws, map_at, &slot);
    Ok(slot)
}
