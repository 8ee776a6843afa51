//! Loading the expanded scene into the workspace: materials, sources, one cluster per scene
//! node (exact instances replaced by their original's tree, approximate ones by their own),
//! grouping levels under crowded clusters, and one root patch per input polygon, in global-id
//! order. Clusters are numbered so that a parent always comes before its children: the
//! push-pull passes are then plain forward and backward loops.

use super::census::Census;
use super::error::HrError;
use super::group::Item;
use super::ids::{Elem, Kind};
use super::layout::{FRAME_BYTES, GROUP_ITEM_BYTES, Layout};
use super::pool::{Blocks, Pool, read, write};
use super::records::*;
use super::settings::{Inline, Instancing, Settings, Stats};
use super::state::State;
use crate::geometry::{Aabb, Similarity, polygon_shape};
use crate::image::{SceneSource, SceneView};
use crate::limits::{MAX_BANDS, NONE};
use crate::material::MaterialData;
use crate::{LightId, MaterialId, NodeId, PolyId, VertexId};
use bytemuck::{Pod, Zeroable};
use glam::{Quat, Vec3};

/// A node whose children are being loaded.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct Frame {
    /// Next child node to visit.
    next: u32,
    /// End of the node's subtree.
    end: u32,
    /// Cluster index for the next child node.
    next_cluster: u32,
    /// The instance expanded in place the node lies in (see `InstanceLeaf::pass`).
    pass: u32,
    rotation: [f32; 4],
    translation: [f32; 3],
    scale: f32,
}

const _: () = assert!(core::mem::size_of::<Frame>() <= FRAME_BYTES);

#[allow(clippy::too_many_arguments)]
pub(crate) fn load<S: SceneSource>(
    view: &SceneView<S>,
    settings: &Settings,
    instancing: Instancing,
    level: &super::level::LevelRoot<'_>,
    census: &Census,
    lay: Layout,
    ws: &mut [u8],
) -> Result<State, HrError> {
    let info = *view.info();
    let bands = info.bands as usize;
    let blocks = Blocks {
        base: lay.blocks_base,
        size: lay.block_size,
        total: lay.block_count,
        used: 0,
    };
    let st = lay.strides;
    let mut s = State {
        lay,
        blocks,
        patches: [
            Pool::new(st.patch1, &blocks, lay.tables[0]),
            Pool::new(st.patch2, &blocks, lay.tables[1]),
        ],
        links: Pool::new(st.link, &blocks, lay.tables[2]),
        bins: Pool::new(st.bins, &blocks, lay.tables[3]),
        settings: *settings,
        bands,
        clusters: 0,
        polygons: 0,
        child_entries: 0,
        power: 0.0,
        unit_power: 0.0,
        scene_sides: 0,
        most_passes: level.most_passes,
        suns: level.suns(view),
        sources: level.sources(view),
        typical_area: 0.0,
        min_area: 0.0,
        far: 0.0,
        contraction: f32::INFINITY,
        prepared: [0; 2],
        pending: (u32::MAX, 0),
        pending_links: 0,
        touched: [(0, u32::MAX); 4],
        shadow_checked: [0; 2],
        correction: NONE as usize,
        correction_split: 0,
        closed: false,
        sees_backs: false,
        instancing,
        instances: 0,
        slots: 0,
        table_floats: 0,
        table_bytes: 0,
        received_floats: 0,
        blocking_bytes: 0,
        own_blocking: census.own_polygons > 0,
        instance_change: (0.0, 0.0),
        scene_min: Vec3::ZERO,
        scene_max: Vec3::ZERO,
        stats: Stats {
            polygons: census.polygons(),
            ..Stats::default()
        },
    };
    // Materials.
    for m in 0..info.materials {
        let d = view.material(MaterialId(m))?;
        let rec = material_record(&d);
        write(
            ws,
            lay.materials + m as usize * core::mem::size_of::<Material>(),
            &rec,
        );
    }
    // No iteration shrinks the change by less than the largest albedo (a side gives back
    // at most rho + tau of what reaches it, and a leaf's coefficients sum to at most 1):
    // the first solution's convergence test starts from that bound.
    let mut albedo = 0.0f32;
    for m in 0..info.materials {
        let rec: Material = read(
            ws,
            lay.materials + m as usize * core::mem::size_of::<Material>(),
        );
        for b in 0..bands {
            for side in 0..2 {
                albedo = albedo.max(rec.rho[side][b] + rec.tau[b]);
            }
        }
    }
    if albedo < 1.0 {
        s.contraction = albedo;
    }
    // Sources: suns, then sky directions (or the beams of an opened instance).
    let beam = super::level::beam_floats(bands);
    for k in 0..s.sources {
        let l = match level.beams {
            None if k < info.suns => view.sun(LightId(k))?,
            None => view.sky(LightId(k - info.suns))?,
            Some((b, _)) => {
                let v = &b[k as usize * beam..(k as usize + 1) * beam];
                let mut irradiance = [0.0f32; MAX_BANDS];
                irradiance[..bands].copy_from_slice(&v[4..]);
                crate::image::LightData {
                    towards: Vec3::new(v[0], v[1], v[2]),
                    irradiance,
                }
            }
        };
        let e = Elem::new(Kind::Source, k);
        let at = s.at(ws, e);
        write(
            ws,
            at,
            &Source {
                towards: l.towards.to_array(),
                outer: match level.beams {
                    None => NONE,
                    Some((b, _)) => super::level::beam_outer(b, k as usize, bands),
                },
            },
        );
        s.b_mut(ws, e, 0).copy_from_slice(&l.irradiance[..bands]);
    }
    if lay.n_instances > 0 {
        for k in 0..info.originals as usize {
            write(ws, lay.slot_map + 4 * k, &NONE);
        }
    }
    load_tree(view, &mut s, ws, level)?;
    finish_clusters(&mut s, ws);
    cluster_order(&mut s, ws);
    super::blockers::build(&s, ws)?;
    super::blockers::note_source_tau(&s, ws);
    let n_sources = s.sources;
    totals(&mut s, ws, n_sources);
    if s.power.is_nan() || s.power <= 0.0 {
        return Err(HrError::NoLight);
    }
    // The initial link: a self-link on the root. Suns and sky light every patch directly
    // (see `direct`).
    let root = Elem::new(Kind::Cluster, 0);
    super::refine::add_link(&mut s, ws, root, root, 0)
        .ok_or(HrError::WorkspaceTooSmall { needed: 0 })?;
    Ok(s)
}

