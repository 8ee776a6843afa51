//! Model -> binary image. The layout and every derived field (boxes, expanded counts,
//! instancing depths) follow exactly the rules the core's validator recomputes, and the
//! result is validated before it is returned: a compiled image always opens.

use super::check::original_order;
use super::{Cluster, Scene, SceneError};
use hirad_core::geometry::{Aabb, Similarity};
use hirad_core::image::*;
use hirad_core::limits::NONE;
use hirad_core::material::TWO_SIDED;
use std::collections::HashMap;

/// Compiles a scene into its canonical binary image. The same scene always gives the same
/// bytes.
pub fn compile(scene: &Scene) -> Result<Vec<u8>, SceneError> {
    scene.check()?;
    let order = original_order(scene)?;
    let mut new_of = vec![0u32; order.len()];
    for (new, &old) in order.iter().enumerate() {
        new_of[old] = new as u32;
    }
    let mut w = Writer {
        new_of,
        ..Writer::default()
    };
    w.band_names = scene
        .band_names
        .iter()
        .map(|n| w_intern(&mut w.strings, n))
        .collect();
    for m in &scene.materials {
        let name = w_intern(&mut w.strings, &m.name);
        let values = w.values.len() as u32;
        let mut buf = [0.0f32; 40];
        let n = m.data.to_values(&mut buf).unwrap_or(0);
        w.values.extend_from_slice(&buf[..n]);
        let flags = if m.data.two_sided { TWO_SIDED } else { 0 };
        w.materials.push(MaterialRecord {
            name,
            flags,
            values,
            reserved: 0,
        });
    }
    for &old in &order {
        let o = &scene.originals[old];
        let root = w.nodes.len() as u32;
        let (sum, _) = w.emit(&o.root);
        let name = w_intern(&mut w.strings, &o.name);
        w.originals.push(OriginalRecord {
            root,
            name,
            instancing_depth: sum.depth,
            reserved: 0,
            expanded_polygons: sum.expanded,
        });
    }
    let scene_root = w.nodes.len() as u32;
    w.emit(&scene.root);
    let bands = scene.bands as usize;
    let mut lights = |list: &[LightData]| -> Vec<LightRecord> {
        list.iter()
            .map(|l| {
                let values = w.values.len() as u32;
                w.values.extend_from_slice(&l.irradiance[..bands]);
                LightRecord {
                    towards: l.towards.to_array(),
                    values,
                }
            })
            .collect()
    };
    let suns = lights(&scene.suns);
    let sky = lights(&scene.sky);
    let cameras: Vec<CameraRecord> = scene
        .cameras
        .iter()
        .map(|c| CameraRecord {
            position: c.position.to_array(),
            target: c.target.to_array(),
            up: c.up.to_array(),
            fovy_deg: c.fovy_deg,
            name: c
                .name
                .as_deref()
                .map_or(NONE, |n| w_intern(&mut w.strings, n)),
            reserved: 0,
        })
        .collect();
    // Tables in increasing order of the originals' new indices, values one after another.
    let mut tables: Vec<&super::Tables> = scene.tables.iter().collect();
    tables.sort_by_key(|t| w.new_of.get(t.original).copied().unwrap_or(u32::MAX));
    let mut records = Vec::with_capacity(tables.len());
    let mut pool: Vec<f32> = Vec::new();
    let mut visibility: Vec<u8> = Vec::new();
    for (i, t) in tables.iter().enumerate() {
        if i > 0 && tables[i - 1].original == t.original {
            return Err(SceneError {
                path: String::new(),
                message: format!("original {} has two tables", t.original),
            });
        }
        if t.values.len() as u64 != t.record.values() {
            return Err(SceneError {
                path: String::new(),
                message: format!(
                    "the tables of original {} hold {} values where their grids need {}",
                    t.original,
                    t.values.len(),
                    t.record.values()
                ),
            });
        }
        if t.visible.len() as u64 != t.record.visible_bytes() {
            return Err(SceneError {
                path: String::new(),
                message: format!(
                    "the tables of original {} hold {} visible fractions where their grid needs {}",
                    t.original,
                    t.visible.len(),
                    t.record.visible_bytes()
                ),
            });
        }
        let Some(&original) = w.new_of.get(t.original) else {
            return Err(SceneError {
                path: String::new(),
                message: format!("tables name original {}, which does not exist", t.original),
            });
        };
        records.push(TableRecord {
            original,
            first: pool.len() as u64,
            first_visible: visibility.len() as u64,
            ..t.record
        });
        pool.extend_from_slice(&t.values);
        visibility.extend_from_slice(&t.visible);
    }
    let bytes = w.finish(
        scene.bands as u32,
        scene_root,
        &suns,
        &sky,
        &cameras,
        (&records, &pool, &visibility),
    )?;
    if let Err(e) = SceneView::open(SliceSource(&bytes)) {
        return Err(SceneError {
            path: String::new(),
            message: format!("internal error: compiled image fails validation: {e}"),
        });
    }
    Ok(bytes)
}

#[derive(Default)]
struct Strings {
    bytes: Vec<u8>,
    refs: Vec<StringRef>,
    index: HashMap<String, u32>,
}

fn w_intern(s: &mut Strings, name: &str) -> u32 {
    if let Some(&i) = s.index.get(name) {
        return i;
    }
    let i = s.refs.len() as u32;
    s.refs.push(StringRef {
        offset: s.bytes.len() as u32,
        len: name.len() as u32,
    });
    s.bytes.extend_from_slice(name.as_bytes());
    s.index.insert(name.to_string(), i);
    i
}

