//! Errors of the checked view: what is wrong and at which byte offset of the image.

use super::header::Section;
use super::source::SourceError;
use crate::geometry::{ShapeError, TransformError};
use crate::material::MaterialError;

/// An image fault and the byte offset of the record (or field) that holds it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImageError {
    /// Byte offset from the start of the image.
    pub offset: u64,
    /// What is wrong.
    pub kind: ImageErrorKind,
}

impl ImageError {
    pub(crate) const fn at(offset: u64, kind: ImageErrorKind) -> Self {
        ImageError { offset, kind }
    }
}

/// What is wrong with an image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[allow(missing_docs)] // field names say what they are: indices of the records involved
pub enum ImageErrorKind {
    /// The source failed.
    Source(SourceError),
    /// Shorter than a header.
    TooShort { len: u64 },
    /// Not a hirad scene image.
    BadMagic,
    /// Written by another version of the format.
    UnsupportedVersion { found: u32 },
    /// Header size field does not match this version.
    HeaderSize { found: u32 },
    /// Band count outside 1..=8.
    Bands { found: u32 },
    /// A reserved field or flag is not zero.
    Reserved,
    /// The header's file size does not match the source's length.
    FileSize { claimed: u64, actual: u64 },
    /// A section's record size is not the one this version uses.
    RecordSize { section: Section, found: u32 },
    /// A section holds more records than can be indexed.
    SectionTooLarge { section: Section },
    /// A section is not where the canonical layout puts it.
    SectionOffset {
        section: Section,
        expected: u64,
        found: u64,
    },
    /// A padding byte between sections is not zero.
    Padding,
    /// A string lies outside the string bytes or is too long.
    StringRange { string: u32 },
    /// A string is not valid UTF-8.
    StringUtf8 { string: u32 },
    /// A name refers to a string that does not exist.
    NameIndex { index: u32 },
    /// Band names present but not one per band.
    BandNames { found: u64 },
    /// A value in the value pool is NaN or infinite.
    Value { index: u64 },
    /// A vertex coordinate is NaN or infinite.
    Vertex { vertex: u64 },
    /// A material's values lie outside the value pool.
    MaterialValues { material: u32 },
    /// A material's values are physically impossible.
    Material { material: u32, error: MaterialError },
    /// Unknown material flags.
    MaterialFlags { material: u32 },
    /// A polygon corner indexes past its node's vertices.
    Corner { polygon: u32, corner: u8 },
    /// A polygon uses a material that does not exist.
    PolygonMaterial { polygon: u32, material: u32 },
    /// A polygon's shape is unusable.
    Shape { polygon: u32, error: ShapeError },
    /// The image holds no scene tree.
    NoScene,
    /// A node's subtree end is not inside its parent's range.
    SubtreeEnd { node: u32 },
    /// Clusters nested deeper than [`crate::limits::MAX_NODE_DEPTH`].
    TooDeep { node: u32 },
    /// A node's own polygons are not the next ones in depth-first order.
    PolygonRange { node: u32 },
    /// A node's own vertices are not the next ones in depth-first order.
    VertexRange { node: u32 },
    /// Unknown node flags, or a non-finite or negative age.
    NodeAttributes { node: u32 },
    /// A tree root (of an original or the scene) is an instance.
    RootIsInstance { node: u32 },
    /// A node's instance is not the next instance record in depth-first order.
    InstanceOrder { node: u32, instance: u32 },
    /// An exact instance has geometry or children of its own.
    ExactWithContent { node: u32 },
    /// Unknown instance flags.
    InstanceFlags { instance: u32 },
    /// An instance refers to an original that does not exist.
    OriginalIndex { instance: u32, original: u32 },
    /// An instance inside an original refers to that original or a later one: a cycle.
    OriginalCycle { instance: u32, original: u32 },
    /// An instance's transform is unusable.
    Transform {
        instance: u32,
        error: TransformError,
    },
    /// A node's bounding box is not finite, inverted, or does not contain its content.
    Bbox { node: u32 },
    /// A node's expanded polygon count is wrong.
    Expanded { node: u32 },
    /// The expanded scene has more than 2^64 polygons.
    ExpansionOverflow { node: u32 },
    /// Instances nested deeper than [`crate::limits::MAX_INSTANCING_DEPTH`].
    InstancingTooDeep { node: u32 },
    /// An original's root is not where the previous tree ended.
    OriginalRoot { original: u32 },
    /// An original's summary (expanded polygons, instancing depth) is wrong.
    OriginalSummary { original: u32 },
    /// The scene root is not where the last original's tree ended, or its tree does not end
    /// at the last node.
    SceneRoot,
    /// Records left over that no node owns.
    Unowned {
        section: Section,
        used: u64,
        count: u64,
    },
    /// A light's direction is not a unit vector.
    LightDirection { light: u32 },
    /// A light's values lie outside the pool or are negative.
    LightValues { light: u32 },
    /// A camera is unusable (non-finite, eye on target, up along the view, bad field of view).
    Camera { camera: u32 },
    /// A table names no original, or the tables are not in increasing order of originals.
    TableOriginal { table: u32 },
    /// A table's bands, grid sides, flags or reserved fields are wrong.
    TableGrid { table: u32 },
    /// A table's box is not finite or its corners are not ordered, or an error it records
    /// is not a finite non-negative number.
    TableBox { table: u32 },
    /// A table's values do not follow the previous table's in the pool, or the pool holds
    /// values no table owns.
    TableRange { table: u32 },
    /// A table value is out of its range (`tau` and the albedo 0..=1, the response finite and
    /// non-negative).
    TableValue { table: u32, index: u64 },
    /// A caller asked for a record past the end of a section.
    OutOfRange { section: Section, index: u64 },
}

