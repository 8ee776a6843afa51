//! The binary scene image (`.hirb`) and its checked view.
//!
//! One little-endian byte image: a [`Header`] with a table of sections, then the sections in a
//! fixed order, each 8-byte aligned, with zero padding between them. Records are plain old
//! data read with bytemuck. Nodes are stored depth-first, each tree (every original, then the
//! scene) one contiguous range, and every subtree's polygons and vertices one contiguous range,
//! so that a subtree can be read on its own. [`SceneView::open`] validates every index, count,
//! float and nesting depth before anything is used, reading through a [`SceneSource`] piece by
//! piece with fixed stack buffers: nothing is ever sized from what the file claims.

mod error;
mod header;
mod layout;
mod records;
mod source;
mod validate;
mod view;

pub use error::{ImageError, ImageErrorKind};
pub use header::{FORMAT_VERSION, Header, MAGIC, SECTION_COUNT, Section, SectionEntry};
pub use layout::{ImageLayout, align8};
pub use records::{
    CameraRecord, EXACT, HAS_AGE, InstanceRecord, LightRecord, MaterialRecord, NodeRecord,
    OriginalRecord, PolygonRecord, StringRef, TABLE_MET, TableRecord,
};
pub use source::{SceneSource, SliceSource, SourceError};
pub use view::{CameraData, LightData, SceneInfo, SceneView};
