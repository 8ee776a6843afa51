//! The image header and its section table.

use bytemuck::{Pod, Zeroable};

/// First eight bytes of every image.
pub const MAGIC: [u8; 8] = *b"HIRADSCN";

/// The image version this core reads and writes.
pub const FORMAT_VERSION: u32 = 3;

/// Number of sections in the table.
pub const SECTION_COUNT: usize = 16;

/// The sections, in the order they are laid out in the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Section {
    /// UTF-8 bytes of every name.
    StringBytes = 0,
    /// [`super::StringRef`]: one per name.
    Strings,
    /// `u32` string ids naming the bands (none, or one per band).
    BandNames,
    /// `f32` pool holding material and light values.
    Values,
    /// [`super::MaterialRecord`].
    Materials,
    /// `[f32; 3]` vertex positions (m).
    Vertices,
    /// [`super::PolygonRecord`].
    Polygons,
    /// [`super::NodeRecord`], depth-first.
    Nodes,
    /// [`super::InstanceRecord`], in the depth-first order of their nodes.
    Instances,
    /// [`super::OriginalRecord`].
    Originals,
    /// [`super::LightRecord`]: directional sources.
    Suns,
    /// [`super::LightRecord`]: sky directions.
    Sky,
    /// [`super::CameraRecord`].
    Cameras,
    /// [`super::TableRecord`]: an original's directional tables, by increasing original.
    Tables,
    /// `f32` pool of the tables' values, each table's `tau`, albedo, shares, response and
    /// scatterers' shapes in turn.
    TableValues,
    /// `u8` pool of the tables' scatterers' visible fractions (1/255 steps), table by table.
    TableVisibility,
}

impl Section {
    /// Every section in layout order.
    pub const ALL: [Section; SECTION_COUNT] = [
        Section::StringBytes,
        Section::Strings,
        Section::BandNames,
        Section::Values,
        Section::Materials,
        Section::Vertices,
        Section::Polygons,
        Section::Nodes,
        Section::Instances,
        Section::Originals,
        Section::Suns,
        Section::Sky,
        Section::Cameras,
        Section::Tables,
        Section::TableValues,
        Section::TableVisibility,
    ];

    /// Size of one record in bytes.
    pub const fn record_size(self) -> u32 {
        use super::records::*;
        (match self {
            Section::StringBytes => 1,
            Section::Strings => core::mem::size_of::<StringRef>(),
            Section::BandNames => 4,
            Section::Values => 4,
            Section::Materials => core::mem::size_of::<MaterialRecord>(),
            Section::Vertices => 12,
            Section::Polygons => core::mem::size_of::<PolygonRecord>(),
            Section::Nodes => core::mem::size_of::<NodeRecord>(),
            Section::Instances => core::mem::size_of::<InstanceRecord>(),
            Section::Originals => core::mem::size_of::<OriginalRecord>(),
            Section::Suns | Section::Sky => core::mem::size_of::<LightRecord>(),
            Section::Cameras => core::mem::size_of::<CameraRecord>(),
            Section::Tables => core::mem::size_of::<TableRecord>(),
            Section::TableValues => 4,
            Section::TableVisibility => 1,
        }) as u32
    }

    /// Lower-case name for messages.
    pub const fn name(self) -> &'static str {
        match self {
            Section::StringBytes => "string bytes",
            Section::Strings => "strings",
            Section::BandNames => "band names",
            Section::Values => "values",
            Section::Materials => "materials",
            Section::Vertices => "vertices",
            Section::Polygons => "polygons",
            Section::Nodes => "nodes",
            Section::Instances => "instances",
            Section::Originals => "originals",
            Section::Suns => "suns",
            Section::Sky => "sky",
            Section::Cameras => "cameras",
            Section::Tables => "tables",
            Section::TableValues => "table values",
            Section::TableVisibility => "table visibility",
        }
    }
}

/// Where a section lies and how many records it holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable, Default)]
#[repr(C)]
pub struct SectionEntry {
    /// Byte offset from the start of the image (8-aligned).
    pub offset: u64,
    /// Number of records.
    pub count: u64,
    /// Size of one record in bytes (must equal [`Section::record_size`]).
    pub record_size: u32,
    /// Zero.
    pub reserved: u32,
}

/// The fixed-size header at byte 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
#[repr(C)]
pub struct Header {
    /// [`MAGIC`].
    pub magic: [u8; 8],
    /// [`FORMAT_VERSION`].
    pub version: u32,
    /// `size_of::<Header>()`.
    pub header_size: u32,
    /// Spectral bands, 1..=8.
    pub bands: u32,
    /// Zero (reserved for future flags).
    pub flags: u32,
    /// Node index of the scene root: the first node after every original's tree.
    pub scene_root: u32,
    /// Zero.
    pub reserved: u32,
    /// Total image length in bytes.
    pub file_size: u64,
    /// The section table, indexed by [`Section`].
    pub sections: [SectionEntry; SECTION_COUNT],
}

impl Header {
    /// The entry of one section.
    pub fn section(&self, s: Section) -> SectionEntry {
        self.sections[s as usize]
    }
}