impl core::fmt::Display for ImageError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "byte {}: ", self.offset)?;
        core::fmt::Display::fmt(&self.kind, f)
    }
}

impl core::fmt::Display for ImageErrorKind {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        use ImageErrorKind::*;
        match *self {
            Source(e) => write!(f, "{e}"),
            TooShort { len } => write!(f, "only {len} bytes: too short for a scene image header"),
            BadMagic => f.write_str("not a hirad scene image (bad magic bytes)"),
            UnsupportedVersion { found } => write!(
                f,
                "image format version {found}, but this hirad reads version {}",
                super::FORMAT_VERSION
            ),
            HeaderSize { found } => write!(f, "header size {found} does not match this format version"),
            Bands { found } => write!(f, "{found} spectral bands; 1 to {} are supported", crate::limits::MAX_BANDS),
            Reserved => f.write_str("a reserved field or flag is not zero"),
            FileSize { claimed, actual } => {
                write!(f, "header claims {claimed} bytes but the image has {actual} (truncated or padded)")
            }
            RecordSize { section, found } => write!(
                f,
                "section '{}' has {found}-byte records, expected {}",
                section.name(),
                section.record_size()
            ),
            SectionTooLarge { section } => write!(f, "section '{}' claims an absurd record count", section.name()),
            SectionOffset { section, expected, found } => write!(
                f,
                "section '{}' starts at byte {found}, expected {expected} (counts and layout disagree)",
                section.name()
            ),
            Padding => f.write_str("padding between sections is not zero"),
            StringRange { string } => write!(f, "string {string} lies outside the string bytes or is too long"),
            StringUtf8 { string } => write!(f, "string {string} is not valid UTF-8"),
            NameIndex { index } => write!(f, "name refers to string {index}, which does not exist"),
            BandNames { found } => write!(f, "{found} band names, expected none or one per band"),
            Value { index } => write!(f, "value {index} is not a finite number"),
            Vertex { vertex } => write!(f, "vertex {vertex} has a coordinate that is not a finite number"),
            MaterialValues { material } => write!(f, "material {material}: values lie outside the value pool"),
            Material { material, error } => write!(f, "material {material}: {error}"),
            MaterialFlags { material } => write!(f, "material {material}: unknown flags"),
            Corner { polygon, corner } => {
                write!(f, "polygon {polygon}: corner {corner} indexes past its node's vertices")
            }
            PolygonMaterial { polygon, material } => {
                write!(f, "polygon {polygon}: material {material} does not exist")
            }
            Shape { polygon, error } => write!(f, "polygon {polygon}: {error}"),
            NoScene => f.write_str("the image holds no scene tree"),
            SubtreeEnd { node } => write!(f, "node {node}: its subtree overruns its parent (or is empty)"),
            TooDeep { node } => write!(
                f,
                "node {node}: clusters nested deeper than {} levels",
                crate::limits::MAX_NODE_DEPTH
            ),
            PolygonRange { node } => write!(f, "node {node}: own polygons are out of depth-first order or past the end"),
            VertexRange { node } => write!(f, "node {node}: own vertices are out of depth-first order or past the end"),
            NodeAttributes { node } => write!(f, "node {node}: unknown flags, or an age that is negative or not finite"),
            RootIsInstance { node } => write!(f, "node {node}: the root of a tree cannot be an instance"),
            InstanceOrder { node, instance } => {
                write!(f, "node {node}: instance {instance} is not the next instance in depth-first order")
            }
            ExactWithContent { node } => write!(f, "node {node}: an exact instance cannot hold geometry or children"),
            InstanceFlags { instance } => write!(f, "instance {instance}: unknown flags"),
            OriginalIndex { instance, original } => {
                write!(f, "instance {instance}: original {original} does not exist")
            }
            OriginalCycle { instance, original } => write!(
                f,
                "instance {instance}: original {original} is the original being defined or a later one (a cycle)"
            ),
            Transform { instance, error } => write!(f, "instance {instance}: {error}"),
            Bbox { node } => write!(f, "node {node}: bounding box is not finite or does not contain its content"),
            Expanded { node } => write!(f, "node {node}: expanded polygon count does not match its content"),
            ExpansionOverflow { node } => write!(f, "node {node}: the expanded scene exceeds 2^64 polygons"),
            InstancingTooDeep { node } => write!(
                f,
                "node {node}: instances nested deeper than {} levels",
                crate::limits::MAX_INSTANCING_DEPTH
            ),
            OriginalRoot { original } => write!(f, "original {original}: root is not where the previous tree ended"),
            OriginalSummary { original } => {
                write!(f, "original {original}: expanded polygon count or instancing depth is wrong")
            }
            SceneRoot => f.write_str("scene root is not after the last original, or its tree does not end at the last node"),
            Unowned { section, used, count } => write!(
                f,
                "section '{}' holds {count} records but the nodes own only {used}",
                section.name()
            ),
            LightDirection { light } => write!(f, "light {light}: direction is not a unit vector"),
            LightValues { light } => {
                write!(f, "light {light}: irradiance values lie outside the pool or are negative")
            }
            Camera { camera } => write!(
                f,
                "camera {camera}: not finite, eye on target, up along the view, or field of view outside (0, 180) degrees"
            ),
            TableOriginal { table } => write!(
                f,
                "table {table}: names no original, or the tables are not in increasing order of originals"
            ),
            TableGrid { table } => write!(
                f,
                "table {table}: bands, grid sides (1 to 256), flags or reserved fields are wrong"
            ),
            TableBox { table } => write!(
                f,
                "table {table}: box not finite or not ordered, or a recorded error is not a finite non-negative number"
            ),
            TableRange { table } => write!(
                f,
                "table {table}: values do not follow the previous table's in the pool, or the pool holds values no table owns"
            ),
            TableValue { table, index } => write!(
                f,
                "table {table}: value {index} is out of range (tau and albedo 0 to 1, response finite and non-negative)"
            ),
            OutOfRange { section, index } => write!(f, "no record {index} in section '{}'", section.name()),
        }
    }
}

impl core::error::Error for ImageError {}
