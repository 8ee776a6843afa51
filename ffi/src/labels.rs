//! What a caller needs besides the numbers: names of materials, the results table's header
//! as `hirad solve --results` writes it, the expanded scene's polygons in world space (for
//! a caller's ray caster), and floats written the way hirad's tables write them.

use crate::scene::{HiradScene, on_scene};
use crate::status::{Failure, HiradStatus, aligned};
use hirad::output::{RowLabels, TableLayout, columns::band_labels};
use std::ffi::{CString, c_char};

/// An expanded polygon in world space (m), corners counter-clockwise seen from the front.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HiradWorldPolygon {
    /// Corners (the first `corners` of them used).
    pub corner: [[f32; 3]; 4],
    /// 3 or 4.
    pub corners: u32,
}

/// Keeps `text` with the handle and returns its pointer.
fn keep(s: &mut HiradScene, text: &str) -> *const c_char {
    s.strings
        .push(CString::new(text.replace('\0', " ")).unwrap_or_default());
    s.strings.last().map_or(std::ptr::null(), |c| c.as_ptr())
}

/// The name of material `index` at `*name` (NUL-terminated, valid until the handle is
/// freed).
///
/// # Safety
/// `scene` null or a live handle; `name` null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hirad_scene_material_name(
    scene: *mut HiradScene,
    index: u32,
    name: *mut *const c_char,
) -> HiradStatus {
    // SAFETY: the caller's promise, passed on.
    unsafe {
        on_scene(scene, |s| {
            if name.is_null() {
                return Err(Failure::new(HiradStatus::NullArgument, "name is null"));
            }
            let model = s.model()?;
            let Some(m) = model.materials.get(index as usize) else {
                return Err(Failure::new(
                    HiradStatus::InvalidSettings,
                    format!(
                        "material {index} does not exist: the scene has {}",
                        model.materials.len()
                    ),
                ));
            };
            let p = keep(s, &m.name);
            name.write(p);
            Ok(())
        })
    }
}

/// The header line (without a line break) of the results table `hirad solve --results`
/// writes for this scene, at `*header` (valid until the handle is freed), and at
/// `*two_sided` 1 when the table has back-side columns (some polygon is two-sided; a
/// one-sided polygon leaves them empty). Columns: `id,area_m2`, `rad_BAND_W_m2` and
/// `irr_BAND_W_m2` per band (front), the same with `_back` when two-sided, then
/// `material,group`.
///
/// # Safety
/// `scene` null or a live handle; `header` and `two_sided` null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hirad_scene_results_header(
    scene: *mut HiradScene,
    header: *mut *const c_char,
    two_sided: *mut u32,
) -> HiradStatus {
    // SAFETY: the caller's promise, passed on.
    unsafe {
        on_scene(scene, |s| {
            if header.is_null() || two_sided.is_null() {
                return Err(Failure::new(
                    HiradStatus::NullArgument,
                    "header or two_sided is null",
                ));
            }
            if !aligned(two_sided) {
                return Err(Failure::new(
                    HiradStatus::Misaligned,
                    "two_sided is not aligned",
                ));
            }
            let model = s.model()?;
            let labels = RowLabels::shared(model.clone());
            let both = labels.uses_material(|m| model.materials[m].data.two_sided);
            let layout = TableLayout {
                labels: band_labels(model.bands as usize, &model.band_names),
                two_sided: both,
                faces: None,
                rows: Some(labels),
            };
            let p = keep(s, &layout.header());
            header.write(p);
            two_sided.write(u32::from(both));
            Ok(())
        })
    }
}

/// Writes every polygon of the expanded scene in world space, in global-id order, to
/// `out[0..]` (`capacity` entries; `HiradSceneInfo::expanded_polygons` are needed, else
/// `HIRAD_STATUS_SHORT_BUFFER` and nothing written): what a caller's ray caster intersects,
/// polygon id = index.
///
/// # Safety
/// `scene` null or a live handle; `out` null or `capacity` writable entries.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hirad_scene_world_polygons(
    scene: *mut HiradScene,
    out: *mut HiradWorldPolygon,
    capacity: u64,
) -> HiradStatus {
    // SAFETY: the caller's promise, passed on.
    unsafe {
        on_scene(scene, |s| {
            if out.is_null() {
                return Err(Failure::new(HiradStatus::NullArgument, "out is null"));
            }
            if !aligned(out) {
                return Err(Failure::new(HiradStatus::Misaligned, "out is not aligned"));
            }
            let n = s.open_view()?.info().expanded_polygons;
            if capacity < n {
                return Err(Failure::new(
                    HiradStatus::ShortBuffer,
                    format!("the scene has {n} polygons, room was given for {capacity}"),
                ));
            }
            let model = s.model()?;
            let polygons = hirad::solve::world_polygons(&model);
            for (i, p) in polygons.iter().enumerate() {
                let mut w = HiradWorldPolygon {
                    corners: p.len().min(4) as u32,
                    ..HiradWorldPolygon::default()
                };
                for (c, v) in w.corner.iter_mut().zip(p) {
                    *c = v.to_array();
                }
                out.add(i).write(w);
            }
            Ok(())
        })
    }
}

/// Writes `value` in the shortest decimal that reads back as the same float, as hirad's
/// results tables do (`0.1`, `1`, `0.0067882254`, `inf`, `NaN`), NUL-terminated, to
/// `buf[0..len]` when it fits; returns its length without the NUL either way (as
/// `snprintf` does), so a caller can tell it did not fit (at most 64 with any float).
///
/// # Safety
/// `buf` null or `len` writable bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hirad_format_float(value: f32, buf: *mut c_char, len: usize) -> usize {
    let text = std::panic::catch_unwind(|| value.to_string()).unwrap_or_default();
    if !buf.is_null() && len > text.len() {
        // SAFETY: `len` writable bytes at `buf` by the caller's promise; `text.len() + 1`
        // of them written.
        unsafe {
            std::ptr::copy_nonoverlapping(text.as_ptr(), buf.cast::<u8>(), text.len());
            buf.add(text.len()).write(0);
        }
    } else if !buf.is_null() && len > 0 {
        // SAFETY: at least one writable byte.
        unsafe { buf.write(0) };
    }
    text.len()
}
