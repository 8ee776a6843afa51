//! Binary image -> model.

use super::{Camera, Cluster, InstanceOf, Material, Original, Scene};
use hirad_core::image::*;
use hirad_core::limits::MAX_NAME_BYTES;
use hirad_core::*;

/// Opens (validates) an image held in memory.
pub fn read_image(bytes: &[u8]) -> Result<SceneView<SliceSource<'_>>, ImageError> {
    SceneView::open(SliceSource(bytes))
}

fn name<S: SceneSource>(
    v: &SceneView<S>,
    id: Option<StringId>,
) -> Result<Option<String>, ImageError> {
    let mut buf = [0u8; MAX_NAME_BYTES];
    match id {
        Some(id) => Ok(Some(v.string(id, &mut buf)?.to_string())),
        None => Ok(None),
    }
}

fn sid(raw: u32) -> Option<StringId> {
    (raw != limits::NONE).then_some(StringId(raw))
}

/// Rebuilds the model from a validated image. Unnamed materials and originals get the names
/// `material_N` / `original_N`; repeated names get a `_N` suffix so that the text form
/// stays unambiguous.
pub fn decompile<S: SceneSource>(v: &SceneView<S>) -> Result<Scene, ImageError> {
    decompile_with(v, true)
}

/// [`decompile`] keeping of each original's tables only its record (values and visible
/// fractions left empty): what says which originals have tables, without copying them (a
/// canopy's are 20 MB). Such a model does not compile again; the image is read instead.
pub fn decompile_records<S: SceneSource>(v: &SceneView<S>) -> Result<Scene, ImageError> {
    decompile_with(v, false)
}

fn decompile_with<S: SceneSource>(v: &SceneView<S>, contents: bool) -> Result<Scene, ImageError> {
    let info = *v.info();
    let mut scene = Scene::new(info.bands as u8);
    for b in 0..info.bands {
        if let Some(id) = v.band_name(b)? {
            scene
                .band_names
                .push(name(v, Some(id))?.unwrap_or_default());
        }
    }
    for i in 0..info.materials {
        let rec = v.material_record(MaterialId(i))?;
        let n = name(v, sid(rec.name))?.unwrap_or_else(|| format!("material_{i}"));
        let n = unique(n, scene.materials.iter().map(|m| m.name.as_str()), i);
        scene.materials.push(Material {
            name: n,
            data: v.material(MaterialId(i))?,
        });
    }
    for i in 0..info.originals {
        let rec = v.original(OriginalId(i))?;
        let n = name(v, sid(rec.name))?.unwrap_or_else(|| format!("original_{i}"));
        let n = unique(n, scene.originals.iter().map(|o| o.name.as_str()), i);
        let (root, _) = build(v, rec.root)?;
        scene.originals.push(Original { name: n, root });
    }
    scene.root = build(v, info.scene_root.0)?.0;
    for i in 0..info.suns {
        scene.suns.push(v.sun(LightId(i))?);
    }
    for i in 0..info.sky {
        scene.sky.push(v.sky(LightId(i))?);
    }
    for i in 0..info.cameras {
        let c = v.camera(CameraId(i))?;
        scene.cameras.push(Camera {
            name: name(v, c.name)?,
            position: c.position,
            target: c.target,
            up: c.up,
            fovy_deg: c.fovy_deg,
        });
    }
    for i in 0..info.tables {
        let record = v.table(i)?;
        let (mut values, mut visible) = (Vec::new(), Vec::new());
        if contents {
            values = vec![0.0f32; record.values() as usize];
            v.table_values(record.first, &mut values)?;
            visible = vec![0u8; record.visible_bytes() as usize];
            v.table_visibility(record.first_visible, &mut visible)?;
        }
        scene.tables.push(super::Tables {
            original: record.original as usize,
            record,
            values,
            visible,
        });
    }
    Ok(scene)
}

fn unique<'a>(n: String, existing: impl Iterator<Item = &'a str> + Clone, i: u32) -> String {
    if existing.clone().any(|e| e == n) {
        format!("{n}_{i}")
    } else {
        n
    }
}

/// Builds the subtree at `i`; returns it and the index after it. Recursion depth is bounded
/// by the validated nesting limit.
fn build<S: SceneSource>(v: &SceneView<S>, i: u32) -> Result<(Cluster, u32), ImageError> {
    let rec = v.node(NodeId(i))?;
    let mut verts = vec![[0f32; 3]; rec.vert_count as usize];
    v.vertices(VertexId(rec.vert_first), &mut verts)?;
    let mut polygons = vec![PolygonRecord::default(); rec.poly_count as usize];
    v.polygons(PolyId(rec.poly_first), &mut polygons)?;
    let instance = match rec.instance() {
        Some(id) => {
            let r = v.instance(id)?;
            Some(InstanceOf {
                original: r.original as usize,
                exact: r.is_exact(),
                transform: geometry::Similarity {
                    rotation: glam::Quat::from_array(r.rotation),
                    translation: r.translation.into(),
                    scale: r.scale,
                },
            })
        }
        None => None,
    };
    let mut c = Cluster {
        name: name(v, rec.name())?,
        axis: rec.axis(),
        age: rec.age(),
        instance,
        vertices: verts.into_iter().map(glam::Vec3::from).collect(),
        polygons,
        children: Vec::new(),
    };
    let mut j = i + 1;
    while j < rec.subtree_end {
        let (child, next) = build(v, j)?;
        c.children.push(child);
        j = next;
    }
    Ok((c, rec.subtree_end))
}
