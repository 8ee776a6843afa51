//! Receiver quadrature of every element: the core's rule (2 x 2 Gauss on quads, 3 points on
//! triangles), optionally applied to the element's `4^split` sub-pieces for near-field
//! accuracy. The same points serve every emitter, so an element's form factors to a closed
//! surround sum to 1 exactly as the point-to-polygon form factors do.

use super::mesh::{Mesh, area_of};
use glam::Vec3;
use hirad_core::sampling::{MAX_QUADRATURE, quadrature, subdivide};

/// Quadrature points and weights (summing to 1 per element) of every element, flattened.
#[derive(Clone, Debug)]
pub struct Quadrature {
    points: Vec<Vec3>,
    weights: Vec<f32>,
    /// Element `e` owns `offsets[e]..offsets[e + 1]`.
    offsets: Vec<usize>,
}

impl Quadrature {
    /// The points of every element of `mesh`, each element split `split` more times.
    pub fn new(mesh: &Mesh, split: u32) -> Quadrature {
        let mut q = Quadrature {
            points: Vec::new(),
            weights: Vec::new(),
            offsets: vec![0],
        };
        for e in &mesh.elements {
            let start = q.points.len();
            q.add(e.corners(), split);
            let total: f32 = q.weights[start..].iter().sum();
            if total > 0.0 {
                for w in &mut q.weights[start..] {
                    *w /= total;
                }
            }
            q.offsets.push(q.points.len());
        }
        q
    }

    /// Appends the points of `corners` split `split` times, weighted by piece area (m^2).
    fn add(&mut self, corners: &[Vec3], split: u32) {
        if split == 0 {
            let (mut p, mut w) = ([Vec3::ZERO; MAX_QUADRATURE], [0.0; MAX_QUADRATURE]);
            let n = quadrature(corners, &mut p, &mut w);
            let area = area_of(corners);
            self.points.extend_from_slice(&p[..n]);
            self.weights.extend(w[..n].iter().map(|w| w * area));
            return;
        }
        let mut children = [[Vec3::ZERO; 4]; 4];
        let k = subdivide(corners, &mut children);
        for child in &children {
            self.add(&child[..k], split - 1);
        }
    }

    /// Points and weights of element `e`.
    pub fn of(&self, e: usize) -> (&[Vec3], &[f32]) {
        let r = self.offsets[e]..self.offsets[e + 1];
        (&self.points[r.clone()], &self.weights[r])
    }
}
