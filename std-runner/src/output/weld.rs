//! Welds patch corners into shared vertices and finds the vertices that lie inside patch
//! edges (T-junctions), for smooth shading (see [`super::smooth`]).
//!
//! Two corners are one vertex when they are within `tol` (m) of each other, `tol` being a
//! fraction [`WELD_REL`] of the diagonal of the corners' bounding box, so that the welding
//! does not depend on the scene's units or size.
//!
//! Both grids file vertices under a 64-bit mix of their cell's coordinates, in flat arrays
//! (no list per cell): a batch of the image's patches costs about 40 bytes a vertex here.
//! Cells that share a key only cost a distance test, which every candidate gets anyway.

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

/// A 64-bit key of a cell: its coordinates mixed (distinct cells may share one).
fn key(c: [i64; 3]) -> u64 {
    let mut h = 0x9e37_79b9_7f4a_7c15u64;
    for v in c {
        h = (h ^ v as u64).wrapping_mul(0xff51_afd7_ed55_8ccd);
        h ^= h >> 33;
    }
    h
}

/// No vertex (the end of a cell's chain).
const END: u32 = u32::MAX;

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
    // neighbour. Per key its first and last vertex; per vertex the next of its key's.
    let cell = 2.0 * tol;
    let mut chains: HashMap<u64, (u32, u32)> = HashMap::new();
    let mut next: Vec<u32> = Vec::new();
    let mut positions: Vec<DVec3> = Vec::new();
    let mut vertex_of = Vec::with_capacity(points.len());
    for &p in points {
        let c = cell_of(p, cell);
        let mut found = None;
        'search: for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let k = key([c[0] + dx, c[1] + dy, c[2] + dz]);
                    let mut v = chains.get(&k).map_or(END, |&(first, _)| first);
                    while v != END {
                        if positions[v as usize].distance(p) <= tol {
                            found = Some(v);
                            break 'search;
                        }
                        v = next[v as usize];
                    }
                }
            }
        }
        let v = found.unwrap_or_else(|| {
            let v = positions.len() as u32;
            positions.push(p);
            next.push(END);
            match chains.get_mut(&key(c)) {
                Some((_, last)) => {
                    next[*last as usize] = v;
                    *last = v;
                }
                None => {
                    chains.insert(key(c), (v, v));
                }
            }
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
    /// (cell key, vertex), sorted.
    filed: Vec<(u64, u32)>,
}

impl<'a> OnEdges<'a> {
    /// An index of `welded`'s vertices for segments of typical length `typical` (m).
    pub fn new(welded: &'a Welded, typical: f64) -> Self {
        let cell = typical.max(8.0 * welded.tol);
        let reach = 0.25 * cell + welded.tol;
        let mut filed = Vec::with_capacity(2 * welded.positions.len());
        for (v, &p) in welded.positions.iter().enumerate() {
            let a = cell_of(p - DVec3::splat(reach), cell);
            let b = cell_of(p + DVec3::splat(reach), cell);
            for x in a[0]..=b[0] {
                for y in a[1]..=b[1] {
                    for z in a[2]..=b[2] {
                        filed.push((key([x, y, z]), v as u32));
                    }
                }
            }
        }
        filed.sort_unstable();
        filed.dedup();
        OnEdges {
            welded,
            cell,
            filed,
        }
    }

    /// The vertices filed under the cell of `p`.
    fn near(&self, p: DVec3) -> &[(u64, u32)] {
        let k = key(cell_of(p, self.cell));
        let start = self.filed.partition_point(|e| e.0 < k);
        let end = start + self.filed[start..].partition_point(|e| e.0 == k);
        &self.filed[start..end]
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
            for &(_, v) in self.near(p) {
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
