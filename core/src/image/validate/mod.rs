//! Validation of an untrusted image, in one streaming pass with fixed stack buffers.
//!
//! Order: header and section layout; strings; values; materials; vertices; then every tree
//! (each original, then the scene) depth-first with an explicit stack bounded by
//! [`crate::limits::MAX_NODE_DEPTH`], checking polygons, instances, boxes and expanded counts; then lights and
//! cameras. Stack use is a few KiB whatever the image claims.

use super::error::{ImageError, ImageErrorKind as K};
use super::header::{FORMAT_VERSION, Header, MAGIC, SECTION_COUNT, Section};
use super::layout::ImageLayout;
use super::source::SceneSource;
use super::view::{SceneInfo, SceneView, read_records};
use crate::NodeId;
use crate::limits::{MAX_BANDS, NONE};
use bytemuck::Pod;

mod records;
mod tree;

use records::{
    check_cameras, check_lights, check_materials, check_strings, check_tables, check_values,
    check_vertices,
};
use tree::check_trees;

/// A window of consecutive records, refilled on a miss: sequential scans and the local random
/// reads of polygon corners both cost one source read per `N` records.
pub(super) struct Window<T: Pod, const N: usize> {
    section: Section,
    first: u64,
    len: usize,
    buf: [T; N],
}

impl<T: Pod, const N: usize> Window<T, N> {
    pub(super) fn new(section: Section) -> Self {
        Window {
            section,
            first: 0,
            len: 0,
            buf: [T::zeroed(); N],
        }
    }

    pub(super) fn get<S: SceneSource>(
        &mut self,
        src: &S,
        h: &Header,
        index: u64,
    ) -> Result<T, ImageError> {
        if index < self.first || index >= self.first + self.len as u64 {
            let count = h.section(self.section).count;
            if index >= count {
                return Err(ImageError::at(
                    offset_of(h, self.section, index),
                    K::OutOfRange {
                        section: self.section,
                        index,
                    },
                ));
            }
            let len = (count - index).min(N as u64) as usize;
            read_records(src, h, self.section, index, &mut self.buf[..len])?;
            self.first = index;
            self.len = len;
        }
        Ok(self.buf[(index - self.first) as usize])
    }
}

pub(super) fn offset_of(h: &Header, s: Section, index: u64) -> u64 {
    let e = h.section(s);
    e.offset
        .saturating_add(index.saturating_mul(e.record_size as u64))
}

pub(super) fn err<T>(h: &Header, s: Section, index: u64, kind: K) -> Result<T, ImageError> {
    Err(ImageError::at(offset_of(h, s, index), kind))
}

pub(crate) fn validate<S: SceneSource>(src: S) -> Result<SceneView<S>, ImageError> {
    let header = read_header(&src)?;
    let mut info = SceneInfo {
        bands: header.bands,
        image_bytes: header.file_size,
        scene_root: NodeId(header.scene_root),
        ..SceneInfo::default()
    };
    let count = |s: Section| header.section(s).count as u32; // < NONE, checked by read_header
    info.materials = count(Section::Materials);
    info.nodes = count(Section::Nodes);
    info.polygons = count(Section::Polygons);
    info.vertices = count(Section::Vertices);
    info.originals = count(Section::Originals);
    info.suns = count(Section::Suns);
    info.sky = count(Section::Sky);
    info.cameras = count(Section::Cameras);
    info.strings = count(Section::Strings);

    check_padding(&src, &header)?;
    check_strings(&src, &header)?;
    check_values(&src, &header)?;
    check_materials(&src, &header)?;
    check_vertices(&src, &header)?;
    check_trees(&src, &header, &mut info)?;
    check_lights(&src, &header, Section::Suns)?;
    check_lights(&src, &header, Section::Sky)?;
    check_cameras(&src, &header)?;
    info.tables = check_tables(&src, &header)?;
    Ok(SceneView { src, header, info })
}

