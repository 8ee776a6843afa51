//! The in-memory scene model of the runner: a tree that parsers build and printers walk.
//!
//! It mirrors the binary image (see `hirad_core::image`) with names as strings and children
//! nested, and reuses the core's value types so that every check is the core's own. A scene is
//! the compact, instanced form: it never holds the expanded geometry.
//!
//! Units: metres for lengths, W/m^2 for exitance and irradiance.

mod check;
mod compile;
mod decompile;
mod expand;
mod sample;
mod small;
mod up;

pub use check::SceneError;
pub use compile::compile;
pub use decompile::{decompile, decompile_records, read_image};
pub use expand::{ExpandVisitor, ExpandedNode, expand};
pub use sample::sample;
pub use small::{too_small_detail, too_small_message};
pub use up::Up;

pub use hirad_core::geometry::Similarity;
pub use hirad_core::image::{CameraData, LightData, PolygonRecord as Polygon};
pub use hirad_core::material::MaterialData;

use glam::Vec3;
use hirad_core::limits::NONE;

/// A whole scene in compact (instanced) form.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// Spectral bands, 1..=8.
    pub bands: u8,
    /// Band names: empty, or one per band.
    pub band_names: Vec<String>,
    /// Materials; polygons refer to them by index.
    pub materials: Vec<Material>,
    /// Originals; instances refer to them by index. Any order: compiling sorts them so that
    /// an original only contains instances of originals before it, and refuses cycles.
    pub originals: Vec<Original>,
    /// The scene tree.
    pub root: Cluster,
    /// Directional sources.
    pub suns: Vec<LightData>,
    /// Sky directions, each with its share of the sky's irradiance.
    pub sky: Vec<LightData>,
    /// Cameras; the first is the default view.
    pub cameras: Vec<Camera>,
    /// Directional tables of originals (`hirad tables`), at most one per original; only the
    /// binary image holds them.
    pub tables: Vec<Tables>,
}

/// An original's directional tables as the image stores them.
#[derive(Clone, Debug, PartialEq)]
pub struct Tables {
    /// Index into [`Scene::originals`].
    pub original: usize,
    /// Grids, box and bake errors (its `original` and `first` are set when compiling).
    pub record: hirad_core::image::TableRecord,
    /// `tau`, albedo, shares, response and scatterers' shape values, in that order (see
    /// the record's `lengths`).
    pub values: Vec<f32>,
    /// The scatterers' visible fractions (see the record's `visible_bytes`).
    pub visible: Vec<u8>,
}

/// A named material.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Unique name.
    pub name: String,
    /// Per-band values (the core's checks apply).
    pub data: MaterialData,
}

/// A named cluster hierarchy shared by instances.
#[derive(Clone, Debug, PartialEq)]
pub struct Original {
    /// Unique name.
    pub name: String,
    /// Its tree (the root is a plain cluster).
    pub root: Cluster,
}

/// What makes a cluster an instance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InstanceOf {
    /// Index into [`Scene::originals`].
    pub original: usize,
    /// Exact instances use the original's geometry when opened and hold none of their own;
    /// approximate ones carry their own geometry (in the instance's local frame).
    pub exact: bool,
    /// Places the local frame in the parent's frame.
    pub transform: Similarity,
}

/// A node of a tree: a plain cluster, or an instance (see [`InstanceOf`]).
///
/// Order of the expansion (global ids): own polygons first, then children in order.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Cluster {
    /// Optional name.
    pub name: Option<String>,
    /// Optional axis kind (botanical axis order or any user class).
    pub axis: Option<u32>,
    /// Optional age (growth units, usually years).
    pub age: Option<f32>,
    /// Set when this node is an instance.
    pub instance: Option<InstanceOf>,
    /// Own vertex positions (m), in this node's content frame.
    pub vertices: Vec<Vec3>,
    /// Own polygons; corners index `vertices`.
    pub polygons: Vec<Polygon>,
    /// Child nodes.
    pub children: Vec<Cluster>,
}

impl Scene {
    /// Drops the vertices of every cluster (its tree's and its originals'): what a solve
    /// that reads the scene's image as it goes keeps of the model is its structure.
    pub fn drop_vertices(&mut self) {
        let mut todo: Vec<&mut Cluster> = vec![&mut self.root];
        todo.extend(self.originals.iter_mut().map(|o| &mut o.root));
        while let Some(c) = todo.pop() {
            c.vertices = Vec::new();
            todo.extend(c.children.iter_mut());
        }
    }
}

/// A pinhole camera.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Optional name.
    pub name: Option<String>,
    /// Eye (m).
    pub position: Vec3,
    /// Point looked at (m).
    pub target: Vec3,
    /// Up direction.
    pub up: Vec3,
    /// Vertical field of view (degrees).
    pub fovy_deg: f32,
}

impl Scene {
    /// An empty scene with `bands` bands.
    pub fn new(bands: u8) -> Self {
        Scene {
            bands,
            band_names: Vec::new(),
            materials: Vec::new(),
            originals: Vec::new(),
            root: Cluster::default(),
            suns: Vec::new(),
            sky: Vec::new(),
            cameras: Vec::new(),
            tables: Vec::new(),
        }
    }

    /// Index of the material called `name`.
    pub fn material_index(&self, name: &str) -> Option<usize> {
        self.materials.iter().position(|m| m.name == name)
    }

    /// Index of the original called `name`.
    pub fn original_index(&self, name: &str) -> Option<usize> {
        self.originals.iter().position(|o| o.name == name)
    }
}

/// A triangle with the given corners and material.
pub fn triangle(a: u32, b: u32, c: u32, material: u32) -> Polygon {
    Polygon {
        corners: [a, b, c, NONE],
        material,
    }
}

/// A quad with the given corners and material.
pub fn quad(a: u32, b: u32, c: u32, d: u32, material: u32) -> Polygon {
    Polygon {
        corners: [a, b, c, d],
        material,
    }
}

/// A directional light or sky direction.
pub fn light(towards: Vec3, irradiance: &[f32]) -> LightData {
    let mut irr = [0.0; hirad_core::limits::MAX_BANDS];
    for (d, s) in irr.iter_mut().zip(irradiance) {
        *d = *s;
    }
    LightData {
        towards,
        irradiance: irr,
    }
}

impl Cluster {
    /// A plain cluster with a name.
    pub fn named(name: &str) -> Self {
        Cluster {
            name: Some(name.to_string()),
            ..Cluster::default()
        }
    }

    /// Adds a vertex and returns its index.
    pub fn vertex(&mut self, p: Vec3) -> u32 {
        self.vertices.push(p);
        (self.vertices.len() - 1) as u32
    }
}

#[cfg(test)]
mod tests;
