//! The canonical placement of sections, shared by writers and the validating reader so that
//! one scene always gives the same bytes.

use super::header::{FORMAT_VERSION, Header, MAGIC, SECTION_COUNT, Section, SectionEntry};

/// Rounds up to the next multiple of 8.
pub const fn align8(x: u64) -> u64 {
    (x + 7) & !7
}

/// Section offsets for given record counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImageLayout {
    /// One entry per section, in layout order.
    pub sections: [SectionEntry; SECTION_COUNT],
    /// Total image length in bytes.
    pub file_size: u64,
}

impl ImageLayout {
    /// Lays out sections with the given record counts, or `None` if the image would exceed
    /// `u64` bytes.
    pub fn new(counts: &[u64; SECTION_COUNT]) -> Option<Self> {
        let mut sections = [SectionEntry::default(); SECTION_COUNT];
        let mut at = align8(core::mem::size_of::<Header>() as u64);
        for s in Section::ALL {
            let count = counts[s as usize];
            let size = s.record_size();
            let bytes = count.checked_mul(size as u64)?;
            sections[s as usize] = SectionEntry {
                offset: at,
                count,
                record_size: size,
                reserved: 0,
            };
            at = at.checked_add(bytes)?.checked_add(7)? & !7;
        }
        Some(ImageLayout {
            sections,
            file_size: at,
        })
    }

    /// The header for this layout.
    pub fn header(&self, bands: u32, scene_root: u32) -> Header {
        Header {
            magic: MAGIC,
            version: FORMAT_VERSION,
            header_size: core::mem::size_of::<Header>() as u32,
            bands,
            flags: 0,
            scene_root,
            reserved: 0,
            file_size: self.file_size,
            sections: self.sections,
        }
    }
}
