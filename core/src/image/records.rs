//! Plain-old-data records of the image sections. All little-endian; `NONE` (`u32::MAX`)
//! marks an absent index.

use crate::limits::NONE;
use crate::{InstanceId, MaterialId, NodeId, OriginalId, StringId};
use bytemuck::{Pod, Zeroable};

/// A name: a range of the string-bytes section, valid UTF-8.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable, Default)]
#[repr(C)]
pub struct StringRef {
    /// Byte offset into the string-bytes section.
    pub offset: u32,
    /// Length in bytes.
    pub len: u32,
}

/// A material: its values live in the value pool (see [`crate::material::MaterialData`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable, Default)]
#[repr(C)]
pub struct MaterialRecord {
    /// Name (required, unique).
    pub name: u32,
    /// [`crate::material::TWO_SIDED`] or 0.
    pub flags: u32,
    /// Index of the first value in the value pool.
    pub values: u32,
    /// Zero.
    pub reserved: u32,
}

/// A triangle (`corners[3] == NONE`) or quad. Corners index the owning node's own vertices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable, Default)]
#[repr(C)]
pub struct PolygonRecord {
    /// Corner indices relative to the owning node's `vert_first`, counter-clockwise seen
    /// from the front.
    pub corners: [u32; 4],
    /// Material index.
    pub material: u32,
}

impl PolygonRecord {
    /// 3 for a triangle, 4 for a quad.
    pub fn corner_count(&self) -> usize {
        if self.corners[3] == NONE { 3 } else { 4 }
    }

    /// The material handle.
    pub fn material(&self) -> MaterialId {
        MaterialId(self.material)
    }
}

/// Node flag: the `age` field is present.
pub const HAS_AGE: u32 = 1;

/// A cluster node. Nodes are depth-first: the first child of node `i` is `i + 1`, the next
/// sibling of a child `c` is `c.subtree_end`. A node's own polygons come before the polygons of
/// its children, so the polygons of a subtree are one contiguous range (and so are vertices).
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable, Default)]
#[repr(C)]
pub struct NodeRecord {
    /// Lower corner of the bounding box in the parent's frame (m).
    pub bbox_min: [f32; 3],
    /// Upper corner of the bounding box in the parent's frame (m).
    pub bbox_max: [f32; 3],
    /// Polygons in this subtree once every instance inside is expanded.
    pub expanded_polygons: u64,
    /// One past the last node of this subtree.
    pub subtree_end: u32,
    /// First own polygon.
    pub poly_first: u32,
    /// Number of own polygons.
    pub poly_count: u32,
    /// First own vertex.
    pub vert_first: u32,
    /// Number of own vertices.
    pub vert_count: u32,
    /// Instance record, or `NONE` for a plain cluster.
    pub instance: u32,
    /// Name, or `NONE`.
    pub name: u32,
    /// Axis kind (botanical axis order, or any user class), or `NONE`.
    pub axis: u32,
    /// Age of the axis (growth units, usually years); valid when `flags & HAS_AGE`.
    pub age: f32,
    /// [`HAS_AGE`] or 0.
    pub flags: u32,
}

impl NodeRecord {
    /// The instance handle, if this node is an instance.
    pub fn instance(&self) -> Option<InstanceId> {
        (self.instance != NONE).then_some(InstanceId(self.instance))
    }

    /// The name handle, if any.
    pub fn name(&self) -> Option<StringId> {
        (self.name != NONE).then_some(StringId(self.name))
    }

    /// The axis kind, if any.
    pub fn axis(&self) -> Option<u32> {
        (self.axis != NONE).then_some(self.axis)
    }

    /// The age, if any.
    pub fn age(&self) -> Option<f32> {
        (self.flags & HAS_AGE != 0).then_some(self.age)
    }

    /// One past the last node of the subtree.
    pub fn subtree_end(&self) -> NodeId {
        NodeId(self.subtree_end)
    }
}

/// Instance flag: the instance is exact (uses the original's geometry when opened); without
/// it the instance is approximate and its node's subtree holds its own geometry.
pub const EXACT: u32 = 1;

/// An instance: an original placed by a similarity transform.
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable, Default)]
#[repr(C)]
pub struct InstanceRecord {
    /// The original.
    pub original: u32,
    /// [`EXACT`] or 0.
    pub flags: u32,
    /// Rotation quaternion `x, y, z, w` (unit length).
    pub rotation: [f32; 4],
    /// Translation (m).
    pub translation: [f32; 3],
    /// Uniform scale (> 0).
    pub scale: f32,
}

impl InstanceRecord {
    /// The original's handle.
    pub fn original(&self) -> OriginalId {
        OriginalId(self.original)
    }

    /// True for an exact instance.
    pub fn is_exact(&self) -> bool {
        self.flags & EXACT != 0
    }

    /// The similarity transform (validated by [`super::SceneView::open`]).
    pub fn transform(&self) -> crate::geometry::Similarity {
        crate::geometry::Similarity {
            rotation: glam::Quat::from_array(self.rotation),
            translation: self.translation.into(),
            scale: self.scale,
        }
    }
}

