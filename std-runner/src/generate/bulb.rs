//! A light bulb as the paper's stand has them: a sphere of about 1,000 small emitting
//! polygons grouped into clusters (two hemispheres cut into azimuth sectors), so that the
//! solver can link to parts of the source rather than to every facet.

use crate::generate::shapes::{add_quad, add_triangle};
use crate::scene::Cluster;
use glam::Vec3;
use std::f32::consts::{PI, TAU};

/// The shape of a bulb.
#[derive(Clone, Copy, Debug)]
pub struct BulbShape {
    /// Sphere radius (m).
    pub radius: f32,
    /// Rings of facets from pole to pole (even: the hemispheres split between rings).
    pub stacks: u32,
    /// Facets around each ring.
    pub slices: u32,
    /// Azimuth sectors per hemisphere: the bulb has twice this many clusters.
    pub sectors: u32,
}

impl BulbShape {
    /// About `polygons` facets (at least 8 x 8) in 8 clusters, rings and slices in a 4 : 7
    /// ratio (facets about square at the equator).
    pub fn with_polygons(radius: f32, polygons: u32) -> Self {
        let stacks = (((polygons as f32) * 4.0 / 7.0).sqrt() / 2.0)
            .round()
            .max(4.0) as u32
            * 2;
        let slices = ((polygons as f32 / stacks as f32).round() as u32).max(8);
        BulbShape {
            radius,
            stacks,
            slices,
            sectors: 4,
        }
    }

    /// Facets of the whole sphere.
    pub fn polygons(&self) -> u32 {
        self.stacks * self.slices
    }
}

/// A bulb centred on the origin, facing out, made of `material`: a plain cluster named
/// `bulb` whose children are the hemisphere sectors.
pub fn bulb(shape: &BulbShape, material: u32) -> Cluster {
    let mut root = Cluster::named("bulb");
    let (stacks, slices) = (shape.stacks.max(2), shape.slices.max(3));
    let sectors = shape.sectors.clamp(1, slices);
    let p = |i: u32, j: u32| {
        let th = i as f32 / stacks as f32 * PI;
        let ph = j as f32 / slices as f32 * TAU;
        Vec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()) * shape.radius
    };
    for half in 0..2 {
        let rings = if half == 0 {
            0..stacks / 2
        } else {
            stacks / 2..stacks
        };
        for s in 0..sectors {
            let mut c = Cluster::named(&format!("{}-{s}", ["upper", "lower"][half]));
            let (j0, j1) = (s * slices / sectors, (s + 1) * slices / sectors);
            for i in rings.clone() {
                for j in j0..j1 {
                    let (a, b, cc, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
                    if i == 0 {
                        add_triangle(&mut c, [a, b, cc], material);
                    } else if i == stacks - 1 {
                        add_triangle(&mut c, [a, b, d], material);
                    } else {
                        add_quad(&mut c, [a, b, cc, d], material);
                    }
                }
            }
            root.children.push(c);
        }
    }
    root
}

#[cfg(test)]
mod tests {
    use super::*;
    use hirad_core::geometry::polygon_shape;

    #[test]
    fn a_thousand_facets_in_eight_clusters_facing_out() {
        let shape = BulbShape::with_polygons(0.5, 1000);
        let b = bulb(&shape, 0);
        assert_eq!(b.children.len(), 8);
        let n: usize = b.children.iter().map(|c| c.polygons.len()).sum();
        assert_eq!(n as u32, shape.polygons());
        assert!((900..=1100).contains(&n), "{n}");
        for c in &b.children {
            for p in &c.polygons {
                let corners: Vec<Vec3> = p.corners[..p.corner_count()]
                    .iter()
                    .map(|&i| c.vertices[i as usize])
                    .collect();
                let mid = corners.iter().copied().sum::<Vec3>() / corners.len() as f32;
                assert!(polygon_shape(&corners).unwrap().normal.dot(mid) > 0.0);
            }
        }
    }
}
