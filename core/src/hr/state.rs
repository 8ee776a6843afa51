//! The solver's state: the workspace bytes, where things are in them, and typed access to
//! elements, values and links.

use super::ids::{Elem, Kind};
use super::layout::Layout;
use super::pool::{Blocks, Pool, floats, floats_mut, read, write};
use super::records::*;
use super::settings::{Instancing, Settings, Stats};
use crate::limits::NONE;
use glam::Vec3;

mod instances;
pub(crate) use instances::{Handed, received_parts_floats};

/// Everything the solver knows, minus the workspace bytes (kept apart so that phases can
/// borrow the bytes shared and a scratch buffer mutably at the same time).
#[derive(Clone, Debug)]
pub(crate) struct State {
    pub lay: Layout,
    pub blocks: Blocks,
    /// One-sided and two-sided patches.
    pub patches: [Pool; 2],
    pub links: Pool,
    /// Emission bins of large clusters (see `bins`).
    pub bins: Pool,
    pub settings: Settings,
    pub bands: usize,
    /// Clusters created so far.
    pub clusters: u32,
    /// Input polygons loaded so far.
    pub polygons: u32,
    /// Entries of the child-list array used so far.
    pub child_entries: u32,
    /// Epsilon's unit (W): the power leaving all surfaces (emitted and reflected, the
    /// largest band), as of the last solution; before the first, what they emit and reflect
    /// of the direct light.
    pub power: f32,
    /// The power epsilon is relative to when it is larger than `power` (W): an opened
    /// instance's level refines by its scene's threshold, as the expanded scene would; 0
    /// otherwise.
    pub unit_power: f32,
    /// Receiving sides of the whole scene's polygons, every instance expanded, when this
    /// is one of its levels (the final gather spreads its rays over them, see
    /// `gather_rays::rays_per_side`); 0: this level's own.
    pub scene_sides: u64,
    /// Most passes of the final gather (its relighting passes and the polygons' own) when
    /// their number is automatic: an opened level takes at most as many as its parent did
    /// (see `relight::relight_passes`).
    pub most_passes: u32,
    /// Suns (the first sources) and all sources (suns, then sky directions).
    pub suns: u32,
    pub sources: u32,
    /// Geometric mean of the input polygons' areas (m^2): the scale of the shadows polygons
    /// cast, for sampling direct light.
    pub typical_area: f32,
    /// Minimum patch area (m^2).
    pub min_area: f32,
    /// Length beyond which a ray towards a directional source has left the scene (m).
    pub far: f32,
    /// True when no light leaves the scene (see `direct::test_closed`), and whether light
    /// then reaches the back of a one-sided polygon.
    pub closed: bool,
    pub sees_backs: bool,
    /// The contraction ratio of the last solution's iterations (infinite until known).
    pub contraction: f32,
    /// Patches of each pool below these indices are prepared (see `direct`): new patches
    /// only ever come at the end of their pool.
    pub prepared: [u32; 2],
    /// Links waiting for evaluation lie in `pending.0..pending.1` (empty when start >= end);
    /// there are `pending_links` of them.
    pub pending: (u32, u32),
    pub pending_links: u64,
    /// Per kind of receiver (clusters, one-sided, two-sided patches, closed instances), the
    /// index range that may hold links no refinement pass has examined yet (see `refine`).
    pub touched: [(u32, u32); 4],
    /// Per patch pool, the patches below this index were checked for shadow edges in this
    /// round (see `refine`).
    pub shadow_checked: [u32; 2],
    /// The final gather's corrections (see `relight::relight`): byte offset of one
    /// value per band for every side of every patch, one-sided patches first, or `NONE as
    /// usize` before the gather takes them; and how many one-sided patches there were then.
    pub correction: usize,
    pub correction_split: u32,
    /// Which instances stay closed, and how many closed instances, table slots, table
    /// values (floats), visible fractions (bytes) and received floats are loaded so far.
    pub instancing: Instancing,
    pub instances: u32,
    pub slots: u32,
    pub table_floats: usize,
    pub table_bytes: usize,
    pub received_floats: usize,
    /// Bytes of the blocking region used (see `original_geometry`).
    pub blocking_bytes: usize,
    /// True when the level's closed approximate instances block with their own polygons
    /// (see `Settings::own_polygons`; the census decided it for the level as a whole).
    pub own_blocking: bool,
    /// The last gather's largest change of a closed instance's mean radiosity and the
    /// largest such radiosity (W/m^2; see `instance_gather::gather_instances`).
    pub instance_change: (f32, f32),
    /// The scene's box (m).
    pub scene_min: Vec3,
    pub scene_max: Vec3,
    pub stats: Stats,
}

