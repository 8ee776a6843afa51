//! The checked view: an image whose every record has been validated, read on demand.

use super::error::{ImageError, ImageErrorKind};
use super::header::{Header, Section};
use super::records::*;
use super::source::SceneSource;
use crate::limits::{MAX_BANDS, MAX_NAME_BYTES, NONE};
use crate::material::{MaterialData, TWO_SIDED};
use crate::*;
use bytemuck::Pod;
use glam::Vec3;

/// Summary of a validated image.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct SceneInfo {
    /// Spectral bands.
    pub bands: u32,
    /// Materials.
    pub materials: u32,
    /// Stored nodes (clusters and instances), originals' trees included.
    pub nodes: u32,
    /// Stored plain clusters.
    pub clusters: u32,
    /// Stored polygons.
    pub polygons: u32,
    /// Stored vertices.
    pub vertices: u32,
    /// Originals.
    pub originals: u32,
    /// Stored exact instances.
    pub exact_instances: u32,
    /// Stored approximate instances.
    pub approximate_instances: u32,
    /// Directional sources.
    pub suns: u32,
    /// Sky directions.
    pub sky: u32,
    /// Cameras.
    pub cameras: u32,
    /// Names in the string table.
    pub strings: u32,
    /// Polygons of the scene once every instance is expanded (the global-id count).
    pub expanded_polygons: u64,
    /// Most instances nested along one path of the expanded scene.
    pub instancing_depth: u32,
    /// Deepest cluster nesting in any stored tree (root = 1).
    pub max_node_depth: u32,
    /// Scene root node.
    pub scene_root: NodeId,
    /// Originals with directional tables.
    pub tables: u32,
    /// Size of the image in bytes.
    pub image_bytes: u64,
}

/// A directional source or sky direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightData {
    /// Unit vector from the scene towards the source.
    pub towards: Vec3,
    /// Irradiance per band on a plane facing the source (W/m^2); `bands` entries used.
    pub irradiance: [f32; MAX_BANDS],
}

/// A pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraData {
    /// Eye (m).
    pub position: Vec3,
    /// Point looked at (m).
    pub target: Vec3,
    /// Up direction.
    pub up: Vec3,
    /// Vertical field of view (degrees).
    pub fovy_deg: f32,
    /// Name, if any.
    pub name: Option<StringId>,
}

/// A validated scene image over a source. Every accessor re-checks its arguments and returns
/// an error rather than panicking; the records themselves were validated by [`SceneView::open`].
#[derive(Debug)]
pub struct SceneView<S> {
    pub(crate) src: S,
    pub(crate) header: Header,
    pub(crate) info: SceneInfo,
}

impl<S: SceneSource> SceneView<S> {
    /// Validates the whole image (reading it once, piece by piece, with fixed stack buffers)
    /// and returns the view.
    pub fn open(src: S) -> Result<Self, ImageError> {
        super::validate::validate(src)
    }

    /// The summary.
    pub fn info(&self) -> &SceneInfo {
        &self.info
    }

    /// The header.
    pub fn header(&self) -> &Header {
        &self.header
    }

    /// The underlying source.
    pub fn source(&self) -> &S {
        &self.src
    }

    /// Gives the source back.
    pub fn into_source(self) -> S {
        self.src
    }

    /// Number of records in a section.
    pub fn count(&self, s: Section) -> u64 {
        self.header.section(s).count
    }

    /// Reads `out.len()` consecutive records of section `s` starting at `first`.
    pub fn read<T: Pod>(&self, s: Section, first: u64, out: &mut [T]) -> Result<(), ImageError> {
        read_records(&self.src, &self.header, s, first, out)
    }

    fn one<T: Pod>(&self, s: Section, index: u64) -> Result<T, ImageError> {
        let mut v = [T::zeroed()];
        self.read(s, index, &mut v)?;
        Ok(v[0])
    }

    /// One node.
    pub fn node(&self, id: NodeId) -> Result<NodeRecord, ImageError> {
        self.one(Section::Nodes, id.0 as u64)
    }

    /// Consecutive nodes starting at `first`.
    pub fn nodes(&self, first: NodeId, out: &mut [NodeRecord]) -> Result<(), ImageError> {
        self.read(Section::Nodes, first.0 as u64, out)
    }

    /// Consecutive polygons starting at `first`.
    pub fn polygons(&self, first: PolyId, out: &mut [PolygonRecord]) -> Result<(), ImageError> {
        self.read(Section::Polygons, first.0 as u64, out)
    }

    /// Consecutive vertex positions (m) starting at `first`.
    pub fn vertices(&self, first: VertexId, out: &mut [[f32; 3]]) -> Result<(), ImageError> {
        self.read(Section::Vertices, first.0 as u64, out)
    }

    /// One instance.
    pub fn instance(&self, id: InstanceId) -> Result<InstanceRecord, ImageError> {
        self.one(Section::Instances, id.0 as u64)
    }

    /// One original.
    pub fn original(&self, id: OriginalId) -> Result<OriginalRecord, ImageError> {
        self.one(Section::Originals, id.0 as u64)
    }

    /// One material record.
    pub fn material_record(&self, id: MaterialId) -> Result<MaterialRecord, ImageError> {
        self.one(Section::Materials, id.0 as u64)
    }

