//! Validation of an untrusted image, in one streaming pass with fixed stack buffers.
//!
//! Order: header and section layout; strings; values; materials; vertices; then every tree
//! (each original, then the scene) depth-first with an explicit stack bounded by
//! [`MAX_NODE_DEPTH`], checking polygons, instances, boxes and expanded counts; then lights and
//! cameras. Stack use is a few KiB whatever the image claims.

use super::error::{ImageError, ImageErrorKind as K};
use super::header::{FORMAT_VERSION, Header, MAGIC, SECTION_COUNT, Section};
use super::layout::ImageLayout;
use super::records::*;
use super::source::SceneSource;
use super::view::{SceneInfo, SceneView, read_records};
use crate::NodeId;
use crate::geometry::{Aabb, Similarity, UNIT_TOLERANCE, camera_ok, polygon_shape};
use crate::limits::{MAX_BANDS, MAX_INSTANCING_DEPTH, MAX_NAME_BYTES, MAX_NODE_DEPTH, NONE};
use crate::material::{MaterialData, TWO_SIDED};
use bytemuck::Pod;
use glam::{Quat, Vec3};

/// A window of consecutive records, refilled on a miss: sequential scans and the local random
/// reads of polygon corners both cost one source read per `N` records.
struct Window<T: Pod, const N: usize> {
    section: Section,
    first: u64,
    len: usize,
    buf: [T; N],
}

impl<T: Pod, const N: usize> Window<T, N> {
    fn new(section: Section) -> Self {
        Window {
            section,
            first: 0,
            len: 0,
            buf: [T::zeroed(); N],
        }
    }

    fn get<S: SceneSource>(&mut self, src: &S, h: &Header, index: u64) -> Result<T, ImageError> {
        if index < self.first || index >= self.first + self.len as u64 {
            let count = h.section(self.section).count;
            if index >= count {
                return Err(ImageError::at(
                    offset_of(h, self.section, index),
                    K::OutOfRange {
                        section: self.section,
                        index,
                    },
                ));
            }
            let len = (count - index).min(N as u64) as usize;
            read_records(src, h, self.section, index, &mut self.buf[..len])?;
            self.first = index;
            self.len = len;
        }
        Ok(self.buf[(index - self.first) as usize])
    }
}

fn offset_of(h: &Header, s: Section, index: u64) -> u64 {
    let e = h.section(s);
    e.offset
        .saturating_add(index.saturating_mul(e.record_size as u64))
}

fn err<T>(h: &Header, s: Section, index: u64, kind: K) -> Result<T, ImageError> {
    Err(ImageError::at(offset_of(h, s, index), kind))
}

pub(crate) fn validate<S: SceneSource>(src: S) -> Result<SceneView<S>, ImageError> {
    let header = read_header(&src)?;
    let mut info = SceneInfo {
        bands: header.bands,
        image_bytes: header.file_size,
        scene_root: NodeId(header.scene_root),
        ..SceneInfo::default()
    };
    let count = |s: Section| header.section(s).count as u32; // < NONE, checked by read_header
    info.materials = count(Section::Materials);
    info.nodes = count(Section::Nodes);
    info.polygons = count(Section::Polygons);
    info.vertices = count(Section::Vertices);
    info.originals = count(Section::Originals);
    info.suns = count(Section::Suns);
    info.sky = count(Section::Sky);
    info.cameras = count(Section::Cameras);
    info.strings = count(Section::Strings);

    check_padding(&src, &header)?;
    check_strings(&src, &header)?;
    check_values(&src, &header)?;
    check_materials(&src, &header)?;
    check_vertices(&src, &header)?;
    check_trees(&src, &header, &mut info)?;
    check_lights(&src, &header, Section::Suns)?;
    check_lights(&src, &header, Section::Sky)?;
    check_cameras(&src, &header)?;
    Ok(SceneView { src, header, info })
}

