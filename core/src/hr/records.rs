//! The plain-old-data records the solver keeps in its workspace. Each element record is
//! followed by its per-band values (see the `*_values` functions): only what the element
//! needs — clusters and one-sided patches one side, two-sided patches two.

use bytemuck::{Pod, Zeroable};

/// A surface element: an input polygon or one of its quadtree sub-patches.
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct Patch {
    /// World-space corners (m); the fourth is unused for triangles.
    pub corners: [[f32; 3]; 4],
    /// Parent element (a cluster for an input polygon, else the parent patch).
    pub parent: u32,
    /// First of the 4 children (consecutive in the same pool), or NONE for a leaf.
    pub first_child: u32,
    /// Input polygon index (= global id in a fully expanded scene).
    pub poly: u32,
    /// Head of the list of links this element receives.
    pub links: u32,
    /// Area (m^2).
    pub area: f32,
    /// Corner count (3 or 4) in the low byte, subdivision depth in the next.
    pub shape: u32,
    /// Per receiving side, the factor that makes the irradiance inherited from ancestor
    /// patches exact at this patch's own quadrature points (see `closure`): 1 when the
    /// patch inherits nothing.
    pub closure: [f32; 2],
}

impl Patch {
    pub(crate) fn corner_count(&self) -> usize {
        (self.shape & 0xFF) as usize
    }
    pub(crate) fn depth(&self) -> u32 {
        (self.shape >> 8) & 0xFF
    }

    /// True when the links this patch receives changed since its sub-patches' closure
    /// factors were computed (or it is new).
    pub(crate) fn stale(&self) -> bool {
        self.shape & STALE != 0
    }
}

/// A cluster: a box of elements exchanging light as an isotropic volume.
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct Cluster {
    /// Box (m).
    pub bbox_min: [f32; 3],
    /// Box (m).
    pub bbox_max: [f32; 3],
    /// Parent cluster, or NONE for the root.
    pub parent: u32,
    /// First entry of its children in the child-list array.
    pub children: u32,
    /// Number of children.
    pub child_count: u32,
    /// Head of the list of links this element receives.
    pub links: u32,
    /// Total area of the surfaces inside (one side, m^2).
    pub area: f32,
    /// Number of input polygons inside.
    pub polygons: u32,
}

/// A directional source: a sun or one sky direction.
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct Source {
    /// Unit vector from the scene towards the source.
    pub towards: [f32; 3],
    /// Unused.
    pub reserved: u32,
}

/// An input polygon: what every patch of it shares.
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct Polygon {
    /// Unit front normal.
    pub normal: [f32; 3],
    /// Material index.
    pub material: u32,
    /// Its root patch.
    pub root: u32,
}

/// A material, every band, as the solver reads it.
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct Material {
    pub rho: [[f32; 8]; 2],
    pub emit: [[f32; 8]; 2],
    pub tau: [f32; 8],
    pub two_sided: u32,
}

/// A link: light gathered by `recv` from `emit`. The coefficients follow the header: `k[r][s]`
/// turns the emitter's side-`s` radiosity into irradiance on the receiver's side `r`; one
/// coefficient (front from front) in scenes without two-sided materials, four otherwise.
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct Link {
    pub recv: u32,
    pub emit: u32,
    /// Next link received by the same element.
    pub next: u32,
    /// `PENDING`, `EXAMINED`, `PARTIAL` bits.
    pub flags: u32,
    /// The same coefficients without occlusion, summed over sides (drives refinement of
    /// partly or wholly hidden links).
    pub k_open: f32,
}

/// Patch `shape` bit: the patch's received links changed (see `Patch::stale`).
pub(crate) const STALE: u32 = 1 << 16;

/// The link's coefficients have not been computed yet.
pub(crate) const PENDING: u32 = 1;
/// The link was considered for refinement with the current radiosities.
pub(crate) const EXAMINED: u32 = 2;
/// Some of the link's visibility rays were blocked.
pub(crate) const PARTIAL: u32 = 4;
/// The record is on the free list.
pub(crate) const FREE: u32 = 8;
