//! Receiver quadrature of every element: the core's rule (2 x 2 Gauss on quads, 3 points on
//! triangles), optionally applied to the element's `4^split` sub-pieces for near-field
//! accuracy. The same points serve every emitter, so an element's form factors to a closed
//! surround sum to 1 exactly as the point-to-polygon form factors do.

use super::mesh::{Mesh, area_of};
use glam::Vec3;
use hirad_core::sampling::{MAX_QUADRATURE, quadrature, subdivide};

/// Quadrature points and weights (summing to 1 per element, or all 0 for an element whose
/// points are all buried) of every element, flattened.
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

    /// Leaves the points of element `e` marked in `buried` out of its rule: their weights
    /// become 0 and the others' are scaled to sum to 1 (all 0 when every point is buried).
    /// Returns the exposed fraction: the sum of the exposed points' weights before scaling.
    pub fn restrict(&mut self, e: usize, buried: &[bool]) -> f64 {
        let weights = &mut self.weights[self.offsets[e]..self.offsets[e + 1]];
        if !buried.iter().any(|&b| b) {
            return 1.0;
        }
        let mut exposed = 0.0f64;
        for (w, &b) in weights.iter_mut().zip(buried) {
            if b {
                *w = 0.0;
            } else {
                exposed += *w as f64;
            }
        }
        for w in weights.iter_mut() {
            *w = if exposed > 0.0 {
                (*w as f64 / exposed) as f32
            } else {
                0.0
            };
        }
        exposed.clamp(0.0, 1.0)
    }

    /// Points and weights of element `e` (a buried point's weight is 0).
    pub fn of(&self, e: usize) -> (&[Vec3], &[f32]) {
        let r = self.offsets[e]..self.offsets[e + 1];
        (&self.points[r.clone()], &self.weights[r])
    }
}
