//! The reference solver's mesh: every instance expanded into world-space polygons (in
//! global-id order), each polygon split uniformly into `4^level` elements, with the levels
//! chosen so that elements have about the same area and their total stays within budget.

use super::error::ExactError;
use super::{ExactSettings, MAX_ELEMENTS};
use crate::scene::{ExpandVisitor, ExpandedNode, Scene, SceneError, expand, too_small_message};
use glam::Vec3;
use hirad_core::geometry::{Aabb, ShapeError, polygon_shape};
use hirad_core::limits::NONE;
use hirad_core::material::MaterialData;
use hirad_core::sampling::subdivide;
use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::ops::Range;

/// Deepest uniform subdivision of one polygon (4^12 elements is far beyond any budget).
const MAX_LEVEL: u32 = 12;

/// An input polygon of the expanded scene, in world space.
#[derive(Clone, Debug)]
pub struct WorldPolygon {
    /// Corners (m), 3 or 4 used; counter-clockwise seen from the front.
    pub corners: [Vec3; 4],
    /// 3 or 4.
    pub count: u8,
    /// Unit front normal.
    pub normal: Vec3,
    /// Area (m^2).
    pub area: f32,
    /// Index into the scene's materials.
    pub material: usize,
    /// Subdivision level: the polygon is split into `4^level` elements.
    pub level: u32,
    /// Its elements in [`Mesh::elements`].
    pub elements: Range<usize>,
}

impl WorldPolygon {
    /// The used corners.
    pub fn corners(&self) -> &[Vec3] {
        &self.corners[..self.count as usize]
    }
}

/// One element: a uniform piece of an input polygon.
#[derive(Clone, Copy, Debug)]
pub struct Element {
    /// Corners (m), 3 or 4 used; same orientation as the polygon.
    pub corners: [Vec3; 4],
    /// 3 or 4.
    pub count: u8,
    /// Unit front normal (the polygon's).
    pub normal: Vec3,
    /// Area (m^2).
    pub area: f32,
    /// Global id of the polygon it belongs to (also its visibility id).
    pub polygon: u32,
    /// Slot of its back side in the radiosity vector ([`NONE`] for one-sided materials);
    /// the front side's slot is the element's own index.
    pub back_slot: u32,
}

impl Element {
    /// The used corners.
    pub fn corners(&self) -> &[Vec3] {
        &self.corners[..self.count as usize]
    }

    /// True when the element has a back side (two-sided material).
    pub fn two_sided(&self) -> bool {
        self.back_slot != NONE
    }
}

/// The expanded, subdivided scene.
#[derive(Clone, Debug)]
pub struct Mesh {
    /// Input polygons in global-id order.
    pub polygons: Vec<WorldPolygon>,
    /// Elements, grouped by polygon in global-id order.
    pub elements: Vec<Element>,
    /// Number of radiosity slots: one per element plus one per two-sided element.
    pub slots: usize,
    /// Box around every corner (m).
    pub bounds: Aabb,
}

impl Mesh {
    /// Checks `scene` (`Scene::check`), expands it and subdivides it within the element
    /// budget of `settings`.
    pub fn build<E>(scene: &Scene, settings: &ExactSettings) -> Result<Mesh, ExactError<E>> {
        let mut polygons = expand_polygons(scene)?;
        let budget = settings.max_elements.max(polygons.len());
        assign_levels(&mut polygons, budget);
        let mut elements = Vec::new();
        let mut back = 0usize;
        let mut bounds = Aabb::EMPTY;
        let mut pieces = Vec::new();
        for (id, p) in polygons.iter_mut().enumerate() {
            let two_sided = scene.materials[p.material].data.two_sided;
            let start = elements.len();
            pieces.clear();
            split(p.corners(), p.level, &mut pieces);
            for (corners, count) in &pieces {
                for c in &corners[..*count] {
                    bounds.include(*c);
                }
                elements.push(Element {
                    corners: *corners,
                    count: *count as u8,
                    normal: p.normal,
                    area: area_of(&corners[..*count]),
                    polygon: id as u32,
                    back_slot: if two_sided { back as u32 } else { NONE },
                });
                back += two_sided as usize;
            }
            p.elements = start..elements.len();
        }
        let n = elements.len();
        for e in elements.iter_mut().filter(|e| e.two_sided()) {
            e.back_slot += n as u32;
        }
        Ok(Mesh {
            polygons,
            elements,
            slots: n + back,
            bounds,
        })
    }

    /// Material of element `e`.
    pub fn material<'a>(&self, scene: &'a Scene, e: usize) -> &'a MaterialData {
        let p = &self.polygons[self.elements[e].polygon as usize];
        &scene.materials[p.material].data
    }
}

