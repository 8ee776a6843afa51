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
    /// Per receiving side, the closure factor minus 1 (see `closure`): what the patch's
    /// links bring is scaled by `1 + closure`. 0 in scenes light can leave.
    pub closure: [f32; 2],
    /// Fraction of the area not buried inside closed objects (0..=1): the weight of the
    /// patch's radiosity in its parent's (see `direct`). Points of a floor under a block see
    /// nothing and are seen by nothing; averaging their darkness into the visible part would
    /// darken what the block's faces receive from the floor.
    pub exposed: f32,
    /// How strongly the direct light of suns and sky varies over the patch (W: the power of
    /// the direct light that falls on its lit part, times the lit fraction's distance from
    /// uniform); drives subdivision at shadow edges.
    pub shadow: f32,
    /// Per receiving side, the share of its light that the final gather recomputes, noted
    /// from the hierarchy's solution before the gather changes it (see
    /// `gather_rays::note_shares`): 0 not noted, else `1 + share x 65534`.
    pub gather: [u16; 2],
}

impl Patch {
    pub(crate) fn corner_count(&self) -> usize {
        (self.shape & 0xFF) as usize
    }
    pub(crate) fn depth(&self) -> u32 {
        (self.shape >> 8) & 0xFF
    }

    /// Its box (m): the smallest and largest of its corners' coordinates.
    pub(crate) fn bounds(&self) -> (glam::Vec3, glam::Vec3) {
        let (mut lo, mut hi) = (glam::Vec3::INFINITY, glam::Vec3::NEG_INFINITY);
        for c in &self.corners[..self.corner_count()] {
            lo = lo.min(glam::Vec3::from(*c));
            hi = hi.max(glam::Vec3::from(*c));
        }
        (lo, hi)
    }

    /// True when the links this patch receives changed since its sub-patches' closure
    /// factors were computed (or it is new).
    pub(crate) fn stale(&self) -> bool {
        self.shape & STALE != 0
    }

    /// True when quadrature point `q` lies inside a closed object (see `direct`).
    pub(crate) fn buried(&self, q: usize) -> bool {
        self.shape & (BURIED << q) != 0
    }