/// Geometry of an element, as the evaluation needs it.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Shape {
    Patch {
        corners: [Vec3; 4],
        n: usize,
        normal: Vec3,
        poly: u32,
        area: f32,
        two_sided: bool,
    },
    Cluster {
        min: Vec3,
        max: Vec3,
        area: f32,
    },
    Source {
        towards: Vec3,
    },
    /// A closed instance: its index, world box (m) and reference area (m^2, see
    /// `instance_kernel`).
    Instance {
        index: u32,
        min: Vec3,
        max: Vec3,
        area_ref: f32,
    },
}

impl State {
    /// The end of a ray from `x` along the unit direction `d` that has left the scene: twice
    /// as far as the scene's box reaches that way, so that a polygon on the box's boundary
    /// is met in the middle of the segment, well inside the caster's relative margins
    /// (a segment of fixed great length would let rays starting near an edge slip past the
    /// polygon beside it).
    pub(crate) fn beyond(&self, x: Vec3, d: Vec3) -> Vec3 {
        let mut t = f32::INFINITY;
        for k in 0..3 {
            let dk = d[k];
            if dk > 0.0 {
                t = t.min((self.scene_max[k] - x[k]) / dk);
            } else if dk < 0.0 {
                t = t.min((self.scene_min[k] - x[k]) / dk);
            }
        }
        let diag = (self.scene_max - self.scene_min).length();
        let t = if t.is_finite() { t.max(0.0) } else { self.far };
        x + d * (2.0 * t + 1e-3 * diag).min(self.far)
    }

    pub(crate) fn pool(&self, k: Kind) -> &Pool {
        match k {
            Kind::Patch2 => &self.patches[1],
            _ => &self.patches[0],
        }
    }

    /// Byte offset of an element's record.
    pub(crate) fn at(&self, ws: &[u8], e: Elem) -> usize {
        let s = &self.lay.strides;
        match e.kind() {
            Kind::Cluster => self.lay.clusters + e.index() as usize * s.cluster,
            Kind::Source => self.lay.sources + e.index() as usize * s.source,
            Kind::Instance => self.lay.instances + e.index() as usize * s.instance,
            k => self.pool(k).at(ws, &self.blocks, e.index()),
        }
    }

