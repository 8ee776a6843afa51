//! Where everything lives in the workspace, computed the same way for planning and for
//! solving, so that a plan is exact.
//!
//! Static regions (sized from the census): materials, input polygons, clusters with their
//! values, child lists, sources, the loading stack, grouping scratch, the executor's scratch
//! and the block tables. The rest is cut into blocks shared by the growing pools.

use super::census::Census;
use super::records::*;

/// Growing pools sharing the blocks: one-sided patches, two-sided patches, links, emission
/// bins of large clusters.
pub(crate) const POOLS: usize = 4;

/// Alignment of every region (bytes).
pub(crate) const ALIGN: usize = 16;

pub(crate) fn up(x: usize) -> usize {
    x.div_ceil(ALIGN) * ALIGN
}

/// Bytes of one loading-stack frame.
pub(crate) const FRAME_BYTES: usize = 64;
/// Bytes per grouping item (element id + centroid).
pub(crate) const GROUP_ITEM_BYTES: usize = 16;
/// Links evaluated or receivers gathered per chunk of work (fixed: results never depend on
/// how many threads share the chunks).
pub(crate) const CHUNK: usize = 64;
/// Items per chunk in the phases where one item costs many rays (lighting a patch,
/// evaluating a link) and only the new ones are worked on: after a refinement pass they can
/// be a few hundred, and chunks of 64 would leave threads idle.
pub(crate) const FINE_CHUNK: usize = 8;

/// Record strides of a scene.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Strides {
    pub bands: usize,
    /// True when the scene has suns or sky directions: patches keep their direct light.
    pub direct: bool,
    /// True when patches also keep apart the part of their direct light that came through
    /// links (an opened instance's level: sources lit by links of the levels around it,
    /// whose light its final gather reads through those levels instead, see
    /// `final_gather`).
    pub links_apart: bool,
    pub polygon: usize,
    pub cluster: usize,
    pub patch1: usize,
    pub patch2: usize,
    pub source: usize,
    pub instance: usize,
    pub link: usize,
    /// Coefficients per link: 1 without two-sided materials, 4 with.
    pub link_k: usize,
    /// A large cluster's emission bins (see `bins`).
    pub bins: usize,
}

impl Strides {
    pub(crate) fn new(
        bands: usize,
        any_two_sided: bool,
        sources: bool,
        links_apart: bool,
    ) -> Strides {
        let link_k = if any_two_sided { 4 } else { 1 };
        let links_apart = sources && links_apart;
        // Per side: radiosity, gathered irradiance and, with sources, direct irradiance (and
        // its part through links).
        let per_side = 4
            * bands
            * if links_apart {
                4
            } else if sources {
                3
            } else {
                2
            };
        Strides {
            bands,
            direct: sources,
            links_apart,
            polygon: core::mem::size_of::<Polygon>() + 16 * bands,
            cluster: core::mem::size_of::<Cluster>()
                + 4 * bands
                + 4 * super::oriented::summary_floats(bands),
            patch1: core::mem::size_of::<Patch>() + per_side,
            patch2: core::mem::size_of::<Patch>() + 2 * per_side,
            source: core::mem::size_of::<Source>() + 4 * bands,
            instance: core::mem::size_of::<InstanceLeaf>(),
            link: core::mem::size_of::<Link>() + 4 * link_k + 4 * bands,
            link_k,
            bins: 4 * super::bins::bin_floats(bands),
        }
    }

    /// Floats an evaluated link hands back: its coefficients, the open coefficient, the
    /// partial-visibility flag, the rays cast, the light's mean direction, the spread, the
    /// exact flag, the refinement's visible coefficient and the two witnesses.
    pub(crate) fn eval_out(&self) -> usize {
        self.link_k + 11
    }

    /// Floats a gathered receiver hands back: irradiance per side and band.
    pub(crate) fn gather_out(&self) -> usize {
        2 * self.bands
    }

    /// Floats a prepared patch hands back: its buried points, exposure, shadow measure,
    /// direct irradiance per side and band, the rays cast, and the direct irradiance's part
    /// through links per side and band.
    pub(crate) fn prepare_out(&self) -> usize {
        4 + if self.links_apart { 4 } else { 2 } * self.bands
    }
}

