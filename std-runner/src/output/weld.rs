//! Welds patch corners into shared vertices and finds the vertices that lie inside patch
//! edges (T-junctions), for smooth shading (see [`super::smooth`]).
//!
//! Two corners are one vertex when they are within `tol` (m) of each other, `tol` being a
//! fraction [`WELD_REL`] of the diagonal of the corners' bounding box, so that the welding
//! does not depend on the scene's units or size.

use glam::DVec3;
use std::collections::HashMap;

/// Corners nearer than this fraction of the bounding box's diagonal are one vertex.
pub const WELD_REL: f64 = 1e-6;

/// Shared vertices of a set of corner positions.
#[derive(Clone, Debug)]
pub struct Welded {
    /// Per input corner: its vertex.
    pub vertex_of: Vec<u32>,
    /// Per vertex: its position (m), that of its first corner.
    pub positions: Vec<DVec3>,
    /// Weld distance (m).
    pub tol: f64,
}

/// Integer cell of a point on a grid of `cell` (m).
fn cell_of(p: DVec3, cell: f64) -> [i64; 3] {
    (p / cell).floor().as_i64vec3().to_array()
}

/// Welds `points` (m): each point joins the first earlier vertex within `tol`, else starts one.
pub fn weld(points: &[DVec3]) -> Welded {
    let (lo, hi) = points.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let diag = if points.is_empty() {
        0.0
    } else {
        (hi - lo).length()
    };
    let tol = (WELD_REL * diag).max(f64::MIN_POSITIVE);
    // Cells of side 2 tol: a vertex within tol of a point is in the point's cell or a
    // neighbour.
    let cell = 2.0 * tol;
    let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
    let mut positions: Vec<DVec3> = Vec::new();
    let mut vertex_of = Vec::with_capacity(points.len());
    for &p in points {
        let c = cell_of(p, cell);
        let mut found = None;
        'search: for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let key = [c[0] + dx, c[1] + dy, c[2] + dz];
                    for &v in grid.get(&key).map_or(&[][..], Vec::as_slice) {
                        if positions[v as usize].distance(p) <= tol {
                            found = Some(v);
                            break 'search;
                        }
                    }
                }
            }
        }
        let v = found.unwrap_or_else(|| {
            let v = positions.len() as u32;
            positions.push(p);
            grid.entry(c).or_default().push(v);
            v
        });
        vertex_of.push(v);
    }
    Welded {
        vertex_of,
        positions,
        tol,
    }
}

/// Finds the vertices that lie on segments, away from their ends: a grid of cells about the
/// segments' median length, each vertex filed in every cell within a quarter cell of it, so
/// that points sampled every half cell along a segment meet every vertex near it.
#[derive(Clone, Debug)]
pub struct OnEdges<'a> {
    welded: &'a Welded,
    cell: f64,
    grid: HashMap<[i64; 3], Vec<u32>>,
}

impl<'a> OnEdges<'a> {
    /// An index of `welded`'s vertices for segments of typical length `typical` (m).
    pub fn new(welded: &'a Welded, typical: f64) -> Self {
        let cell = typical.max(8.0 * welded.tol);
        let reach = 0.25 * cell + welded.tol;
        let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for (v, &p) in welded.positions.iter().enumerate() {
            let a = cell_of(p - DVec3::splat(reach), cell);
            let b = cell_of(p + DVec3::splat(reach), cell);
            for x in a[0]..=b[0] {
                for y in a[1]..=b[1] {
                    for z in a[2]..=b[2] {
                        grid.entry([x, y, z]).or_default().push(v as u32);
                    }
                }
            }
        }
        OnEdges { welded, cell, grid }
    }

    /// The vertices within the weld distance of the segment `a`..`b` (m) and more than it
    /// from both ends, each once, in increasing order, written to `out` (cleared first).
    pub fn inside(&self, a: DVec3, b: DVec3, out: &mut Vec<u32>) {
        out.clear();
        let tol = self.welded.tol;
        let d = b - a;
        let len = d.length();
        if len <= 2.0 * tol {
            return;
        }
        let steps = (len / (0.5 * self.cell)).ceil().min(1e6) as usize;
        for s in 0..=steps {
            let p = a + d * (s as f64 / steps as f64);
            for &v in self
                .grid
                .get(&cell_of(p, self.cell))
                .map_or(&[][..], Vec::as_slice)
            {
                let q = self.welded.positions[v as usize];
                let t = (q - a).dot(d) / (len * len);
                let off = (a + d * t).distance(q);
                if off <= tol && t * len > tol && (1.0 - t) * len > tol {
                    out.push(v);
                }
            }
        }
        out.sort_unstable();
        out.dedup();
    }
}