    /// The final gather's correction of a patch side's irradiance (W/m^2 per band), if the
    /// gather keeps them (see `correction`).
    pub(crate) fn correction<'a>(&self, ws: &'a [u8], e: Elem, side: usize) -> Option<&'a [f32]> {
        let at = self.correction_at(e, side)?;
        Some(floats(ws, at, self.bands))
    }

    pub(crate) fn correction_mut<'a>(
        &self,
        ws: &'a mut [u8],
        e: Elem,
        side: usize,
    ) -> Option<&'a mut [f32]> {
        let at = self.correction_at(e, side)?;
        Some(floats_mut(ws, at, self.bands))
    }

    fn correction_at(&self, e: Elem, side: usize) -> Option<usize> {
        if self.correction == NONE as usize {
            return None;
        }
        let slot = match e.kind() {
            Kind::Patch1 => e.index() as usize,
            Kind::Patch2 => self.correction_split as usize + 2 * e.index() as usize + side.min(1),
            _ => return None,
        };
        Some(self.correction + 4 * self.bands * slot)
    }

    /// Takes workspace blocks for the final gather's corrections, zeroed; false (and
    /// nothing taken) when the blocks left cannot hold them.
    pub(crate) fn take_corrections(&mut self, ws: &mut [u8]) -> bool {
        if self.correction != NONE as usize {
            return true;
        }
        let slots = self.patches[0].len as usize + 2 * self.patches[1].len as usize;
        let bytes = 4 * self.bands * slots;
        let size = self.blocks.size.max(1);
        let need = bytes.div_ceil(size);
        if need > (self.blocks.total - self.blocks.used) as usize {
            return false;
        }
        let at = self.blocks.base + self.blocks.used as usize * size;
        ws[at..at + bytes].fill(0);
        self.blocks.used += need as u32;
        self.correction = at;
        self.correction_split = self.patches[0].len;
        true
    }

    /// Byte offset of an element's values.
    fn values_at(&self, ws: &[u8], e: Elem) -> usize {
        self.at(ws, e)
            + match e.kind() {
                Kind::Cluster => core::mem::size_of::<Cluster>(),
                Kind::Source => core::mem::size_of::<Source>(),
                Kind::Instance => core::mem::size_of::<InstanceLeaf>(),
                _ => core::mem::size_of::<Patch>(),
            }
    }

    /// Sides an element keeps values for: 2 for two-sided patches, else 1.
    pub(crate) fn sides(e: Elem) -> usize {
        if e.kind() == Kind::Patch2 { 2 } else { 1 }
    }

    /// Radiosity of side `side` (W/m^2 per band); sources give their irradiance, clusters
    /// their mean radiosity (power over one-sided area; what they emit towards a given
    /// direction is [`super::emission`]). A side an element does not keep is `None` (it
    /// emits nothing).
    pub(crate) fn b<'a>(&self, ws: &'a [u8], e: Elem, side: usize) -> Option<&'a [f32]> {
        if side >= Self::sides(e) {
            return None;
        }
        let nb = self.bands;
        Some(floats(ws, self.values_at(ws, e) + 4 * nb * side, nb))
    }

    pub(crate) fn b_mut<'a>(&self, ws: &'a mut [u8], e: Elem, side: usize) -> &'a mut [f32] {
        let nb = self.bands;
        let at = self.values_at(ws, e) + 4 * nb * side;
        floats_mut(ws, at, nb)
    }

    /// Byte offset of a patch's per-side value set `set` (1: gathered irradiance, 2: direct,
    /// 3: direct through links; 0 is the radiosity, see [`State::b`]) on side `side`.
    fn side_values_at(&self, ws: &[u8], e: Elem, set: usize, side: usize) -> usize {
        let sides = Self::sides(e);
        self.values_at(ws, e) + 4 * self.bands * (set * sides + side.min(sides - 1))
    }

    /// Gathered irradiance of a patch's side `side` (W/m^2 per band): what its own links and
    /// its ancestor patches' links bring (before the closure factor). Clusters and sources
    /// keep none.
    pub(crate) fn h<'a>(&self, ws: &'a [u8], e: Elem, side: usize) -> &'a [f32] {
        floats(ws, self.side_values_at(ws, e, 1, side), self.bands)
    }

    pub(crate) fn h_mut<'a>(&self, ws: &'a mut [u8], e: Elem, side: usize) -> &'a mut [f32] {
        let at = self.side_values_at(ws, e, 1, side);
        floats_mut(ws, at, self.bands)
    }

    /// Direct irradiance of a patch's side from suns and sky (W/m^2 per band), or `None`
    /// when the scene has no directional sources.
    pub(crate) fn direct<'a>(&self, ws: &'a [u8], e: Elem, side: usize) -> Option<&'a [f32]> {
        self.lay
            .strides
            .direct
            .then(|| floats(ws, self.side_values_at(ws, e, 2, side), self.bands))
    }

    pub(crate) fn direct_mut<'a>(
        &self,
        ws: &'a mut [u8],
        e: Elem,
        side: usize,
    ) -> Option<&'a mut [f32]> {
        let at = self.side_values_at(ws, e, 2, side);
        self.lay
            .strides
            .direct
            .then(|| floats_mut(ws, at, self.bands))
    }

    /// The part of [`State::direct`] that came through links of the levels around (see
    /// `Strides::links_apart`), or `None` when it is not kept apart.
    pub(crate) fn linked<'a>(&self, ws: &'a [u8], e: Elem, side: usize) -> Option<&'a [f32]> {
        self.lay
            .strides
            .links_apart
            .then(|| floats(ws, self.side_values_at(ws, e, 3, side), self.bands))
    }

    pub(crate) fn linked_mut<'a>(
        &self,
        ws: &'a mut [u8],
        e: Elem,
        side: usize,
    ) -> Option<&'a mut [f32]> {
        let at = self.side_values_at(ws, e, 3, side);
        self.lay
            .strides
            .links_apart
            .then(|| floats_mut(ws, at, self.bands))
    }

    /// Byte offset of polygon `i`'s record.
    fn polygon_at(&self, i: u32) -> usize {
        self.lay.polygons + i as usize * self.lay.strides.polygon
    }

    /// Irradiance of polygon `i`'s side from the links its clusters receive (W/m^2 per band).
    pub(crate) fn polygon_h<'a>(&self, ws: &'a [u8], i: u32, side: usize) -> &'a [f32] {
        let nb = self.bands;
        let at = self.polygon_at(i) + core::mem::size_of::<Polygon>() + 4 * nb * side.min(1);
        floats(ws, at, nb)
    }

    pub(crate) fn polygon_h_mut<'a>(&self, ws: &'a mut [u8], i: u32, side: usize) -> &'a mut [f32] {
        let nb = self.bands;
        let at = self.polygon_at(i) + core::mem::size_of::<Polygon>() + 4 * nb * side.min(1);
        floats_mut(ws, at, nb)
    }

    /// Polygon `i`'s side radiosity times its exposed area (W per band), as of the last pull.
    pub(crate) fn polygon_power<'a>(&self, ws: &'a [u8], i: u32, side: usize) -> &'a [f32] {
        let nb = self.bands;
        let at = self.polygon_at(i) + core::mem::size_of::<Polygon>() + 4 * nb * (2 + side.min(1));
        floats(ws, at, nb)
    }

    pub(crate) fn polygon_power_mut<'a>(
        &self,
        ws: &'a mut [u8],
        i: u32,
        side: usize,
    ) -> &'a mut [f32] {
        let nb = self.bands;
        let at = self.polygon_at(i) + core::mem::size_of::<Polygon>() + 4 * nb * (2 + side.min(1));
        floats_mut(ws, at, nb)
    }

    pub(crate) fn set_polygon(&self, ws: &mut [u8], i: u32, p: &Polygon) {
        write(ws, self.polygon_at(i), p)
    }

    /// The `k`-th polygon in cluster order (a cluster's polygons are consecutive).
    pub(crate) fn ordered(&self, ws: &[u8], k: u32) -> u32 {
        read(ws, self.lay.order + 4 * k as usize)
    }

    pub(crate) fn set_ordered(&self, ws: &mut [u8], k: u32, poly: u32) {
        write(ws, self.lay.order + 4 * k as usize, &poly)
    }

    /// A cluster's summary of the light it and its ancestors receive (see
    /// `oriented::summarize`).
    pub(crate) fn summary<'a>(&self, ws: &'a [u8], cluster: u32) -> &'a [f32] {
        let at = self.lay.clusters
            + cluster as usize * self.lay.strides.cluster
            + core::mem::size_of::<Cluster>()
            + 4 * self.bands;
        floats(ws, at, super::oriented::summary_floats(self.bands))
    }

    pub(crate) fn summary_mut<'a>(&self, ws: &'a mut [u8], cluster: u32) -> &'a mut [f32] {
        let at = self.lay.clusters
            + cluster as usize * self.lay.strides.cluster
            + core::mem::size_of::<Cluster>()
            + 4 * self.bands;
        floats_mut(ws, at, super::oriented::summary_floats(self.bands))
    }

    /// A link's current flux density per band (see [`Link`]).
    pub(crate) fn link_flux<'a>(&self, ws: &'a [u8], i: u32) -> &'a [f32] {
        let at = self.links.at(ws, &self.blocks, i)
            + core::mem::size_of::<Link>()
            + 4 * self.lay.strides.link_k;
        floats(ws, at, self.bands)
    }

    pub(crate) fn link_flux_mut<'a>(&self, ws: &'a mut [u8], i: u32) -> &'a mut [f32] {
        let at = self.links.at(ws, &self.blocks, i)
            + core::mem::size_of::<Link>()
            + 4 * self.lay.strides.link_k;
        floats_mut(ws, at, self.bands)
    }

    /// The leaf patches of the quadtree under `root`, depth first, children in order.
    pub(crate) fn leaves<'a>(&'a self, ws: &'a [u8], root: Elem) -> Leaves<'a> {
        let mut stack = heapless::Vec::new();
        let _ = stack.push(root.0);
        Leaves {
            st: self,
            ws,
            stack,
        }
    }

    pub(crate) fn patch(&self, ws: &[u8], e: Elem) -> Patch {
        read(ws, self.at(ws, e))
    }

    pub(crate) fn set_patch(&self, ws: &mut [u8], e: Elem, p: &Patch) {
        let at = self.at(ws, e);
        write(ws, at, p)
    }

    pub(crate) fn cluster(&self, ws: &[u8], i: u32) -> Cluster {
        read(
            ws,
            self.lay.clusters + i as usize * self.lay.strides.cluster,
        )
    }

    pub(crate) fn set_cluster(&self, ws: &mut [u8], i: u32, c: &Cluster) {
        write(
            ws,
            self.lay.clusters + i as usize * self.lay.strides.cluster,
            c,
        )
    }

    pub(crate) fn polygon(&self, ws: &[u8], i: u32) -> Polygon {
        read(ws, self.polygon_at(i))
    }

    pub(crate) fn material(&self, ws: &[u8], i: u32) -> Material {
        read(
            ws,
            self.lay.materials + i as usize * core::mem::size_of::<Material>(),
        )
    }

    pub(crate) fn child(&self, ws: &[u8], entry: u32) -> Elem {
        Elem(read(ws, self.lay.children + 4 * entry as usize))
    }

    /// The head of an element's received-link list.
    pub(crate) fn links_head(&self, ws: &[u8], e: Elem) -> u32 {
        match e.kind() {
            Kind::Cluster => self.cluster(ws, e.index()).links,
            Kind::Instance => self.instance(ws, e.index()).links,
            Kind::Source => NONE,
            _ => self.patch(ws, e).links,
        }
    }

    pub(crate) fn set_links_head(&self, ws: &mut [u8], e: Elem, head: u32) {
        match e.kind() {
            Kind::Cluster => {
                let mut c = self.cluster(ws, e.index());
                c.links = head;
                self.set_cluster(ws, e.index(), &c);
            }
            Kind::Source => {}
            Kind::Instance => {
                let mut c = self.instance(ws, e.index());
                c.links = head;
                self.set_instance(ws, e.index(), &c);
            }
            _ => {
                let mut p = self.patch(ws, e);
                p.links = head;
                self.set_patch(ws, e, &p);
            }
        }
    }

    pub(crate) fn link(&self, ws: &[u8], i: u32) -> Link {
        read(ws, self.links.at(ws, &self.blocks, i))
    }

    pub(crate) fn set_link(&self, ws: &mut [u8], i: u32, l: &Link) {
        let at = self.links.at(ws, &self.blocks, i);
        write(ws, at, l)
    }

    /// A link's coefficients (`link_k` of them).
    pub(crate) fn link_k<'a>(&self, ws: &'a [u8], i: u32) -> &'a [f32] {
        let at = self.links.at(ws, &self.blocks, i) + core::mem::size_of::<Link>();
        floats(ws, at, self.lay.strides.link_k)
    }

    pub(crate) fn link_k_mut<'a>(&self, ws: &'a mut [u8], i: u32) -> &'a mut [f32] {
        let at = self.links.at(ws, &self.blocks, i) + core::mem::size_of::<Link>();
        floats_mut(ws, at, self.lay.strides.link_k)
    }

    /// Geometry of an element.
    pub(crate) fn shape(&self, ws: &[u8], e: Elem) -> Shape {
        match e.kind() {
            Kind::Cluster => {
                let c = self.cluster(ws, e.index());
                Shape::Cluster {
                    min: c.bbox_min.into(),
                    max: c.bbox_max.into(),
                    area: c.area,
                }
            }
            Kind::Source => {
                let s: Source = read(ws, self.at(ws, e));
                Shape::Source {
                    towards: s.towards.into(),
                }
            }
            Kind::Instance => {
                let c = self.instance(ws, e.index());
                Shape::Instance {
                    index: e.index(),
                    min: c.bbox_min.into(),
                    max: c.bbox_max.into(),
                    area_ref: c.area_ref,
                }
            }
            k => {
                let p = self.patch(ws, e);
                let poly = self.polygon(ws, p.poly);
                let mut corners = [Vec3::ZERO; 4];
                for (c, src) in corners.iter_mut().zip(p.corners) {
                    *c = src.into();
                }
                Shape::Patch {
                    corners,
                    n: p.corner_count(),
                    normal: poly.normal.into(),
                    poly: p.poly,
                    area: p.area,
                    two_sided: k == Kind::Patch2,
                }
            }
        }
    }

    /// The `skip` of a ray from polygon `poly` towards source `k`: the polygon, and how far
    /// the ray goes through the levels an opened instance lies in (see `records::Source`).
    pub(crate) fn source_skip(&self, ws: &[u8], k: u32, poly: u32) -> [u32; 2] {
        let src: Source = read(ws, self.at(ws, Elem::new(Kind::Source, k)));
        [poly, super::vis::depth_entry(src.outer)]
    }

    /// Bytes of the workspace in use: the static part and the blocks handed out.
    pub(crate) fn bytes_in_use(&self) -> usize {
        self.lay.static_bytes + self.blocks.used as usize * self.blocks.size
    }

    /// Every receiver, in the fixed order the solver walks them: clusters, one-sided
    /// patches, two-sided patches.
    pub(crate) fn receiver_count(&self) -> u64 {
        self.clusters as u64 + self.patches[0].len as u64 + self.patches[1].len as u64
    }

    /// The `i`-th receiver in that order.
    pub(crate) fn receiver(&self, i: u64) -> Elem {
        let c = self.clusters as u64;
        let p1 = self.patches[0].len as u64;
        if i < c {
            Elem::new(Kind::Cluster, i as u32)
        } else if i < c + p1 {
            Elem::new(Kind::Patch1, (i - c) as u32)
        } else {
            Elem::new(Kind::Patch2, (i - c - p1) as u32)
        }
    }
}

/// See [`State::leaves`]. Depth first: at most 3 pending siblings per level.
pub(crate) struct Leaves<'a> {
    st: &'a State,
    ws: &'a [u8],
    stack: heapless::Vec<u32, 256>,
}

impl Iterator for Leaves<'_> {
    type Item = (Elem, Patch);

    fn next(&mut self) -> Option<(Elem, Patch)> {
        while let Some(raw) = self.stack.pop() {
            let e = Elem(raw);
            let p = self.st.patch(self.ws, e);
            if p.first_child == NONE {
                return Some((e, p));
            }
            for j in (0..4).rev() {
                let _ = self.stack.push(Elem::new(e.kind(), p.first_child + j).0);
            }
        }
        None
    }
}