fn material_record(d: &MaterialData) -> Material {
    let mut m = Material::zeroed();
    let n = d.bands as usize;
    m.rho[0][..n].copy_from_slice(&d.rho_front[..n]);
    m.emit[0][..n].copy_from_slice(&d.emit_front[..n]);
    if d.two_sided {
        m.rho[1][..n].copy_from_slice(&d.rho_back[..n]);
        m.emit[1][..n].copy_from_slice(&d.emit_back[..n]);
        m.tau[..n].copy_from_slice(&d.tau[..n]);
        m.two_sided = 1;
    }
    let _ = MAX_BANDS;
    m
}

fn frame_at(lay: &Layout, depth: usize) -> usize {
    lay.stack + depth * FRAME_BYTES
}

fn new_cluster(s: &mut State, ws: &mut [u8], parent: u32) -> Result<u32, HrError> {
    if s.clusters >= s.lay.n_clusters {
        return Err(HrError::SceneTooLarge);
    }
    let i = s.clusters;
    s.clusters += 1;
    let c = Cluster {
        bbox_min: [0.0; 3],
        bbox_max: [0.0; 3],
        parent,
        children: 0,
        child_count: 0,
        links: NONE,
        area: 0.0,
        polygons: 0,
        first_polygon: 0,
        bins: NONE,
        peak: 0.0,
        emitted: 0.0,
        instances: 0,
        first_instance: 0,
    };
    s.set_cluster(ws, i, &c);
    let e = Elem::new(Kind::Cluster, i);
    s.b_mut(ws, e, 0).fill(0.0);
    Ok(i)
}

/// Walks the expanded scene depth-first and creates clusters and root patches.
fn load_tree<S: SceneSource>(
    view: &SceneView<S>,
    s: &mut State,
    ws: &mut [u8],
    level: &super::level::LevelRoot<'_>,
) -> Result<(), HrError> {
    let lay = s.lay;
    let root = new_cluster(s, ws, NONE)?;
    let mut depth = 0usize;
    // Instances expanded in place so far, in the order entered (see `InstanceLeaf::pass`).
    let mut passes = 0u32;
    let inline = level.inline;
    open_node(view, s, ws, inline, level.node, root, level.place, 0, depth)?;
    loop {
        let at = frame_at(&lay, depth);
        let mut f: Frame = read(ws, at);
        if f.next >= f.end {
            if depth == 0 {
                break;
            }
            depth -= 1;
            continue;
        }
        let child = f.next;
        let rec = view.node(NodeId(child))?;
        f.next = rec.subtree_end;
        if super::load_instances::closes(view, s, inline, &rec)? {
            // A closed instance: its leaf was made with its parent's children.
            write(ws, at, &f);
            continue;
        }
        let cluster = f.next_cluster;
        f.next_cluster += 1;
        write(ws, at, &f);
        let t = Similarity {
            rotation: Quat::from_array(f.rotation),
            translation: f.translation.into(),
            scale: f.scale,
        };
        let (node, t) = effective(view, child, &t)?;
        let pass = if rec.instance().is_some() {
            passes += 1;
            passes
        } else {
            f.pass
        };
        depth += 1;
        if frame_at(&lay, depth) + FRAME_BYTES > lay.group {
            return Err(HrError::SceneTooLarge);
        }
        open_node(view, s, ws, inline, node, cluster, t, pass, depth)?;
    }
    Ok(())
}