/// Collects the expanded polygons in world space, refusing more than [`MAX_ELEMENTS`].
fn expand_polygons<E>(scene: &Scene) -> Result<Vec<WorldPolygon>, ExactError<E>> {
    scene.check().map_err(ExactError::Scene)?;
    let mut v = Collect {
        out: Vec::new(),
        refused: None,
    };
    match expand(scene, &mut v) {
        Ok(_) => Ok(v.out),
        Err(()) => Err(v.refused.unwrap_or_else(|| {
            ExactError::Settings("the scene could not be expanded".to_string())
        })),
    }
}

/// The expansion visitor: world polygons in global-id order.
struct Collect<E> {
    out: Vec<WorldPolygon>,
    refused: Option<ExactError<E>>,
}

impl<E> ExpandVisitor for Collect<E> {
    type Error = ();

    fn node(&mut self, node: &ExpandedNode<'_>) -> Result<(), ()> {
        let c = node.cluster;
        let count = self.out.len() + c.polygons.len();
        if count > MAX_ELEMENTS {
            self.refused = Some(ExactError::TooLarge {
                what: "expanded polygons",
                count: count as u64,
                limit: MAX_ELEMENTS as u64,
            });
            return Err(());
        }
        let t = node.to_world;
        for (k, poly) in c.polygons.iter().enumerate() {
            let n = poly.corner_count();
            let mut local = [Vec3::ZERO; 4];
            for (l, &v) in local.iter_mut().zip(&poly.corners[..n]) {
                *l = c.vertices[v as usize];
            }
            // A checked scene holds only valid polygons and a similarity keeps them valid,
            // so the world normal and area follow exactly from the local ones.
            let shape = match polygon_shape(&local[..n]) {
                Ok(s) => s,
                Err(e) => {
                    self.refused = Some(ExactError::Scene(SceneError {
                        path: format!("polygon {}", node.first_id + k as u64),
                        message: e.to_string(),
                    }));
                    return Err(());
                }
            };
            let mut corners = [t.point(local[n - 1]); 4];
            for (w, l) in corners.iter_mut().zip(&local[..n]) {
                *w = t.point(*l);
            }
            // Placed far from the origin (or scaled down), a valid polygon can become too
            // small for f32 where it lands: refused like the hr solver refuses it.
            if let Err(e) = polygon_shape(&corners[..n]) {
                let message = match e {
                    ShapeError::TooSmall => too_small_message("the polygon", &corners[..n]),
                    e => e.to_string(),
                };
                self.refused = Some(ExactError::Scene(SceneError {
                    path: format!("polygon {}", node.first_id + k as u64),
                    message: format!("once placed by its instances, {message}"),
                }));
                return Err(());
            }
            self.out.push(WorldPolygon {
                corners,
                count: n as u8,
                normal: t.direction(shape.normal).normalize(),
                area: shape.area * t.scale * t.scale,
                material: poly.material as usize,
                level: 0,
                elements: 0..0,
            });
        }
        Ok(())
    }
}

/// Chooses each polygon's level: repeatedly splits the polygon whose elements are largest
/// (ties: lowest global id) while the total stays within `budget`. Deterministic.
fn assign_levels(polygons: &mut [WorldPolygon], budget: usize) {
    let mut total = polygons.len();
    // Element areas are finite and >= 0, so their bit patterns order like the values.
    let mut heap: BinaryHeap<(u32, Reverse<usize>)> = polygons
        .iter()
        .enumerate()
        .map(|(i, p)| (p.area.to_bits(), Reverse(i)))
        .collect();
    while let Some((bits, Reverse(i))) = heap.pop() {
        let p = &mut polygons[i];
        let extra = 3usize << (2 * p.level);
        if p.level >= MAX_LEVEL || total + extra > budget {
            break;
        }
        total += extra;
        p.level += 1;
        heap.push(((f32::from_bits(bits) * 0.25).to_bits(), Reverse(i)));
    }
}

/// Splits a polygon `level` times into `4^level` pieces (depth-first order).
fn split(corners: &[Vec3], level: u32, out: &mut Vec<([Vec3; 4], usize)>) {
    if level == 0 {
        let mut c = [corners[corners.len() - 1]; 4];
        c[..corners.len()].copy_from_slice(corners);
        out.push((c, corners.len()));
        return;
    }
    let mut children = [[Vec3::ZERO; 4]; 4];
    let k = subdivide(corners, &mut children);
    for child in &children {
        split(&child[..k], level - 1, out);
    }
}

/// Area of a triangle or of a planar quad (half the cross product of its diagonals) (m^2).
pub fn area_of(c: &[Vec3]) -> f32 {
    if c.len() == 4 {
        0.5 * (c[2] - c[0]).cross(c[3] - c[1]).length()
    } else {
        0.5 * (c[1] - c[0]).cross(c[2] - c[0]).length()
    }
}
