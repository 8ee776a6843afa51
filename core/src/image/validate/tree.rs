//! The depth-first walk over every tree (each original, then the scene): node ranges and
//! nesting, own polygons, instances and their originals, boxes and expanded counts.

use super::records::check_name;
use super::{Window, err, offset_of};
use crate::geometry::{Aabb, Similarity, polygon_shape};
use crate::image::error::{ImageError, ImageErrorKind as K};
use crate::image::header::{Header, Section};
use crate::image::records::*;
use crate::image::source::SceneSource;
use crate::image::view::{SceneInfo, read_records};
use crate::limits::{MAX_INSTANCING_DEPTH, MAX_NODE_DEPTH, NONE};
use bytemuck::Pod;
use glam::{Quat, Vec3};

/// What a finished subtree contributes to its parent.
#[derive(Clone, Copy)]
struct Summary {
    expanded: u64,
    bbox: Aabb,
    depth: u32,
}

/// An open node on the validation stack.
#[derive(Clone, Copy)]
struct Frame {
    node: u32,
    end: u32,
    instance: u32,
    stored_bbox: Aabb,
    stored_expanded: u64,
    /// Accumulated over own polygons and finished children, in this node's content frame.
    acc: Summary,
}

/// Cursors that run across all trees, and the record windows they read through.
struct Walk {
    poly: u64,
    vert: u64,
    inst: u64,
    nodes: Window<NodeRecord, 32>,
    polys: Window<PolygonRecord, 64>,
    verts: Window<[f32; 3], 128>,
}

pub(super) fn check_trees<S: SceneSource>(
    src: &S,
    h: &Header,
    info: &mut SceneInfo,
) -> Result<(), ImageError> {
    let n_nodes = h.section(Section::Nodes).count;
    let mut walk = Walk {
        poly: 0,
        vert: 0,
        inst: 0,
        nodes: Window::new(Section::Nodes),
        polys: Window::new(Section::Polygons),
        verts: Window::new(Section::Vertices),
    };
    let mut next_root: u64 = 0;
    let n_orig = h.section(Section::Originals).count;
    for k in 0..n_orig {
        let o: OriginalRecord = one(src, h, Section::Originals, k)?;
        let at = offset_of(h, Section::Originals, k);
        let original = k as u32;
        check_name(h, at + 4, o.name)?;
        if o.reserved != 0 {
            return Err(ImageError::at(at + 12, K::Reserved));
        }
        if o.root as u64 != next_root || next_root >= n_nodes {
            return Err(ImageError::at(at, K::OriginalRoot { original }));
        }
        let (end, sum) = check_tree(src, h, &mut walk, info, o.root, None, original)?;
        if sum.expanded != o.expanded_polygons || sum.depth != o.instancing_depth {
            return Err(ImageError::at(at, K::OriginalSummary { original }));
        }
        next_root = end as u64;
    }
    if h.scene_root as u64 != next_root || next_root >= n_nodes {
        let kind = if n_nodes == 0 {
            K::NoScene
        } else {
            K::SceneRoot
        };
        return Err(ImageError::at(24, kind));
    }
    let (_, sum) = check_tree(
        src,
        h,
        &mut walk,
        info,
        h.scene_root,
        Some(n_nodes as u32),
        n_orig as u32,
    )?;
    info.expanded_polygons = sum.expanded;
    info.instancing_depth = sum.depth;
    for (s, used) in [
        (Section::Polygons, walk.poly),
        (Section::Vertices, walk.vert),
        (Section::Instances, walk.inst),
    ] {
        let count = h.section(s).count;
        if used != count {
            return err(
                h,
                s,
                used,
                K::Unowned {
                    section: s,
                    used,
                    count,
                },
            );
        }
    }
    Ok(())
}

fn one<S: SceneSource, T: Pod>(src: &S, h: &Header, s: Section, i: u64) -> Result<T, ImageError> {
    let mut v = [T::zeroed()];
    read_records(src, h, s, i, &mut v)?;
    Ok(v[0])
}