    /// One material's radiometric data.
    pub fn material(&self, id: MaterialId) -> Result<MaterialData, ImageError> {
        let rec = self.material_record(id)?;
        let two = rec.flags & TWO_SIDED != 0;
        let n = MaterialData::value_count(self.info.bands, two) as usize;
        let mut vals = [0.0f32; 5 * MAX_BANDS];
        self.read(Section::Values, rec.values as u64, &mut vals[..n])?;
        Ok(MaterialData::from_values(
            self.info.bands as u8,
            two,
            &vals[..n],
        ))
    }

    fn light(&self, s: Section, id: LightId) -> Result<LightData, ImageError> {
        let rec: LightRecord = self.one(s, id.0 as u64)?;
        let mut irr = [0.0f32; MAX_BANDS];
        self.read(
            Section::Values,
            rec.values as u64,
            &mut irr[..self.info.bands as usize],
        )?;
        Ok(LightData {
            towards: Vec3::from(rec.towards),
            irradiance: irr,
        })
    }

    /// One directional source.
    pub fn sun(&self, id: LightId) -> Result<LightData, ImageError> {
        self.light(Section::Suns, id)
    }

    /// One sky direction.
    pub fn sky(&self, id: LightId) -> Result<LightData, ImageError> {
        self.light(Section::Sky, id)
    }

    /// Table record `i` (in increasing order of originals).
    pub fn table(&self, i: u32) -> Result<TableRecord, ImageError> {
        let mut r = [TableRecord::default()];
        self.read(Section::Tables, i as u64, &mut r)?;
        Ok(r[0])
    }

    /// The table record of `original`, if it has one (a binary search).
    pub fn table_of(&self, original: OriginalId) -> Result<Option<TableRecord>, ImageError> {
        let (mut lo, mut hi) = (0u32, self.info.tables);
        while lo < hi {
            let mid = lo + (hi - lo) / 2;
            let t = self.table(mid)?;
            match t.original.cmp(&original.0) {
                core::cmp::Ordering::Equal => return Ok(Some(t)),
                core::cmp::Ordering::Less => lo = mid + 1,
                core::cmp::Ordering::Greater => hi = mid,
            }
        }
        Ok(None)
    }

    /// Table values from `first` on into `out`.
    pub fn table_values(&self, first: u64, out: &mut [f32]) -> Result<(), ImageError> {
        self.read(Section::TableValues, first, out)
    }

    /// Scatterers' visible fractions (1/255 steps) from byte `first` on into `out`.
    pub fn table_visibility(&self, first: u64, out: &mut [u8]) -> Result<(), ImageError> {
        self.read(Section::TableVisibility, first, out)
    }

    /// One camera.
    pub fn camera(&self, id: CameraId) -> Result<CameraData, ImageError> {
        let c: CameraRecord = self.one(Section::Cameras, id.0 as u64)?;
        Ok(CameraData {
            position: c.position.into(),
            target: c.target.into(),
            up: c.up.into(),
            fovy_deg: c.fovy_deg,
            name: (c.name != NONE).then_some(StringId(c.name)),
        })
    }

    /// Name of band `band`, if the scene names its bands.
    pub fn band_name(&self, band: u32) -> Result<Option<StringId>, ImageError> {
        if self.count(Section::BandNames) == 0 {
            return Ok(None);
        }
        let id: u32 = self.one(Section::BandNames, band as u64)?;
        Ok(Some(StringId(id)))
    }

    /// Reads a name into `buf` (at least [`MAX_NAME_BYTES`] long to fit any name).
    pub fn string<'b>(&self, id: StringId, buf: &'b mut [u8]) -> Result<&'b str, ImageError> {
        let r: StringRef = self.one(Section::Strings, id.0 as u64)?;
        let at = self.header.section(Section::StringBytes).offset + r.offset as u64;
        let len = r.len as usize;
        let dst = buf.get_mut(..len).ok_or(ImageError::at(
            at,
            ImageErrorKind::StringRange { string: id.0 },
        ))?;
        self.src
            .read_at(at, dst)
            .map_err(|e| ImageError::at(at, ImageErrorKind::Source(e)))?;
        core::str::from_utf8(dst)
            .map_err(|_| ImageError::at(at, ImageErrorKind::StringUtf8 { string: id.0 }))
    }

    /// Length in bytes of a name (at most [`MAX_NAME_BYTES`]).
    pub fn string_len(&self, id: StringId) -> Result<usize, ImageError> {
        let r: StringRef = self.one(Section::Strings, id.0 as u64)?;
        Ok((r.len as usize).min(MAX_NAME_BYTES))
    }
}

/// Reads consecutive records of one section, checking the range against the header.
pub(crate) fn read_records<S: SceneSource, T: Pod>(
    src: &S,
    header: &Header,
    s: Section,
    first: u64,
    out: &mut [T],
) -> Result<(), ImageError> {
    let e = header.section(s);
    let size = core::mem::size_of::<T>() as u64;
    let at = e.offset.saturating_add(first.saturating_mul(size));
    let end = first.checked_add(out.len() as u64);
    if size != e.record_size as u64 || end.is_none_or(|end| end > e.count) {
        return Err(ImageError::at(
            at,
            ImageErrorKind::OutOfRange {
                section: s,
                index: first,
            },
        ));
    }
    if out.is_empty() {
        return Ok(());
    }
    src.read_at(at, bytemuck::cast_slice_mut(out))
        .map_err(|err| ImageError::at(at, ImageErrorKind::Source(err)))
}