fn read_header<S: SceneSource>(src: &S) -> Result<Header, ImageError> {
    let len = src.len();
    let hsize = core::mem::size_of::<Header>() as u64;
    if len < hsize {
        // A short file may still be recognisably not ours.
        let mut m = [0u8; 8];
        let n = (len as usize).min(8);
        src.read_at(0, &mut m[..n])
            .map_err(|e| ImageError::at(0, K::Source(e)))?;
        if m[..n] != MAGIC[..n] {
            return Err(ImageError::at(0, K::BadMagic));
        }
        return Err(ImageError::at(len, K::TooShort { len }));
    }
    let mut h: Header = bytemuck::Zeroable::zeroed();
    src.read_at(0, bytemuck::bytes_of_mut(&mut h))
        .map_err(|e| ImageError::at(0, K::Source(e)))?;
    if h.magic != MAGIC {
        return Err(ImageError::at(0, K::BadMagic));
    }
    if h.version != FORMAT_VERSION {
        return Err(ImageError::at(
            8,
            K::UnsupportedVersion { found: h.version },
        ));
    }
    if h.header_size as u64 != hsize {
        return Err(ImageError::at(
            12,
            K::HeaderSize {
                found: h.header_size,
            },
        ));
    }
    if h.bands == 0 || h.bands as usize > MAX_BANDS {
        return Err(ImageError::at(16, K::Bands { found: h.bands }));
    }
    if h.flags != 0 {
        return Err(ImageError::at(20, K::Reserved));
    }
    if h.reserved != 0 {
        return Err(ImageError::at(28, K::Reserved));
    }
    if h.file_size != len {
        return Err(ImageError::at(
            32,
            K::FileSize {
                claimed: h.file_size,
                actual: len,
            },
        ));
    }
    let mut counts = [0u64; SECTION_COUNT];
    for s in Section::ALL {
        let e = h.section(s);
        let at = 40 + 24 * s as u64;
        if e.record_size != s.record_size() {
            return Err(ImageError::at(
                at + 16,
                K::RecordSize {
                    section: s,
                    found: e.record_size,
                },
            ));
        }
        if e.reserved != 0 {
            return Err(ImageError::at(at + 20, K::Reserved));
        }
        if e.count >= NONE as u64 || e.count.saturating_mul(e.record_size as u64) > len {
            return Err(ImageError::at(at + 8, K::SectionTooLarge { section: s }));
        }
        counts[s as usize] = e.count;
    }
    let layout = ImageLayout::new(&counts).ok_or(ImageError::at(
        40,
        K::SectionTooLarge {
            section: Section::StringBytes,
        },
    ))?;
    for s in Section::ALL {
        let expected = layout.sections[s as usize].offset;
        let found = h.section(s).offset;
        if expected != found {
            return Err(ImageError::at(
                40 + 24 * s as u64,
                K::SectionOffset {
                    section: s,
                    expected,
                    found,
                },
            ));
        }
    }
    if layout.file_size != len {
        return Err(ImageError::at(
            32,
            K::FileSize {
                claimed: layout.file_size,
                actual: len,
            },
        ));
    }
    Ok(h)
}

fn check_padding<S: SceneSource>(src: &S, h: &Header) -> Result<(), ImageError> {
    let mut at = core::mem::size_of::<Header>() as u64;
    let mut ends = [0u64; SECTION_COUNT + 1];
    for s in Section::ALL {
        let e = h.section(s);
        ends[s as usize] = e.offset;
    }
    ends[SECTION_COUNT] = h.file_size;
    for (i, &next) in ends.iter().enumerate() {
        let gap = next.saturating_sub(at) as usize;
        if gap > 0 {
            let mut pad = [0u8; 8];
            let pad = &mut pad[..gap.min(8)];
            src.read_at(at, pad)
                .map_err(|e| ImageError::at(at, K::Source(e)))?;
            if pad.iter().any(|&b| b != 0) {
                return Err(ImageError::at(at, K::Padding));
            }
        }
        if i < SECTION_COUNT {
            let e = h.sections[i];
            at = e.offset + e.count * e.record_size as u64;
        }
    }
    Ok(())
}