/// Validates the tree rooted at `root`; `tree_end` is required for the scene (it must reach
/// the last node) and taken from the root for originals. Instances may only refer to
/// originals below `orig_limit`. Returns the tree's end and summary.
fn check_tree<S: SceneSource>(
    src: &S,
    h: &Header,
    walk: &mut Walk,
    info: &mut SceneInfo,
    root: u32,
    tree_end: Option<u32>,
    orig_limit: u32,
) -> Result<(u32, Summary), ImageError> {
    let mut stack: heapless::Vec<Frame, MAX_NODE_DEPTH> = heapless::Vec::new();
    let root_rec = walk.nodes.get(src, h, root as u64)?;
    let end = tree_end.unwrap_or(root_rec.subtree_end);
    if root_rec.subtree_end != end || end <= root || end as u64 > h.section(Section::Nodes).count {
        let kind = if tree_end.is_some() {
            K::SceneRoot
        } else {
            K::SubtreeEnd { node: root }
        };
        return err(h, Section::Nodes, root as u64, kind);
    }
    if root_rec.instance != NONE {
        return err(
            h,
            Section::Nodes,
            root as u64,
            K::RootIsInstance { node: root },
        );
    }
    let mut result = None;
    for i in root..end {
        let rec = walk.nodes.get(src, h, i as u64)?;
        let at = offset_of(h, Section::Nodes, i as u64);
        let parent_end = stack.last().map_or(end, |f| f.end);
        if rec.subtree_end <= i || rec.subtree_end > parent_end {
            return Err(ImageError::at(at + 32, K::SubtreeEnd { node: i }));
        }
        let depth = stack.len() + 1;
        info.max_node_depth = info.max_node_depth.max(depth as u32);
        check_node_fields(h, at, i, &rec)?;
        let own = check_own_geometry(src, h, walk, i, &rec)?;
        if rec.instance == NONE {
            info.clusters += 1;
        } else {
            check_instance_node(src, h, walk, info, i, &rec, orig_limit)?;
        }
        let frame = Frame {
            node: i,
            end: rec.subtree_end,
            instance: rec.instance,
            stored_bbox: Aabb::new(rec.bbox_min.into(), rec.bbox_max.into()),
            stored_expanded: rec.expanded_polygons,
            acc: Summary {
                expanded: rec.poly_count as u64,
                bbox: own,
                depth: 0,
            },
        };
        if stack.push(frame).is_err() {
            return Err(ImageError::at(at, K::TooDeep { node: i }));
        }
        // Close every subtree that ends right after this node.
        while let Some(top) = stack.last() {
            if top.end != i + 1 {
                break;
            }
            let Some(done) = stack.pop() else { break };
            let (sum, contributes) = finish(src, h, &done)?;
            match stack.last_mut() {
                Some(parent) => {
                    parent.acc.expanded =
                        parent
                            .acc
                            .expanded
                            .checked_add(sum.expanded)
                            .ok_or(ImageError::at(
                                at,
                                K::ExpansionOverflow { node: parent.node },
                            ))?;
                    if contributes {
                        parent.acc.bbox = parent.acc.bbox.union(sum.bbox);
                    }
                    parent.acc.depth = parent.acc.depth.max(sum.depth);
                }
                None => result = Some(sum),
            }
        }
    }
    match result {
        Some(sum) => Ok((end, sum)),
        None => err(h, Section::Nodes, root as u64, K::SubtreeEnd { node: root }),
    }
}

fn check_node_fields(h: &Header, at: u64, i: u32, rec: &NodeRecord) -> Result<(), ImageError> {
    check_name(h, at + 60, rec.name)?;
    if rec.flags & !HAS_AGE != 0
        || (rec.flags & HAS_AGE != 0 && !(rec.age >= 0.0 && rec.age.is_finite()))
    {
        return Err(ImageError::at(at + 68, K::NodeAttributes { node: i }));
    }
    if rec.flags & HAS_AGE == 0 && rec.age != 0.0 {
        return Err(ImageError::at(at + 64, K::NodeAttributes { node: i }));
    }
    Ok(())
}

/// Checks the node's own vertices and polygons; returns the box of its own vertices.
fn check_own_geometry<S: SceneSource>(
    src: &S,
    h: &Header,
    walk: &mut Walk,
    i: u32,
    rec: &NodeRecord,
) -> Result<Aabb, ImageError> {
    let at = offset_of(h, Section::Nodes, i as u64);
    let (n_poly, n_vert) = (
        h.section(Section::Polygons).count,
        h.section(Section::Vertices).count,
    );
    if rec.poly_first as u64 != walk.poly || walk.poly + rec.poly_count as u64 > n_poly {
        return Err(ImageError::at(at + 36, K::PolygonRange { node: i }));
    }
    if rec.vert_first as u64 != walk.vert || walk.vert + rec.vert_count as u64 > n_vert {
        return Err(ImageError::at(at + 44, K::VertexRange { node: i }));
    }
    walk.poly += rec.poly_count as u64;
    walk.vert += rec.vert_count as u64;
    let mut bbox = Aabb::EMPTY;
    for v in 0..rec.vert_count as u64 {
        bbox.include(walk.verts.get(src, h, rec.vert_first as u64 + v)?.into());
    }
    let n_mat = h.section(Section::Materials).count;
    for p in rec.poly_first as u64..rec.poly_first as u64 + rec.poly_count as u64 {
        let poly = walk.polys.get(src, h, p)?;
        let polygon = p as u32;
        let n = poly.corner_count();
        let mut corners = [Vec3::ZERO; 4];
        for (c, corner) in corners.iter_mut().enumerate().take(n) {
            let idx = poly.corners[c];
            if idx >= rec.vert_count {
                return err(
                    h,
                    Section::Polygons,
                    p,
                    K::Corner {
                        polygon,
                        corner: c as u8,
                    },
                );
            }
            *corner = walk
                .verts
                .get(src, h, rec.vert_first as u64 + idx as u64)?
                .into();
        }
        if poly.material as u64 >= n_mat {
            return err(
                h,
                Section::Polygons,
                p,
                K::PolygonMaterial {
                    polygon,
                    material: poly.material,
                },
            );
        }
        if let Err(error) = polygon_shape(&corners[..n]) {
            return err(h, Section::Polygons, p, K::Shape { polygon, error });
        }
    }
    Ok(bbox)
}