/// The tree node whose content stands for `node`, and the transform to world: an exact
/// instance is its original's root, placed by the instance.
fn effective<S: SceneSource>(
    view: &SceneView<S>,
    node: u32,
    t: &Similarity,
) -> Result<(u32, Similarity), HrError> {
    let rec = view.node(NodeId(node))?;
    match rec.instance() {
        None => Ok((node, *t)),
        Some(id) => {
            let inst = view.instance(id)?;
            let world = t.compose(&inst.transform());
            if inst.is_exact() {
                Ok((view.original(inst.original())?.root, world))
            } else {
                Ok((node, world))
            }
        }
    }
}

/// Loads a node's own polygons into root patches, reserves clusters for its child nodes
/// (closed instances among them become leaves at once, named by `pass`, see
/// `InstanceLeaf::pass`), groups the children, and pushes the frame that will visit the
/// child nodes.
#[allow(clippy::too_many_arguments)]
fn open_node<S: SceneSource>(
    view: &SceneView<S>,
    s: &mut State,
    ws: &mut [u8],
    inline: Inline<'_>,
    node: u32,
    cluster: u32,
    t: Similarity,
    pass: u32,
    depth: usize,
) -> Result<(), HrError> {
    let lay = s.lay;
    let rec = view.node(NodeId(node))?;
    let mut n_items = 0u32;
    let item_at = |k: u32| lay.group + k as usize * GROUP_ITEM_BYTES;
    // Own polygons, in order: their global ids are assigned here.
    for p in 0..rec.poly_count {
        let mut pr = [crate::image::PolygonRecord::default()];
        view.polygons(PolyId(rec.poly_first + p), &mut pr)?;
        let poly = pr[0];
        let n = poly.corner_count();
        let mut corners = [Vec3::ZERO; 4];
        for (c, corner) in corners.iter_mut().enumerate().take(n) {
            let mut v = [[0.0f32; 3]];
            view.vertices(VertexId(rec.vert_first + poly.corners[c]), &mut v)?;
            *corner = t.point(v[0].into());
        }
        let e = add_root_patch(s, ws, &corners[..n], poly.material, cluster)?;
        let centroid = corners[..n].iter().copied().sum::<Vec3>() / n as f32;
        write(
            ws,
            item_at(n_items),
            &Item {
                elem: e.0,
                centroid: centroid.to_array(),
            },
        );
        n_items += 1;
    }
    // Child nodes: count them and note their centres (from their stored boxes).
    let mut child_nodes = 0u32;
    let mut j = node + 1;
    while j < rec.subtree_end {
        let c = view.node(NodeId(j))?;
        // A closed instance is a leaf at once; other nodes get clusters below.
        let (elem, centre) = if super::load_instances::closes(view, s, inline, &c)? {
            let e = super::load_instances::add_instance(view, s, ws, j, pass, &t)?;
            let leaf = s.instance(ws, e.index());
            let b = Aabb::new(leaf.bbox_min.into(), leaf.bbox_max.into());
            (e.0, b.center())
        } else {
            let b = t.aabb(&Aabb::new(c.bbox_min.into(), c.bbox_max.into()));
            (0, b.center())
        };
        write(
            ws,
            item_at(n_items + child_nodes),
            &Item {
                elem,
                centroid: centre.to_array(),
            },
        );
        child_nodes += 1;
        j = c.subtree_end;
    }
    // Grouping levels first, then the child nodes' clusters: parents before children.
    let total = n_items + child_nodes;
    let groups = super::census::grouping_clusters(total as u64, s.settings.max_children) as u32;
    let first_group = s.clusters;
    for _ in 0..groups {
        new_cluster(s, ws, cluster)?;
    }
    let first_child_cluster = s.clusters;
    for k in 0..child_nodes {
        let at = item_at(n_items + k);
        let mut it: Item = read(ws, at);
        if Elem(it.elem).kind() == Kind::Instance {
            continue;
        }
        let c = new_cluster(s, ws, cluster)?;
        it.elem = Elem::new(Kind::Cluster, c).0;
        write(ws, at, &it);
    }
    super::group::group(s, ws, cluster, total, first_group, groups)?;
    let f = Frame {
        next: node + 1,
        end: rec.subtree_end,
        next_cluster: first_child_cluster,
        pass,
        rotation: t.rotation.to_array(),
        translation: t.translation.to_array(),
        scale: t.scale,
    };
    write(ws, frame_at(&lay, depth), &f);
    Ok(())
}