/// Byte offsets of the static regions and the block area.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Layout {
    pub strides: Strides,
    pub materials: usize,
    pub polygons: usize,
    /// The cluster-order array: polygon indices, each cluster's consecutive.
    pub order: usize,
    pub clusters: usize,
    pub children: usize,
    pub sources: usize,
    pub stack: usize,
    pub group: usize,
    /// The executor's scratch: the last `scratch_floats` floats of the workspace, after
    /// `main_bytes`.
    pub scratch_floats: usize,
    /// Bytes before the BVH and the scratch (everything else lives there).
    pub main_bytes: usize,
    /// Bytes of the core's own BVH (nodes, then primitive order), after `main_bytes`; 0 when
    /// the caller brings its own visibility.
    pub bvh_bytes: usize,
    pub tables: [usize; POOLS],
    pub blocks_base: usize,
    pub block_size: usize,
    pub block_count: u32,
    /// Bytes before the blocks (tables and scratch included).
    pub static_bytes: usize,
    /// Bytes of the static regions alone (without block tables and scratch).
    pub fixed_bytes: usize,
    /// Closed instances (records), their cluster order, the light they receive, the table
    /// slots of their originals, each original's slot (NONE without closed instances), and
    /// the tables' values and visible fractions.
    pub instances: usize,
    pub instance_order: usize,
    pub received: usize,
    pub slots: usize,
    pub slot_map: usize,
    pub table_values: usize,
    pub table_visible: usize,
    pub table_bytes_end: usize,
    /// The polygons and BVHs of the originals whose closed instances block with them (see
    /// `original_geometry`), and its end.
    pub blocking: usize,
    pub blocking_end: usize,
    /// The BVH over the closed instances' boxes (see `blockers`).
    pub closed_bvh: usize,
    /// Per closed instance and source, `tau` towards the source (see `blockers`).
    pub source_tau: usize,
    /// The light between closed instances (see `exchange`).
    pub exchange: usize,
    /// Whether any closed instance may send light through the exchange (some block with
    /// polygons): without, its region keeps no rays (see `exchange::bytes_needed`).
    pub exchange_sends: bool,
    /// Per closed instance, direction cell and band, the radiosity its contents show an
    /// observer that way (see `blockers::note_radiance`).
    pub radiance: usize,
    /// An opened level's light by place, read for closed siblings' polygons met inside it
    /// (see `local_field`).
    pub local_field: usize,
    /// Counts the regions were sized for.
    pub n_clusters: u32,
    pub n_polygons: u32,
    pub n_instances: u32,
}

impl Layout {
    /// Table slots the layout holds.
    pub(crate) fn n_slots(&self) -> u32 {
        ((self.slot_map - self.slots) / core::mem::size_of::<TableSlot>()) as u32
    }

    /// Floats of table values the layout holds.
    pub(crate) fn n_table_floats(&self) -> usize {
        (self.table_visible - self.table_values) / 4
    }

    /// Bytes of visible fractions the layout holds.
    pub(crate) fn n_table_bytes(&self) -> usize {
        self.table_bytes_end - self.table_visible
    }

    /// The workspace by what it holds, `blocks_used` blocks handed out and
    /// `exchange_written` bytes of the exchange's region written.
    pub(crate) fn regions(
        &self,
        blocks_used: u32,
        exchange_written: usize,
    ) -> super::settings::WorkspaceRegions {
        let b = |from: usize, to: usize| to.saturating_sub(from) as u64;
        super::settings::WorkspaceRegions {
            scene: b(self.materials, self.instances) + b(self.sources, self.fixed_bytes),
            instances: b(self.instances, self.received) + b(self.closed_bvh, self.exchange),
            received: b(self.received, self.slots),
            tables: b(self.slots, self.table_bytes_end),
            blocking: b(self.blocking, self.blocking_end),
            exchange: b(self.exchange, self.radiance),
            exchange_written: exchange_written as u64,
            radiance: b(self.radiance, self.sources),
            blocks: b(self.fixed_bytes, self.blocks_base)
                + blocks_used as u64 * self.block_size as u64,
            bvh_scratch: (self.bvh_bytes + 4 * self.scratch_floats) as u64,
        }
    }

    /// Floats of received light the layout holds.
    pub(crate) fn n_received_floats(&self) -> usize {
        (self.slots - self.received) / 4
    }
}

/// Block size for a workspace of `bytes`: about 1/256 of the dynamic space, within
/// 4 KiB..256 KiB, a power of two.
fn block_size(dynamic: usize) -> usize {
    let target = (dynamic / 256).clamp(4096, 256 * 1024);
    let mut b = 4096;
    while b * 2 <= target {
        b *= 2;
    }
    b
}