/// An original: a tree of nodes that instances share.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable, Default)]
#[repr(C)]
pub struct OriginalRecord {
    /// Root node of its tree.
    pub root: u32,
    /// Name (required, unique).
    pub name: u32,
    /// Most instances nested along one path inside it.
    pub instancing_depth: u32,
    /// Zero.
    pub reserved: u32,
    /// Polygons once expanded (equals the root's).
    pub expanded_polygons: u64,
}

/// A directional source or a sky direction.
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable, Default)]
#[repr(C)]
pub struct LightRecord {
    /// Unit vector pointing from the scene towards the source.
    pub towards: [f32; 3],
    /// Index of `bands` irradiance values (W/m^2 on a plane facing the source) in the pool.
    pub values: u32,
}

/// A pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable, Default)]
#[repr(C)]
pub struct CameraRecord {
    /// Eye position (m).
    pub position: [f32; 3],
    /// Point looked at (m).
    pub target: [f32; 3],
    /// Up direction (not necessarily unit).
    pub up: [f32; 3],
    /// Vertical field of view (degrees, 0 < fovy < 180).
    pub fovy_deg: f32,
    /// Name, or `NONE`.
    pub name: u32,
    /// Zero.
    pub reserved: u32,
}

/// An original's directional tables (see [`crate::tables`]): where its values lie in the
/// table value pool, its grids and box, and the errors its bake measured.
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable, Default)]
#[repr(C)]
pub struct TableRecord {
    /// The original (index into the originals).
    pub original: u32,
    /// Bands (equals the image's).
    pub bands: u32,
    /// Side of the `tau` grid.
    pub tau_side: u32,
    /// Side of the incoming grid of the phase table.
    pub incoming_side: u32,
    /// Side of the outgoing grid.
    pub outgoing_side: u32,
    /// Bit 0: the bake met its error targets. Other bits zero.
    pub flags: u32,
    /// The original's box in its own frame (m): lower corner.
    pub lo: [f32; 3],
    /// Upper corner.
    pub hi: [f32; 3],
    /// First value of `tau` (`tau_side^2` values) in the pool; the albedo (`tau_side^2 x 2
    /// x bands`, on the `tau` grid, per side lit), the shares by side lit (`incoming_side^2
    /// x 2 x bands`), the response (`incoming_side^2 x outgoing_side^2 x 2 x bands`) and the
    /// shapes of the scatterers (`scatterers x (4 + 3 x bands)`: normal, area, then per band
    /// front and back reflectance and transmittance) follow it.
    pub first: u64,
    /// Largest relative error of the cross-section at the bake's check directions.
    pub tau_error: f32,
    /// Largest relative error of the scattered power at the bake's check directions.
    pub scattered_error: f32,
    /// Largest error of the bidirectional intensity at the bake's check directions.
    pub intensity_error: f32,
    /// Polygons whose first scattering the tables keep apart (see
    /// [`crate::tables::single`]); 0 when the phase table holds all the scattered light.
    pub scatterers: u32,
    /// Side of the grid of the scatterers' visible fractions; 0 when there are none.
    pub single_side: u32,
    /// Zero.
    pub reserved: u32,
    /// First byte of the scatterers' visible fractions (`single_side^2 x scatterers`) in the
    /// table visibility pool.
    pub first_visible: u64,
}

/// Flag of [`TableRecord::flags`]: the bake met its targets.
pub const TABLE_MET: u32 = 1;

impl TableRecord {
    /// Values of `tau`, of the albedo, of the shares by side lit, of the response and of
    /// the scatterers' shapes, in that order.
    pub fn lengths(&self) -> [u64; 5] {
        let n = |s: u32| s as u64 * s as u64;
        let bands = self.bands as u64;
        [
            n(self.tau_side),
            n(self.tau_side) * 2 * bands,
            n(self.incoming_side) * 2 * bands,
            n(self.incoming_side) * n(self.outgoing_side) * 2 * bands,
            self.scatterers as u64
                * crate::tables::single::shape_stride(self.bands as usize) as u64,
        ]
    }

    /// Bytes of the scatterers' visible fractions in the visibility pool.
    pub fn visible_bytes(&self) -> u64 {
        self.single_side as u64 * self.single_side as u64 * self.scatterers as u64
    }

    /// All its values.
    pub fn values(&self) -> u64 {
        self.lengths().iter().sum()
    }
}

const _: () = {
    assert!(core::mem::size_of::<NodeRecord>() == 72);
    assert!(core::mem::size_of::<PolygonRecord>() == 20);
    assert!(core::mem::size_of::<InstanceRecord>() == 40);
    assert!(core::mem::size_of::<OriginalRecord>() == 24);
    assert!(core::mem::size_of::<MaterialRecord>() == 16);
    assert!(core::mem::size_of::<LightRecord>() == 16);
    assert!(core::mem::size_of::<CameraRecord>() == 48);
    assert!(core::mem::size_of::<TableRecord>() == 88);
    assert!(core::mem::size_of::<super::Header>() == 40 + 24 * super::SECTION_COUNT);
};
