//! A terrain of gentle hills: a square heightfield of triangles (z up, metres), with the
//! exact height of its surface anywhere, so that objects can stand on it.

use crate::generate::rng::Rng;
use crate::generate::shapes::add_triangle;
use crate::scene::Cluster;
use glam::Vec3;
use std::f32::consts::TAU;

/// A square heightfield centred on the origin.
#[derive(Clone, Debug)]
pub struct Terrain {
    /// Side (m).
    pub size: f32,
    /// Cells per side; each cell is two triangles.
    pub cells: u32,
    /// Heights of the `(cells + 1)^2` grid points, row by row from -y (m).
    pub heights: Vec<f32>,
}

impl Terrain {
    /// Hills as a sum of four long waves in random directions, wavelengths from 0.4 to 1
    /// times the side, whose amplitudes add up to `relief` (m).
    pub fn hills(size: f32, cells: u32, relief: f32, rng: &mut Rng) -> Self {
        let cells = cells.max(1);
        let waves: Vec<(f32, f32, f32, f32)> = (0..4)
            .map(|_| {
                let dir = rng.range(0.0, TAU);
                let k = TAU / (size * rng.range(0.4, 1.0));
                (dir, k, rng.range(0.0, TAU), rng.range(0.5, 1.0))
            })
            .collect();
        let norm: f32 = waves.iter().map(|w| w.3).sum();
        let step = size / cells as f32;
        let mut heights = Vec::with_capacity(((cells + 1) * (cells + 1)) as usize);
        for j in 0..=cells {
            for i in 0..=cells {
                let (x, y) = (-0.5 * size + i as f32 * step, -0.5 * size + j as f32 * step);
                let h: f32 = waves
                    .iter()
                    .map(|&(dir, k, phase, a)| {
                        a * ((x * dir.cos() + y * dir.sin()) * k + phase).sin()
                    })
                    .sum();
                heights.push(relief * h / norm);
            }
        }
        Terrain {
            size,
            cells,
            heights,
        }
    }

    fn h(&self, i: u32, j: u32) -> f32 {
        self.heights[(j * (self.cells + 1) + i) as usize]
    }

    fn point(&self, i: u32, j: u32) -> Vec3 {
        let step = self.size / self.cells as f32;
        Vec3::new(
            -0.5 * self.size + i as f32 * step,
            -0.5 * self.size + j as f32 * step,
            self.h(i, j),
        )
    }

    /// Height of the triangulated surface at (x, y) (clamped to the terrain).
    pub fn height_at(&self, x: f32, y: f32) -> f32 {
        let step = self.size / self.cells as f32;
        let fx = ((x + 0.5 * self.size) / step).clamp(0.0, self.cells as f32);
        let fy = ((y + 0.5 * self.size) / step).clamp(0.0, self.cells as f32);
        let (i, j) = (
            (fx.floor() as u32).min(self.cells - 1),
            (fy.floor() as u32).min(self.cells - 1),
        );
        let (u, v) = (fx - i as f32, fy - j as f32);
        let (h00, h10, h01, h11) = (
            self.h(i, j),
            self.h(i + 1, j),
            self.h(i, j + 1),
            self.h(i + 1, j + 1),
        );
        // The diagonal runs from (i, j) to (i + 1, j + 1), as in `cluster`.
        if u >= v {
            h00 + u * (h10 - h00) + v * (h11 - h10)
        } else {
            h00 + v * (h01 - h00) + u * (h11 - h01)
        }
    }

    /// The lowest point of the surface under a disc of `radius` (m) centred on (x, y),
    /// sampled at its centre and 8 points of its rim: where a trunk must start so as not to
    /// float on a slope.
    pub fn footing(&self, x: f32, y: f32, radius: f32) -> f32 {
        (0..8).fold(self.height_at(x, y), |m, k| {
            let a = k as f32 / 8.0 * TAU;
            m.min(self.height_at(x + radius * a.cos(), y + radius * a.sin()))
        })
    }

    /// Lowest and highest grid heights (m).
    pub fn range(&self) -> (f32, f32) {
        self.heights
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &h| {
                (lo.min(h), hi.max(h))
            })
    }

    /// The surface as a cluster named `terrain` of child clusters of `block` x `block`
    /// cells each; triangles face up.
    pub fn cluster(&self, material: u32, block: u32) -> Cluster {
        let mut root = Cluster::named("terrain");
        let block = block.max(1);
        let mut j0 = 0;
        while j0 < self.cells {
            let mut i0 = 0;
            while i0 < self.cells {
                let mut c = Cluster::default();
                for j in j0..(j0 + block).min(self.cells) {
                    for i in i0..(i0 + block).min(self.cells) {
                        let (p00, p10, p01, p11) = (
                            self.point(i, j),
                            self.point(i + 1, j),
                            self.point(i, j + 1),
                            self.point(i + 1, j + 1),
                        );
                        add_triangle(&mut c, [p00, p10, p11], material);
                        add_triangle(&mut c, [p00, p11, p01], material);
                    }
                }
                root.children.push(c);
                i0 += block;
            }
            j0 += block;
        }
        root
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hirad_core::geometry::polygon_shape;

    #[test]
    fn surface_matches_its_triangles() {
        let mut r = Rng::new(5);
        let t = Terrain::hills(100.0, 10, 4.0, &mut r);
        let (lo, hi) = t.range();
        assert!(lo >= -4.0 && hi <= 4.0 && hi - lo > 0.5);
        let c = t.cluster(0, 4);
        assert_eq!(c.children.len(), 9);
        let mut n = 0;
        for b in &c.children {
            for p in &b.polygons {
                let v: Vec<Vec3> = p.corners[..3]
                    .iter()
                    .map(|&i| b.vertices[i as usize])
                    .collect();
                assert!(polygon_shape(&v).unwrap().normal.z > 0.0);
                // The centroid lies on the surface.
                let m = (v[0] + v[1] + v[2]) / 3.0;
                assert!((t.height_at(m.x, m.y) - m.z).abs() < 1e-4);
                n += 1;
            }
        }
        assert_eq!(n, 200);
        assert!(t.footing(3.0, 4.0, 0.5) <= t.height_at(3.0, 4.0));
    }
}