impl Layout {
    /// Lays out a workspace of `total` bytes for a scene; `None` if the static part alone
    /// does not fit (or counts overflow).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        census: &Census,
        materials: u32,
        originals: u32,
        sources: u32,
        bands: usize,
        links_apart: bool,
        internal_bvh: bool,
        total: usize,
    ) -> Option<Layout> {
        let any_two = census.polys_two_sided > 0;
        let strides = Strides::new(bands, any_two, sources > 0, links_apart);
        let n_clusters = u32::try_from(census.clusters)
            .ok()
            .filter(|&c| c <= super::ids::Elem::MAX_INDEX)?;
        let n_polygons = u32::try_from(census.polygons())
            .ok()
            .filter(|&p| p <= super::ids::Elem::MAX_INDEX)?;
        let n_instances = u32::try_from(census.instances)
            .ok()
            .filter(|&p| p <= super::ids::Elem::MAX_INDEX)?;
        let received_floats = u32::try_from(census.received_floats).ok()?;
        let closing = census.instances > 0;
        let mut at = 0usize;
        let mut region = |bytes: usize| -> Option<usize> {
            let start = at;
            at = at.checked_add(up(bytes))?;
            Some(start)
        };
        let materials_at = region(materials as usize * core::mem::size_of::<Material>())?;
        let polygons_at = region((n_polygons as usize).checked_mul(strides.polygon)?)?;
        let order_at = region(n_polygons as usize * 4)?;
        let clusters_at = region((n_clusters as usize).checked_mul(strides.cluster)?)?;
        let children_at =
            region((n_clusters as usize + n_polygons as usize + n_instances as usize) * 4)?;
        let instances_at = region((n_instances as usize).checked_mul(strides.instance)?)?;
        let instance_order_at = region(n_instances as usize * 4)?;
        let received_at = region((received_floats as usize).checked_mul(4)?)?;
        let slots_at = region(
            (census.closed_originals as usize).checked_mul(core::mem::size_of::<TableSlot>())?,
        )?;
        let slot_map_at = region(if closing { originals as usize * 4 } else { 0 })?;
        let table_values_at = region(usize::try_from(census.table_floats).ok()?.checked_mul(4)?)?;
        let table_visible_at = region(usize::try_from(census.table_bytes).ok()?)?;
        let table_bytes_end = region(0)?;
        let blocking_at = region(usize::try_from(census.blocking_bytes).ok()?)?;
        let blocking_end = region(0)?;
        let closed_bvh_at = region(super::blockers::bytes_needed(n_instances))?;
        let source_tau_at = region(
            (n_instances as usize)
                .checked_mul(sources as usize)?
                .checked_mul(4)?,
        )?;
        let exchange_sends = census.blocking_bytes > 0;
        let exchange_at = region(super::exchange::bytes_needed(
            n_instances,
            bands,
            exchange_sends,
        ))?;
        let radiance_at = region(super::blockers::radiance_bytes(n_instances, bands))?;
        let local_field_at = region(super::local_field::bytes_needed(bands))?;
        let sources_at = region(sources as usize * strides.source)?;
        let stack_at = region((census.depth as usize + 1) * FRAME_BYTES)?;
        let group_at = region((census.max_children as usize + 1) * GROUP_ITEM_BYTES)?;
        let scratch_floats = (CHUNK
            * strides
                .eval_out()
                .max(strides.gather_out())
                .max(strides.prepare_out())
                .max(strides.bands))
        .max(super::blockers::radiance_chunk_floats(strides.bands));
        let before_tables = at;
        let bvh_bytes = if internal_bvh {
            up(crate::bvh::bytes_needed(n_polygons))
        } else {
            0
        };
        let total = total
            .checked_sub(up(scratch_floats * 4))?
            .checked_sub(bvh_bytes)?
            / ALIGN
            * ALIGN;
        if before_tables > total {
            return None;
        }
        // Blocks and their tables share what is left: each block costs its bytes plus one
        // table entry in each pool.
        let dynamic = total - before_tables;
        let size = block_size(dynamic);
        let mut count = (dynamic / (size + 4 * POOLS)) as u32;
        loop {
            let tables = POOLS * up(count as usize * 4);
            if before_tables + tables + count as usize * size <= total || count == 0 {
                break;
            }
            count -= 1;
        }
        let table_bytes = up(count as usize * 4);
        let tables = core::array::from_fn(|k| before_tables + k * table_bytes);
        let blocks_base = before_tables + POOLS * table_bytes;
        Some(Layout {
            strides,
            materials: materials_at,
            polygons: polygons_at,
            order: order_at,
            clusters: clusters_at,
            children: children_at,
            sources: sources_at,
            stack: stack_at,
            group: group_at,
            scratch_floats,
            main_bytes: total,
            bvh_bytes,
            tables,
            blocks_base,
            block_size: size,
            block_count: count,
            static_bytes: blocks_base + up(scratch_floats * 4) + bvh_bytes,
            fixed_bytes: before_tables,
            instances: instances_at,
            instance_order: instance_order_at,
            received: received_at,
            slots: slots_at,
            slot_map: slot_map_at,
            table_values: table_values_at,
            table_visible: table_visible_at,
            table_bytes_end,
            blocking: blocking_at,
            blocking_end,
            closed_bvh: closed_bvh_at,
            source_tau: source_tau_at,
            exchange: exchange_at,
            exchange_sends,
            radiance: radiance_at,
            local_field: local_field_at,
            n_clusters,
            n_polygons,
            n_instances,
        })
    }
}