    /// True when the patch's exposure and direct light wait to be computed.
    pub(crate) fn unprepared(&self) -> bool {
        self.shape & UNPREPARED != 0
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
    /// First of its polygons in the cluster-order array (a cluster's polygons are
    /// consecutive there).
    pub first_polygon: u32,
    /// Its emission bins (see `bins`) in the bins pool, or NONE.
    pub bins: u32,
    /// The largest radiosity of its polygons (W/m^2, any side and band), as of the last
    /// pull: what a link from it may bring where its light is uneven (see `refine`).
    pub peak: f32,
    /// The power its polygons emit (W, both sides, the largest band): how the final gather
    /// picks emitting polygons in scenes with many (see `emitter_tree`).
    pub emitted: f32,
    /// Closed instances inside.
    pub instances: u32,
    /// First of its closed instances in the instance-order array (consecutive there).
    pub first_instance: u32,
}

/// A closed instance: a leaf that stands for its contents through its original's
/// directional tables (see `tables::closed`).
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct InstanceLeaf {
    /// The instance's transform to world: rotation (unit quaternion x y z w).
    pub rotation: [f32; 4],
    /// Translation (m).
    pub translation: [f32; 3],
    /// Uniform scale.
    pub scale: f32,
    /// A world box that holds the placed box of its original (m).
    pub bbox_min: [f32; 3],
    /// Upper corner.
    pub bbox_max: [f32; 3],
    /// Parent cluster.
    pub parent: u32,
    /// Head of the list of links this element receives.
    pub links: u32,
    /// Its original's table slot (see [`TableSlot`]).
    pub slot: u32,
    /// First float of the light it received in the received region.
    pub received: u32,
    /// Its node in the image (to open it).
    pub node: u32,
    /// The instance expanded in place that it lies in, numbered in the order a level's
    /// walk enters them (0: the level's own nodes); with `node`, it names the instance
    /// within its level (an original expanded twice holds the same nodes twice).
    pub pass: u32,
    /// Its reference area (m^2): 4 x its contents' cross-section `(1 - tau) A` averaged over
    /// the sphere, the area of an isotropic volume that intercepts as much (see
    /// `instance_kernel`).
    pub area_ref: f32,
    /// Its own polygons it blocks with (an approximate instance, see
    /// `original_geometry::own_blocking_polygons`), or 0.
    pub own_polygons: u32,
    /// Byte offset of their region from the blocking regions' start, when `own_polygons > 0`.
    pub own_at: u32,
}

impl InstanceLeaf {
    /// Its transform to world.
    pub(crate) fn place(&self) -> crate::geometry::Similarity {
        crate::geometry::Similarity {
            rotation: glam::Quat::from_array(self.rotation),
            translation: self.translation.into(),
            scale: self.scale,
        }
    }
}

/// The tables of one original with closed instances, read into the workspace: its record
/// and where its values (f32) and visible fractions (bytes) lie (byte offsets); and where
/// its own polygons lie when its instances block with them (see `original_geometry`).
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct TableSlot {
    pub record: crate::image::TableRecord,
    pub values: u64,
    pub visible: u64,
    /// Byte offset of its polygons' region, when `blocking_polygons > 0`.
    pub blocking: u64,
    /// Its polygons, or 0 when its instances block by `tau`.
    pub blocking_polygons: u32,
    /// 1 when its tables keep each of those polygons' first scattering apart, in the same
    /// order (a gather ray that meets one reads its own light), else 0.
    pub polygons_kept: u32,
}

/// A directional source: a sun or one sky direction.
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct Source {
    /// Unit vector from the scene towards the source.
    pub towards: [f32; 3],
    /// How many of the levels an opened instance's contents lie in its rays go on through
    /// (see `vis::Outer`): NONE for the scene's suns and sky (all of them), 0 for light that
    /// reached the instance through a link (already shaded on its way).
    pub outer: u32,
}

/// An input polygon: what every patch of it shares. Followed, per side and band, by its
/// cluster irradiance (W/m^2: what the links its clusters receive give it, with the
/// polygon's own orientation), then per side and band its emitted power (W: radiosity times
/// exposed area), which its clusters radiate with the polygon's orientation.
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
/// Then, per band, the flux density it brings a receiving cluster in the current iteration
/// (W/m^2 on a plane facing the emitter), which its polygons share by their cosines.
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct Link {
    pub recv: u32,
    pub emit: u32,
    /// Next link received by the same element.
    pub next: u32,
    /// `PENDING`, `EXAMINED`, `PARTIAL` bits.
    pub flags: u32,
    /// The coefficients without occlusion, summed over sides: drives refinement (see
    /// `refine::decide`). Like `k_seen`, `spread` and `PARTIAL`, it comes from samples apart
    /// from those of the coefficients the light goes by, so that which links are kept does
    /// not depend on how their own estimates fell.
    pub k_open: f32,
    /// The coefficients with occlusion, summed over sides, from the refinement's samples.
    pub k_seen: f32,
    /// For a receiving cluster: the mean direction of the light from the emitter, weighted
    /// by its flux density, over the flux density (length 1 for a beam, less for light from
    /// a wide emitter; see `oriented`). Zero otherwise.
    pub dir: [f32; 3],
    /// For a receiving patch: how much the coefficient varies over it (see `refine`).
    pub spread: f32,
    /// For a link gathered from a cluster: two polygon sides among those its samples met,
    /// each drawn by its share of the coefficient (polygon index, side in the top bit), or
    /// `NONE`: whose radiosities the link carries (see `oriented::witness_radiosity`).
    pub witness: [u32; 2],
}

/// Patch `shape` bit: the patch's received links changed (see `Patch::stale`).
pub(crate) const STALE: u32 = 1 << 16;
/// Patch `shape` bits 17..=20: quadrature point q is buried (see `Patch::buried`).
pub(crate) const BURIED: u32 = 1 << 17;
/// Patch `shape` bit: exposure and direct light not computed yet.
pub(crate) const UNPREPARED: u32 = 1 << 21;

/// The link's coefficients have not been computed yet.
pub(crate) const PENDING: u32 = 1;
/// The link was considered for refinement with the current radiosities.
pub(crate) const EXAMINED: u32 = 2;
/// Some of the link's visibility rays were blocked.
pub(crate) const PARTIAL: u32 = 4;
/// The record is on the free list.
pub(crate) const FREE: u32 = 8;
/// The emitter is a small cluster seen polygon by polygon (see `cluster_kernel::SMALL_CLUSTER`).
pub(crate) const EXACT: u32 = 16;