fn read_header<S: SceneSource>(src: &S) -> Result<Header, ImageError> {
    let len = src.len();
    let hsize = core::mem::size_of::<Header>() as u64;
    if len < hsize {
        // A short file may still be recognisably not ours.
        let mut m = [0u8; 8];
        let n = (len as usize).min(8);
        src.read_at(0, &mut m[..n])
            .map_err(|e| ImageError::at(0, K::Source(e)))?;
        if m[..n] != MAGIC[..n] {
            return Err(ImageError::at(0, K::BadMagic));
        }
        return Err(ImageError::at(len, K::TooShort { len }));
    }
    let mut h: Header = bytemuck::Zeroable::zeroed();
    src.read_at(0, bytemuck::bytes_of_mut(&mut h))
        .map_err(|e| ImageError::at(0, K::Source(e)))?;
    if h.magic != MAGIC {
        return Err(ImageError::at(0, K::BadMagic));
    }
    if h.version != FORMAT_VERSION {
        return Err(ImageError::at(
            8,
            K::UnsupportedVersion { found: h.version },
        ));
    }
    if h.header_size as u64 != hsize {
        return Err(ImageError::at(
            12,
            K::HeaderSize {
                found: h.header_size,
            },
        ));
    }
    if h.bands == 0 || h.bands as usize > MAX_BANDS {
        return Err(ImageError::at(16, K::Bands { found: h.bands }));
    }
    if h.flags != 0 {
        return Err(ImageError::at(20, K::Reserved));
    }
    if h.reserved != 0 {
        return Err(ImageError::at(28, K::Reserved));
    }
    if h.file_size != len {
        return Err(ImageError::at(
            32,
            K::FileSize {
                claimed: h.file_size,
                actual: len,
            },
        ));
    }
    let mut counts = [0u64; SECTION_COUNT];
    for s in Section::ALL {
        let e = h.section(s);
        let at = 40 + 24 * s as u64;
        if e.record_size != s.record_size() {
            return Err(ImageError::at(
                at + 16,
                K::RecordSize {
                    section: s,
                    found: e.record_size,
                },
            ));
        }
        if e.reserved != 0 {
            return Err(ImageError::at(at + 20, K::Reserved));
        }
        if e.count >= NONE as u64 || e.count.saturating_mul(e.record_size as u64) > len {
            return Err(ImageError::at(at + 8, K::SectionTooLarge { section: s }));
        }
        counts[s as usize] = e.count;
    }
    let layout = ImageLayout::new(&counts).ok_or(ImageError::at(
        40,
        K::SectionTooLarge {
            section: Section::StringBytes,
        },
    ))?;
    for s in Section::ALL {
        let expected = layout.sections[s as usize].offset;
        let found = h.section(s).offset;
        if expected != found {
            return Err(ImageError::at(
                40 + 24 * s as u64,
                K::SectionOffset {
                    section: s,
                    expected,
                    found,
                },
            ));
        }
    }
    if layout.file_size != len {
        return Err(ImageError::at(
            32,
            K::FileSize {
                claimed: layout.file_size,
                actual: len,
            },
        ));
    }
    Ok(h)
}

fn check_padding<S: SceneSource>(src: &S, h: &Header) -> Result<(), ImageError> {
    let mut at = core::mem::size_of::<Header>() as u64;
    let mut ends = [0u64; SECTION_COUNT + 1];
    for s in Section::ALL {
        let e = h.section(s);
        ends[s as usize] = e.offset;
    }
    ends[SECTION_COUNT] = h.file_size;
    for (i, &next) in ends.iter().enumerate() {
        let gap = next.saturating_sub(at) as usize;
        if gap > 0 {
            let mut pad = [0u8; 8];
            let pad = &mut pad[..gap.min(8)];
            src.read_at(at, pad)
                .map_err(|e| ImageError::at(at, K::Source(e)))?;
            if pad.iter().any(|&b| b != 0) {
                return Err(ImageError::at(at, K::Padding));
            }
        }
        if i < SECTION_COUNT {
            let e = h.sections[i];
            at = e.offset + e.count * e.record_size as u64;
        }
    }
    Ok(())
}

fn check_name(h: &Header, at: u64, name: u32) -> Result<(), ImageError> {
    if name != NONE && name as u64 >= h.section(Section::Strings).count {
        return Err(ImageError::at(at, K::NameIndex { index: name }));
    }
    Ok(())
}

fn check_strings<S: SceneSource>(src: &S, h: &Header) -> Result<(), ImageError> {
    let bytes = h.section(Section::StringBytes);
    let mut w: Window<StringRef, 64> = Window::new(Section::Strings);
    let mut buf = [0u8; MAX_NAME_BYTES];
    for i in 0..h.section(Section::Strings).count {
        let r = w.get(src, h, i)?;
        let end = r.offset as u64 + r.len as u64;
        if end > bytes.count || r.len as usize > MAX_NAME_BYTES {
            return err(h, Section::Strings, i, K::StringRange { string: i as u32 });
        }
        let dst = &mut buf[..r.len as usize];
        let at = bytes.offset + r.offset as u64;
        src.read_at(at, dst)
            .map_err(|e| ImageError::at(at, K::Source(e)))?;
        if core::str::from_utf8(dst).is_err() {
            return Err(ImageError::at(at, K::StringUtf8 { string: i as u32 }));
        }
    }
    let names = h.section(Section::BandNames).count;
    if names != 0 && names != h.bands as u64 {
        return err(h, Section::BandNames, 0, K::BandNames { found: names });
    }
    let mut w: Window<u32, 8> = Window::new(Section::BandNames);
    for i in 0..names {
        let id = w.get(src, h, i)?;
        if id == NONE {
            return err(h, Section::BandNames, i, K::NameIndex { index: id });
        }
        check_name(h, offset_of(h, Section::BandNames, i), id)?;
    }
    Ok(())
}

