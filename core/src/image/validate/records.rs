//! Checks of the flat sections: strings and band names, the value pool, materials,
//! vertices, lights and cameras.

use super::{Window, err, offset_of};
use crate::geometry::{UNIT_TOLERANCE, camera_ok};
use crate::image::error::{ImageError, ImageErrorKind as K};
use crate::image::header::{Header, Section};
use crate::image::records::*;
use crate::image::source::SceneSource;
use crate::image::view::read_records;
use crate::limits::{MAX_BANDS, MAX_NAME_BYTES, NONE};
use crate::material::{MaterialData, TWO_SIDED};
use glam::Vec3;

pub(super) fn check_name(h: &Header, at: u64, name: u32) -> Result<(), ImageError> {
    if name != NONE && name as u64 >= h.section(Section::Strings).count {
        return Err(ImageError::at(at, K::NameIndex { index: name }));
    }
    Ok(())
}

pub(super) fn check_strings<S: SceneSource>(src: &S, h: &Header) -> Result<(), ImageError> {
    let bytes = h.section(Section::StringBytes);
    let mut w: Window<StringRef, 64> = Window::new(Section::Strings);
    let mut buf = [0u8; MAX_NAME_BYTES];
    for i in 0..h.section(Section::Strings).count {
        let r = w.get(src, h, i)?;
        let end = r.offset as u64 + r.len as u64;
        if end > bytes.count || r.len as usize > MAX_NAME_BYTES {
            return err(h, Section::Strings, i, K::StringRange { string: i as u32 });
        }
        let dst = &mut buf[..r.len as usize];
        let at = bytes.offset + r.offset as u64;
        src.read_at(at, dst)
            .map_err(|e| ImageError::at(at, K::Source(e)))?;
        if core::str::from_utf8(dst).is_err() {
            return Err(ImageError::at(at, K::StringUtf8 { string: i as u32 }));
        }
    }
    let names = h.section(Section::BandNames).count;
    if names != 0 && names != h.bands as u64 {
        return err(h, Section::BandNames, 0, K::BandNames { found: names });
    }
    let mut w: Window<u32, 8> = Window::new(Section::BandNames);
    for i in 0..names {
        let id = w.get(src, h, i)?;
        if id == NONE {
            return err(h, Section::BandNames, i, K::NameIndex { index: id });
        }
        check_name(h, offset_of(h, Section::BandNames, i), id)?;
    }
    Ok(())
}

pub(super) fn check_values<S: SceneSource>(src: &S, h: &Header) -> Result<(), ImageError> {
    let mut w: Window<f32, 256> = Window::new(Section::Values);
    for i in 0..h.section(Section::Values).count {
        if !w.get(src, h, i)?.is_finite() {
            return err(h, Section::Values, i, K::Value { index: i });
        }
    }
    Ok(())
}

pub(super) fn check_materials<S: SceneSource>(src: &S, h: &Header) -> Result<(), ImageError> {
    let mut w: Window<MaterialRecord, 32> = Window::new(Section::Materials);
    let pool = h.section(Section::Values).count;
    for i in 0..h.section(Section::Materials).count {
        let m = w.get(src, h, i)?;
        let at = offset_of(h, Section::Materials, i);
        let material = i as u32;
        check_name(h, at, m.name)?;
        if m.flags & !TWO_SIDED != 0 {
            return Err(ImageError::at(at + 4, K::MaterialFlags { material }));
        }
        if m.reserved != 0 {
            return Err(ImageError::at(at + 12, K::Reserved));
        }
        let two = m.flags & TWO_SIDED != 0;
        let n = MaterialData::value_count(h.bands, two) as u64;
        if m.values as u64 + n > pool {
            return Err(ImageError::at(at + 8, K::MaterialValues { material }));
        }
        let mut vals = [0.0f32; 5 * MAX_BANDS];
        read_records(
            src,
            h,
            Section::Values,
            m.values as u64,
            &mut vals[..n as usize],
        )?;
        let data = MaterialData::from_values(h.bands as u8, two, &vals[..n as usize]);
        if let Err(error) = data.check() {
            return Err(ImageError::at(at, K::Material { material, error }));
        }
    }
    Ok(())
}

pub(super) fn check_vertices<S: SceneSource>(src: &S, h: &Header) -> Result<(), ImageError> {
    let mut w: Window<[f32; 3], 256> = Window::new(Section::Vertices);
    for i in 0..h.section(Section::Vertices).count {
        if !Vec3::from(w.get(src, h, i)?).is_finite() {
            return err(h, Section::Vertices, i, K::Vertex { vertex: i });
        }
    }
    Ok(())
}

pub(super) fn check_lights<S: SceneSource>(
    src: &S,
    h: &Header,
    s: Section,
) -> Result<(), ImageError> {
    let mut w: Window<LightRecord, 32> = Window::new(s);
    let pool = h.section(Section::Values).count;
    for i in 0..h.section(s).count {
        let l = w.get(src, h, i)?;
        let light = i as u32;
        let d = Vec3::from(l.towards);
        if !d.is_finite() || (d.length_squared() - 1.0).abs() > UNIT_TOLERANCE {
            return err(h, s, i, K::LightDirection { light });
        }
        if l.values as u64 + h.bands as u64 > pool {
            return err(h, s, i, K::LightValues { light });
        }
        let mut irr = [0.0f32; MAX_BANDS];
        read_records(
            src,
            h,
            Section::Values,
            l.values as u64,
            &mut irr[..h.bands as usize],
        )?;
        if irr.iter().any(|&v| v < 0.0) {
            return err(h, s, i, K::LightValues { light });
        }
    }
    Ok(())
}