fn add_root_patch(
    s: &mut State,
    ws: &mut [u8],
    corners: &[Vec3],
    material: u32,
    parent: u32,
) -> Result<Elem, HrError> {
    let shape = polygon_shape(corners).map_err(|_| HrError::BadGeometry {
        polygon: s.polygons as u64,
    })?;
    let m = s.material(ws, material);
    let kind = if m.two_sided != 0 {
        Kind::Patch2
    } else {
        Kind::Patch1
    };
    let pool = if kind == Kind::Patch2 { 1 } else { 0 };
    let mut blocks = s.blocks;
    let i = s.patches[pool]
        .alloc_run(ws, &mut blocks, 1)
        .ok_or(HrError::WorkspaceTooSmall { needed: 0 })?;
    s.blocks = blocks;
    let e = Elem::new(kind, i);
    let poly = s.polygons;
    s.polygons += 1;
    let mut c = [[0.0f32; 3]; 4];
    for (d, src) in c.iter_mut().zip(corners) {
        *d = src.to_array();
    }
    let p = Patch {
        corners: c,
        parent: Elem::new(Kind::Cluster, parent).0,
        first_child: NONE,
        poly,
        links: NONE,
        area: shape.area,
        shape: corners.len() as u32 | UNPREPARED,
        closure: [0.0; 2],
        exposed: 1.0,
        shadow: 0.0,
        gather: [0; 2],
    };
    s.set_patch(ws, e, &p);
    for side in 0..State::sides(e) {
        let b = s.b_mut(ws, e, side);
        b.copy_from_slice(&m.emit[side][..b.len()]);
        s.h_mut(ws, e, side).fill(0.0);
        if let Some(d) = s.direct_mut(ws, e, side) {
            d.fill(0.0);
        }
        if let Some(d) = s.linked_mut(ws, e, side) {
            d.fill(0.0);
        }
    }
    let rec = Polygon {
        normal: shape.normal.to_array(),
        material,
        root: e.0,
    };
    s.set_polygon(ws, poly, &rec);
    for side in 0..2 {
        s.polygon_h_mut(ws, poly, side).fill(0.0);
        let power = s.polygon_power_mut(ws, poly, side);
        for (p, &em) in power.iter_mut().zip(&m.emit[side.min(State::sides(e) - 1)]) {
            *p = if side < State::sides(e) {
                em * shape.area
            } else {
                0.0
            };
        }
    }
    Ok(e)
}

/// Boxes, areas, polygon counts and emitted powers of clusters, children before parents.
fn finish_clusters(s: &mut State, ws: &mut [u8]) {
    for i in (0..s.clusters).rev() {
        let mut c = s.cluster(ws, i);
        let mut b = Aabb::EMPTY;
        let (mut area, mut polys, mut emitted) = (0.0f32, 0u32, 0.0f32);
        let mut instances = 0u32;
        for k in 0..c.child_count {
            let e = s.child(ws, c.children + k);
            match e.kind() {
                Kind::Cluster => {
                    let cc = s.cluster(ws, e.index());
                    if cc.polygons > 0 || cc.instances > 0 {
                        b = b.union(Aabb::new(cc.bbox_min.into(), cc.bbox_max.into()));
                    }
                    area += cc.area;
                    polys += cc.polygons;
                    emitted += cc.emitted;
                    instances += cc.instances;
                }
                Kind::Instance => {
                    let leaf = s.instance(ws, e.index());
                    b = b.union(Aabb::new(leaf.bbox_min.into(), leaf.bbox_max.into()));
                    instances += 1;
                    // Its equivalent surface: a quarter of its reference area.
                    area += 0.25 * leaf.area_ref;
                }
                _ => {
                    let p = s.patch(ws, e);
                    for corner in &p.corners[..p.corner_count()] {
                        b.include((*corner).into());
                    }
                    area += p.area;
                    polys += 1;
                    emitted += polygon_emission(s, ws, p.poly);
                }
            }
        }
        if b.is_empty() {
            b = Aabb::new(Vec3::ZERO, Vec3::ZERO);
        }
        c.bbox_min = b.min.to_array();
        c.bbox_max = b.max.to_array();
        c.area = area;
        c.polygons = polys;
        c.emitted = emitted;
        c.instances = instances;
        s.set_cluster(ws, i, &c);
    }
}

