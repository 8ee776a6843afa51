//! Closed instances as a level loads them (see `load`): one leaf per instance below the
//! level's root, its transform, world box and reference area, and its original's tables
//! read from the image into the workspace and checked the first time they are needed.

use super::error::HrError;
use super::ids::{Elem, Kind};
use super::pool::{read, write};
use super::records::*;
use super::settings::{Inline, Instancing};
use super::state::State;
use crate::NodeId;
use crate::geometry::{Aabb, Similarity};
use crate::image::{SceneSource, SceneView};
use crate::limits::NONE;

/// True when node `rec`, a child of a loaded node, is an instance that stays closed: any
/// instance under [`Instancing::Top`], unless `inline` expands its original in place.
pub(super) fn closes<S: SceneSource>(
    view: &SceneView<S>,
    s: &State,
    inline: Inline<'_>,
    rec: &crate::image::NodeRecord,
) -> Result<bool, HrError> {
    Ok(match rec.instance() {
        Some(id) if s.instancing == Instancing::Top => !inline.expands(view.instance(id)?.original),
        _ => false,
    })
}

/// Makes the leaf of closed instance node `node` under transform `t` (its parent's), its
/// original's tables read into the workspace and checked the first time they are needed.
pub(super) fn add_instance<S: SceneSource>(
    view: &SceneView<S>,
    s: &mut State,
    ws: &mut [u8],
    node: u32,
    pass: u32,
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
    // All the light and what each kind of beam handed it (see `State::received_at`).
    let received = received_floats(&record);
    if s.received_floats + received > lay.n_received_floats() {
        return Err(HrError::SceneTooLarge);
    }
    let mut bbox = place.aabb(&Aabb::new(record.lo.into(), record.hi.into()));
    // Its own polygons, when it blocks with them: its box then holds them too (an
    // approximate instance's contents need not lie in its original's box).
    let own = if s.own_blocking {
        super::original_geometry::own_blocking_polygons(view, &rec, s.settings.blocking_polygons)?
    } else {
        None
    };
    let (own_polygons, own_at) = match own {
        Some(n) => {
            let at = lay.blocking + s.blocking_bytes;
            let bytes = super::original_geometry::bytes_needed(n);
            if at + bytes > lay.blocking_end {
                return Err(HrError::SceneTooLarge);
            }
            super::original_geometry::load_from(view, &mut ws[at..at + bytes], node, n)?;
            let own_at = u32::try_from(s.blocking_bytes).map_err(|_| HrError::SceneTooLarge)?;
            s.blocking_bytes += bytes;
            let held = t.aabb(&Aabb::new(rec.bbox_min.into(), rec.bbox_max.into()));
            bbox = Aabb::new(bbox.min.min(held.min), bbox.max.max(held.max));
            (n, own_at)
        }
        None => (0, 0),
    };
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
        pass,
        area_ref: 0.0,
        own_polygons,
        own_at,
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
    let stored = view
        .table_of(crate::OriginalId(original))?
        .ok_or(HrError::NoTables { original })?;
    let record = as_loaded(&stored);
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
    read_visible(
        view,
        &stored,
        &record,
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

/// Largest side of the grid of the scatterers' visible fractions kept in the workspace:
/// finer grids (the bake goes to 128 where a plant's first scattering alone needs it) are
/// averaged down 2 x 2 cells at a time as they are read. At 32 a maize plant's fractions take
/// 0.25 MB instead of 4, the fixed part of a canopy's workspace whatever its size; on a dense
/// 320-plant block every organ class's absorbed power moved by at most 0.14% against hr
/// (BENCHMARKS, "Memory of the top level").
pub(crate) const LOADED_SINGLE_SIDE: u32 = 32;

/// `record` as the workspace holds it: its visible fractions' grid at most
/// [`LOADED_SINGLE_SIDE`] (halved while it is finer and even).
pub(crate) fn as_loaded(record: &crate::image::TableRecord) -> crate::image::TableRecord {
    let mut r = *record;
    while r.single_side > LOADED_SINGLE_SIDE && r.single_side.is_multiple_of(2) {
        r.single_side /= 2;
    }
    r
}

/// Reads `stored`'s visible fractions into `out` on `loaded`'s grid: each coarse cell the
/// rounded mean of the fine cells it covers (the grids nest: a regular grid on the square,
/// see `tables::grid`).
fn read_visible<S: SceneSource>(
    view: &SceneView<S>,
    stored: &crate::image::TableRecord,
    loaded: &crate::image::TableRecord,
    out: &mut [u8],
) -> Result<(), HrError> {
    if stored.single_side == loaded.single_side {
        view.table_visibility(stored.first_visible, out)?;
        return Ok(());
    }
    let polygons = stored.scatterers as usize;
    let (fine, coarse) = (stored.single_side as usize, loaded.single_side as usize);
    let f = fine / coarse;
    const RUN: usize = 256;
    let (mut buf, mut acc) = ([0u8; RUN], [0u32; RUN]);
    let m = (f * f) as u32;
    for j in 0..coarse {
        for i in 0..coarse {
            for p0 in (0..polygons).step_by(RUN) {
                let n = (polygons - p0).min(RUN);
                acc[..n].fill(0);
                for dj in 0..f {
                    for di in 0..f {
                        let cell = (j * f + dj) * fine + i * f + di;
                        let at = stored.first_visible + (cell * polygons + p0) as u64;
                        view.table_visibility(at, &mut buf[..n])?;
                        for (a, &b) in acc[..n].iter_mut().zip(&buf[..n]) {
                            *a += u32::from(b);
                        }
                    }
                }
                let to = (j * coarse + i) * polygons + p0;
                for (o, &a) in out[to..to + n].iter_mut().zip(&acc[..n]) {
                    *o = ((a + m / 2) / m) as u8;
                }
            }
        }
    }
    Ok(())
}