#[derive(Default)]
struct Writer {
    new_of: Vec<u32>,
    strings: Strings,
    band_names: Vec<u32>,
    values: Vec<f32>,
    materials: Vec<MaterialRecord>,
    vertices: Vec<[f32; 3]>,
    polygons: Vec<PolygonRecord>,
    nodes: Vec<NodeRecord>,
    instances: Vec<InstanceRecord>,
    originals: Vec<OriginalRecord>,
}

#[derive(Clone, Copy)]
struct Summary {
    expanded: u64,
    bbox: Aabb,
    depth: u32,
}

impl Writer {
    /// Emits a subtree depth-first; returns what it contributes to its parent and whether its
    /// box counts (the validator's `finish`).
    fn emit(&mut self, c: &Cluster) -> (Summary, bool) {
        let idx = self.nodes.len();
        self.nodes.push(NodeRecord::default());
        let poly_first = self.polygons.len() as u32;
        let vert_first = self.vertices.len() as u32;
        let mut own = Aabb::EMPTY;
        for v in &c.vertices {
            own.include(*v);
            self.vertices.push(v.to_array());
        }
        self.polygons.extend_from_slice(&c.polygons);
        let instance = match &c.instance {
            Some(i) => {
                let t = i.transform;
                self.instances.push(InstanceRecord {
                    original: self.new_of[i.original],
                    flags: if i.exact { EXACT } else { 0 },
                    rotation: t.rotation.to_array(),
                    translation: t.translation.to_array(),
                    scale: t.scale,
                });
                (self.instances.len() - 1) as u32
            }
            None => NONE,
        };
        let mut acc = Summary {
            expanded: c.polygons.len() as u64,
            bbox: own,
            depth: 0,
        };
        for child in &c.children {
            let (s, contributes) = self.emit(child);
            acc.expanded = acc.expanded.saturating_add(s.expanded);
            if contributes {
                acc.bbox = acc.bbox.union(s.bbox);
            }
            acc.depth = acc.depth.max(s.depth);
        }
        let computed = match &c.instance {
            None => acc,
            Some(i) => {
                let t: Similarity = i.transform;
                let o = self.originals[self.new_of[i.original] as usize];
                let root = self.nodes[o.root as usize];
                let root_box = if o.expanded_polygons == 0 {
                    Aabb::EMPTY
                } else {
                    t.aabb(&Aabb::new(root.bbox_min.into(), root.bbox_max.into()))
                };
                if i.exact {
                    Summary {
                        expanded: o.expanded_polygons,
                        bbox: root_box,
                        depth: o.instancing_depth + 1,
                    }
                } else {
                    Summary {
                        expanded: acc.expanded,
                        bbox: t.aabb(&acc.bbox).union(root_box),
                        depth: acc.depth + 1,
                    }
                }
            }
        };
        let contributes = !computed.bbox.is_empty();
        let stored = if contributes {
            computed.bbox
        } else {
            Aabb::new(glam::Vec3::ZERO, glam::Vec3::ZERO)
        };
        self.nodes[idx] = NodeRecord {
            bbox_min: stored.min.to_array(),
            bbox_max: stored.max.to_array(),
            expanded_polygons: computed.expanded,
            subtree_end: self.nodes.len() as u32,
            poly_first,
            poly_count: c.polygons.len() as u32,
            vert_first,
            vert_count: c.vertices.len() as u32,
            instance,
            name: c
                .name
                .as_deref()
                .map_or(NONE, |n| w_intern(&mut self.strings, n)),
            axis: c.axis.unwrap_or(NONE),
            age: c.age.unwrap_or(0.0),
            flags: if c.age.is_some() { HAS_AGE } else { 0 },
        };
        (
            Summary {
                bbox: stored,
                ..computed
            },
            contributes,
        )
    }

    fn finish(
        self,
        bands: u32,
        scene_root: u32,
        suns: &[LightRecord],
        sky: &[LightRecord],
        cameras: &[CameraRecord],
        (tables, table_values, visibility): (&[TableRecord], &[f32], &[u8]),
    ) -> Result<Vec<u8>, SceneError> {
        let sections: [&[u8]; SECTION_COUNT] = [
            &self.strings.bytes,
            bytemuck::cast_slice(&self.strings.refs),
            bytemuck::cast_slice(&self.band_names),
            bytemuck::cast_slice(&self.values),
            bytemuck::cast_slice(&self.materials),
            bytemuck::cast_slice(&self.vertices),
            bytemuck::cast_slice(&self.polygons),
            bytemuck::cast_slice(&self.nodes),
            bytemuck::cast_slice(&self.instances),
            bytemuck::cast_slice(&self.originals),
            bytemuck::cast_slice(suns),
            bytemuck::cast_slice(sky),
            bytemuck::cast_slice(cameras),
            bytemuck::cast_slice(tables),
            bytemuck::cast_slice(table_values),
            visibility,
        ];
        let mut counts = [0u64; SECTION_COUNT];
        for s in Section::ALL {
            let bytes = sections[s as usize].len() as u64;
            counts[s as usize] = bytes / s.record_size() as u64;
            if counts[s as usize] >= NONE as u64 {
                return Err(SceneError {
                    path: String::new(),
                    message: format!("too many {} for one image (at most {})", s.name(), NONE - 1),
                });
            }
        }
        let layout = ImageLayout::new(&counts).ok_or_else(|| SceneError {
            path: String::new(),
            message: "image too large".into(),
        })?;
        let header = layout.header(bands, scene_root);
        let mut out = Vec::with_capacity(layout.file_size as usize);
        out.extend_from_slice(bytemuck::bytes_of(&header));
        for s in Section::ALL {
            out.resize(layout.sections[s as usize].offset as usize, 0);
            out.extend_from_slice(sections[s as usize]);
        }
        out.resize(layout.file_size as usize, 0);
        Ok(out)
    }
}