fn check_values<S: SceneSource>(src: &S, h: &Header) -> Result<(), ImageError> {
    let mut w: Window<f32, 256> = Window::new(Section::Values);
    for i in 0..h.section(Section::Values).count {
        if !w.get(src, h, i)?.is_finite() {
            return err(h, Section::Values, i, K::Value { index: i });
        }
    }
    Ok(())
}

fn check_materials<S: SceneSource>(src: &S, h: &Header) -> Result<(), ImageError> {
    let mut w: Window<MaterialRecord, 32> = Window::new(Section::Materials);
    let pool = h.section(Section::Values).count;
    for i in 0..h.section(Section::Materials).count {
        let m = w.get(src, h, i)?;
        let at = offset_of(h, Section::Materials, i);
        let material = i as u32;
        check_name(h, at, m.name)?;
        if m.flags & !TWO_SIDED != 0 {
            return Err(ImageError::at(at + 4, K::MaterialFlags { material }));
        }
        if m.reserved != 0 {
            return Err(ImageError::at(at + 12, K::Reserved));
        }
        let two = m.flags & TWO_SIDED != 0;
        let n = MaterialData::value_count(h.bands, two) as u64;
        if m.values as u64 + n > pool {
            return Err(ImageError::at(at + 8, K::MaterialValues { material }));
        }
        let mut vals = [0.0f32; 5 * MAX_BANDS];
        read_records(
            src,
            h,
            Section::Values,
            m.values as u64,
            &mut vals[..n as usize],
        )?;
        let data = MaterialData::from_values(h.bands as u8, two, &vals[..n as usize]);
        if let Err(error) = data.check() {
            return Err(ImageError::at(at, K::Material { material, error }));
        }
    }
    Ok(())
}

fn check_vertices<S: SceneSource>(src: &S, h: &Header) -> Result<(), ImageError> {
    let mut w: Window<[f32; 3], 256> = Window::new(Section::Vertices);
    for i in 0..h.section(Section::Vertices).count {
        if !Vec3::from(w.get(src, h, i)?).is_finite() {
            return err(h, Section::Vertices, i, K::Vertex { vertex: i });
        }
    }
    Ok(())
}

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

fn check_trees<S: SceneSource>(
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

fn check_lights<S: SceneSource>(src: &S, h: &Header, s: Section) -> Result<(), ImageError> {
    let mut w: Window<LightRecord, 32> = Window::new(s);
    let pool = h.section(Section::Values).count;
    for i in 0..h.section(s).count {
        let l = w.get(src, h, i)?;
        let light = i as u32;
        let d = Vec3::from(l.towards);
        if !d.is_finite() || (d.length_squared() - 1.0).abs() > UNIT_TOLERANCE {
            return err(h, s, i, K::LightDirection { light });
        }
        if l.values as u64 + h.bands as u64 > pool {
            return err(h, s, i, K::LightValues { light });
        }
        let mut irr = [0.0f32; MAX_BANDS];
        read_records(
            src,
            h,
            Section::Values,
            l.values as u64,
            &mut irr[..h.bands as usize],
        )?;
        if irr.iter().any(|&v| v < 0.0) {
            return err(h, s, i, K::LightValues { light });
        }
    }
    Ok(())
}

fn check_cameras<S: SceneSource>(src: &S, h: &Header) -> Result<(), ImageError> {
    let mut w: Window<CameraRecord, 16> = Window::new(Section::Cameras);
    for i in 0..h.section(Section::Cameras).count {
        let c = w.get(src, h, i)?;
        let at = offset_of(h, Section::Cameras, i);
        check_name(h, at + 40, c.name)?;
        if c.reserved != 0 {
            return Err(ImageError::at(at + 44, K::Reserved));
        }
        if !camera_ok(c.position.into(), c.target.into(), c.up.into(), c.fovy_deg) {
            return Err(ImageError::at(at, K::Camera { camera: i as u32 }));
        }
    }
    Ok(())
}