pub(super) fn check_cameras<S: SceneSource>(src: &S, h: &Header) -> Result<(), ImageError> {
    let mut w: Window<CameraRecord, 16> = Window::new(Section::Cameras);
    for i in 0..h.section(Section::Cameras).count {
        let c = w.get(src, h, i)?;
        let at = offset_of(h, Section::Cameras, i);
        check_name(h, at + 40, c.name)?;
        if c.reserved != 0 {
            return Err(ImageError::at(at + 44, K::Reserved));
        }
        if !camera_ok(c.position.into(), c.target.into(), c.up.into(), c.fovy_deg) {
            return Err(ImageError::at(at, K::Camera { camera: i as u32 }));
        }
    }
    Ok(())
}

/// The tables: each names an original (in increasing order), has the image's bands, grid
/// sides within the grid's range and a finite ordered box; their values follow each other
/// in the pool, which holds nothing else, and each value is within its range; so do their
/// scatterers' visible fractions in the visibility pool.
pub(super) fn check_tables<S: SceneSource>(src: &S, h: &Header) -> Result<u32, ImageError> {
    let originals = h.section(Section::Originals).count;
    let pool = h.section(Section::TableValues).count;
    let visibility = h.section(Section::TableVisibility).count;
    let mut w: Window<TableRecord, 16> = Window::new(Section::Tables);
    let mut v: Window<f32, 256> = Window::new(Section::TableValues);
    let (mut next, mut next_visible) = (0u64, 0u64);
    let mut previous: Option<u32> = None;
    let count = h.section(Section::Tables).count;
    for i in 0..count {
        let t = w.get(src, h, i)?;
        let table = i as u32;
        if t.original as u64 >= originals || previous.is_some_and(|p| t.original <= p) {
            return err(h, Section::Tables, i, K::TableOriginal { table });
        }
        previous = Some(t.original);
        let side_ok = |s: u32| (1..=crate::tables::grid::MAX_SIDE).contains(&s);
        let single_ok = if t.scatterers == 0 {
            t.single_side == 0
        } else {
            side_ok(t.single_side)
        };
        if t.bands != h.bands
            || !side_ok(t.tau_side)
            || !side_ok(t.incoming_side)
            || !side_ok(t.outgoing_side)
            || !single_ok
            || t.flags & !TABLE_MET != 0
            || t.reserved != 0
        {
            return err(h, Section::Tables, i, K::TableGrid { table });
        }
        let (lo, hi) = (Vec3::from(t.lo), Vec3::from(t.hi));
        let errors = [t.tau_error, t.scattered_error, t.intensity_error];
        if !lo.is_finite()
            || !hi.is_finite()
            || lo.cmpgt(hi).any()
            || errors.iter().any(|e| !e.is_finite() || *e < 0.0)
        {
            return err(h, Section::Tables, i, K::TableBox { table });
        }
        if t.first != next || t.values() > pool.saturating_sub(next) {
            return err(h, Section::Tables, i, K::TableRange { table });
        }
        if t.first_visible != next_visible
            || t.visible_bytes() > visibility.saturating_sub(next_visible)
        {
            return err(h, Section::Tables, i, K::TableRange { table });
        }
        let [tau, albedo, shares, response, _] = t.lengths();
        let stride = crate::tables::single::shape_stride(t.bands as usize) as u64;
        let mut normal = [0.0f32; 3];
        for k in 0..t.values() {
            let x = v.get(src, h, next + k)?;
            let ok = if k < tau {
                (0.0..=1.0).contains(&x)
            } else if k < tau + albedo + shares {
                (0.0..=1.0 + 1e-3).contains(&x)
            } else if k < tau + albedo + shares + response {
                x.is_finite() && x >= 0.0
            } else {
                // A scatterer's shape: a unit normal, an area, materials within 0..=1.
                let j = ((k - tau - albedo - shares - response) % stride) as usize;
                match j {
                    0..=2 => {
                        normal[j] = x;
                        x.is_finite()
                            && (j < 2 || {
                                let n = Vec3::from(normal);
                                (n.length() - 1.0).abs() <= 1e-3
                            })
                    }
                    3 => x.is_finite() && x >= 0.0,
                    _ => (0.0..=1.0).contains(&x),
                }
            };
            if !ok {
                return err(
                    h,
                    Section::TableValues,
                    next + k,
                    K::TableValue { table, index: k },
                );
            }
        }
        next += t.values();
        next_visible += t.visible_bytes();
    }
    let table = count as u32;
    if next != pool {
        return err(h, Section::TableValues, next, K::TableRange { table });
    }
    if next_visible != visibility {
        return err(
            h,
            Section::TableVisibility,
            next_visible,
            K::TableRange { table },
        );
    }
    Ok(count as u32)
}