/// The power polygon `poly` emits (W, the sides it has, the largest band).
pub(crate) fn polygon_emission(s: &State, ws: &[u8], poly: u32) -> f32 {
    let rec = s.polygon(ws, poly);
    let m = s.material(ws, rec.material);
    let root = Elem(rec.root);
    let area = s.patch(ws, root).area;
    let sides = State::sides(root);
    (0..s.bands)
        .map(|b| area * (0..sides).map(|k| m.emit[k][b]).sum::<f32>())
        .fold(0.0f32, f32::max)
}

/// Each cluster's polygons, consecutive in the cluster-order array: parents are numbered
/// before their children, so walking clusters in order places every child range inside its
/// parent's.
fn cluster_order(s: &mut State, ws: &mut [u8]) {
    for i in 0..s.clusters {
        let c = s.cluster(ws, i);
        let mut at = c.first_polygon;
        let mut at_instance = c.first_instance;
        for k in 0..c.child_count {
            let e = s.child(ws, c.children + k);
            if e.kind() == Kind::Cluster {
                let mut cc = s.cluster(ws, e.index());
                cc.first_polygon = at;
                at += cc.polygons;
                cc.first_instance = at_instance;
                at_instance += cc.instances;
                s.set_cluster(ws, e.index(), &cc);
            } else if e.kind() == Kind::Instance {
                write(
                    ws,
                    s.lay.instance_order + 4 * at_instance as usize,
                    &e.index(),
                );
                at_instance += 1;
            } else {
                let poly = s.patch(ws, e).poly;
                s.set_ordered(ws, at, poly);
                at += 1;
            }
        }
    }
}

/// The scene's emitted power (epsilon's first unit), the typical polygon area, the minimum
/// patch area and the ray length that leaves the scene.
fn totals(s: &mut State, ws: &[u8], sources: u32) {
    let nb = s.bands;
    let mut power = [0.0f64; MAX_BANDS];
    let (mut log_area, mut counted) = (0.0f64, 0u64);
    for i in 0..s.polygons {
        let poly = s.polygon(ws, i);
        let m = s.material(ws, poly.material);
        let area = s.patch(ws, Elem(poly.root)).area as f64;
        if area > 0.0 {
            log_area += libm::log(area);
            counted += 1;
        }
        for (b, p) in power.iter_mut().enumerate().take(nb) {
            *p += area * (m.emit[0][b] as f64 + m.emit[1][b] as f64);
        }
    }
    // Closed instances that block with their own polygons cast shadows of their size too
    // (a soil alone under closed plants would take a plant's shadow in a few samples).
    for i in 0..s.instances {
        let leaf = s.instance(ws, i);
        if let Some(g) = s.original_geometry(ws, leaf.slot) {
            let scale2 = (leaf.scale as f64) * (leaf.scale as f64);
            g.each_area(|a| {
                if a > 0.0 {
                    log_area += libm::log(a as f64 * scale2);
                    counted += 1;
                }
            });
        }
    }
    s.typical_area = if counted > 0 {
        libm::exp(log_area / counted as f64) as f32
    } else {
        0.0
    };
    let root = s.cluster(ws, 0);
    let (lo, hi) = (Vec3::from(root.bbox_min), Vec3::from(root.bbox_max));
    let d = hi - lo;
    for k in 0..sources {
        let e = Elem::new(Kind::Source, k);
        let src: Source = read(ws, s.at(ws, e));
        let t = Vec3::from(src.towards).abs();
        let projected = (t.x * d.y * d.z + t.y * d.x * d.z + t.z * d.x * d.y) as f64;
        if let Some(irr) = s.b(ws, e, 0) {
            for (b, p) in power.iter_mut().enumerate().take(nb) {
                *p += projected * irr[b] as f64;
            }
        }
    }
    s.power = power[..nb].iter().copied().fold(0.0, f64::max) as f32;
    s.stats.emitted_power = s.power;
    s.min_area = root.area * s.settings.min_area;
    s.far = 4.0 * d.length().max(f32::MIN_POSITIVE);
    s.scene_min = lo;
    s.scene_max = hi;
}