fn check_instance_node<S: SceneSource>(
    src: &S,
    h: &Header,
    walk: &mut Walk,
    info: &mut SceneInfo,
    i: u32,
    rec: &NodeRecord,
    orig_limit: u32,
) -> Result<(), ImageError> {
    let at = offset_of(h, Section::Nodes, i as u64);
    if rec.instance as u64 != walk.inst || walk.inst >= h.section(Section::Instances).count {
        return Err(ImageError::at(
            at + 52,
            K::InstanceOrder {
                node: i,
                instance: rec.instance,
            },
        ));
    }
    walk.inst += 1;
    let inst = load_instance(src, h, rec.instance)?;
    let iat = offset_of(h, Section::Instances, rec.instance as u64);
    if inst.original >= orig_limit {
        let (instance, original) = (rec.instance, inst.original);
        let kind = if (original as u64) < h.section(Section::Originals).count {
            K::OriginalCycle { instance, original }
        } else {
            K::OriginalIndex { instance, original }
        };
        return Err(ImageError::at(iat, kind));
    }
    if inst.is_exact() {
        if rec.subtree_end != i + 1 || rec.poly_count != 0 || rec.vert_count != 0 {
            return Err(ImageError::at(at, K::ExactWithContent { node: i }));
        }
        info.exact_instances += 1;
    } else {
        info.approximate_instances += 1;
    }
    Ok(())
}

/// Reads and checks an instance record.
fn load_instance<S: SceneSource>(
    src: &S,
    h: &Header,
    id: u32,
) -> Result<InstanceRecord, ImageError> {
    let inst: InstanceRecord = one(src, h, Section::Instances, id as u64)?;
    let iat = offset_of(h, Section::Instances, id as u64);
    if inst.flags & !EXACT != 0 {
        return Err(ImageError::at(iat + 4, K::InstanceFlags { instance: id }));
    }
    if let Err(error) = similarity(&inst) {
        return Err(ImageError::at(
            iat + 8,
            K::Transform {
                instance: id,
                error,
            },
        ));
    }
    Ok(inst)
}

pub(crate) fn similarity(
    inst: &InstanceRecord,
) -> Result<Similarity, crate::geometry::TransformError> {
    Similarity::checked(
        Quat::from_array(inst.rotation),
        inst.translation.into(),
        inst.scale,
    )
}

/// Completes a node: computes what it stands for, checks its stored box and count, and
/// returns its contribution to the parent (the stored box, unless its content is empty).
fn finish<S: SceneSource>(src: &S, h: &Header, f: &Frame) -> Result<(Summary, bool), ImageError> {
    let at = offset_of(h, Section::Nodes, f.node as u64);
    let node = f.node;
    let computed = if f.instance == NONE {
        f.acc
    } else {
        let inst = load_instance(src, h, f.instance)?;
        let t = similarity(&inst).map_err(|error| {
            ImageError::at(
                at,
                K::Transform {
                    instance: f.instance,
                    error,
                },
            )
        })?;
        let o: OriginalRecord = one(src, h, Section::Originals, inst.original as u64)?;
        let root: NodeRecord = one(src, h, Section::Nodes, o.root as u64)?;
        let root_box = if o.expanded_polygons == 0 {
            Aabb::EMPTY
        } else {
            t.aabb(&Aabb::new(root.bbox_min.into(), root.bbox_max.into()))
        };
        if inst.is_exact() {
            Summary {
                expanded: o.expanded_polygons,
                bbox: root_box,
                depth: o.instancing_depth.saturating_add(1),
            }
        } else {
            Summary {
                expanded: f.acc.expanded,
                bbox: t.aabb(&f.acc.bbox).union(root_box),
                depth: f.acc.depth.saturating_add(1),
            }
        }
    };
    if computed.depth > MAX_INSTANCING_DEPTH {
        return Err(ImageError::at(at, K::InstancingTooDeep { node }));
    }
    if computed.expanded != f.stored_expanded {
        return Err(ImageError::at(at + 24, K::Expanded { node }));
    }
    // The content's box is either empty or finite: a transform that overflows f32 is refused
    // here (a NaN box would otherwise count as empty and be "contained").
    let content_ok = computed.bbox == Aabb::EMPTY || computed.bbox.is_finite_nonempty();
    if !content_ok || !f.stored_bbox.is_finite_nonempty() || !f.stored_bbox.contains(&computed.bbox)
    {
        return Err(ImageError::at(at, K::Bbox { node }));
    }
    let contributes = !computed.bbox.is_empty();
    Ok((
        Summary {
            bbox: f.stored_bbox,
            ..computed
        },
        contributes,
    ))
}
