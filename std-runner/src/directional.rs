//! Parallel rays without the BVH: the polygons projected along one direction (a sun's or a
//! sky direction's) onto a uniform 2D grid, every cell listing the polygons whose projected
//! box reaches it, nearest the source first. A ray along the direction can only meet the
//! polygons of the cell its origin projects into, and only those that reach nearer the
//! source than its origin; the caller's exact segment test decides, so the answers are the
//! BVH's, at a fraction of the cost (no tree walk: a lookup and a few box tests).

use glam::{DVec3, Vec3};

/// Entries (polygon-in-cell) allowed per polygon before the grid is coarsened: bounds the
/// memory when a few large polygons (walls, soil quads) cover many cells.
const ENTRIES_PER_POLYGON: usize = 12;

/// Padding of every projected box and depth, relative to the scene's extent: far above the
/// rounding of the f32 boxes and of the segments the solver casts.
const PAD: f64 = 1e-5;

/// Polygons projected along one direction onto a uniform grid.
#[derive(Debug)]
pub struct DirectionalGrid {
    /// Unit direction the rays run along (towards the source).
    towards: DVec3,
    /// Orthonormal basis of the projection plane.
    u: DVec3,
    v: DVec3,
    /// Lower corner of the grid in the plane (m).
    origin: [f64; 2],
    /// Cells per metre.
    inv_cell: f64,
    /// Cells along u and v.
    nx: u32,
    ny: u32,
    /// Cell `c` lists entries `start[c]..start[c + 1]`.
    start: Vec<u32>,
    /// Per entry, the polygon.
    ids: Vec<u32>,
    /// Per entry, the polygon's largest depth along `towards` (m, padded), descending within
    /// a cell: the first entry not above a ray's origin ends the search.
    top: Vec<f32>,
    /// Per polygon, its projected box relative to `origin` (m, padded): u0, v0, u1, v1.
    boxes: Vec<[f32; 4]>,
    /// Lateral padding (m): a segment that strays further from the line through its origin
    /// is not answered here.
    pad: f64,
}

impl DirectionalGrid {
    /// Builds the grid of `polygons` (world corners) along the unit direction `towards`;
    /// `None` when the direction is not finite and non-zero, a corner is not finite, or there
    /// is nothing to hold.
    pub fn new<P: AsRef<[Vec3]>>(polygons: &[P], towards: Vec3) -> Option<DirectionalGrid> {
        let t = towards.as_dvec3().normalize_or_zero();
        if t == DVec3::ZERO || !t.is_finite() || polygons.is_empty() {
            return None;
        }
        let (u, v) = t.any_orthonormal_pair();
        let project = |c: Vec3| {
            let c = c.as_dvec3();
            (c.dot(u), c.dot(v), c.dot(t))
        };
        // Boxes in the plane and depth tops, in world units.
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        let mut extent = 0.0f64;
        let mut raw = Vec::with_capacity(polygons.len());
        for p in polygons {
            let mut b = [
                f64::INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::NEG_INFINITY,
            ];
            let mut top = f64::NEG_INFINITY;
            for &c in p.as_ref() {
                if !c.is_finite() {
                    return None;
                }
                let (a, bb, d) = project(c);
                b = [b[0].min(a), b[1].min(bb), b[2].max(a), b[3].max(bb)];
                top = top.max(d);
                extent = extent.max(a.abs()).max(bb.abs()).max(d.abs());
            }
            if !b.iter().all(|x| x.is_finite()) || !top.is_finite() {
                return None;
            }
            lo = [lo[0].min(b[0]), lo[1].min(b[1])];
            hi = [hi[0].max(b[2]), hi[1].max(b[3])];
            raw.push((b, top));
        }
        let pad = PAD * extent.max(f64::MIN_POSITIVE);
        let origin = [lo[0] - 2.0 * pad, lo[1] - 2.0 * pad];
        let (w, h) = (hi[0] - lo[0] + 4.0 * pad, hi[1] - lo[1] + 4.0 * pad);
        // About one cell per polygon, coarsened until the entries fit their budget.
        let n = polygons.len() as f64;
        let mut cell = (w * h / n).sqrt().max(w.max(h) / 4096.0).max(pad);
        let budget = ENTRIES_PER_POLYGON * polygons.len() + 1024;
        let dims = |cell: f64| {
            (
                ((w / cell).ceil() as u32).max(1),
                ((h / cell).ceil() as u32).max(1),
            )
        };
        let range = |b: &[f64; 4], cell: f64, nx: u32, ny: u32| {
            let i = |x: f64, n: u32| ((x / cell).floor().max(0.0) as u32).min(n - 1);
            (
                i(b[0] - pad - origin[0], nx),
                i(b[1] - pad - origin[1], ny),
                i(b[2] + pad - origin[0], nx),
                i(b[3] + pad - origin[1], ny),
            )
        };
        let (nx, ny) = loop {
            let (nx, ny) = dims(cell);
            let entries: usize = raw
                .iter()
                .map(|(b, _)| {
                    let (i0, j0, i1, j1) = range(b, cell, nx, ny);
                    (i1 - i0 + 1) as usize * (j1 - j0 + 1) as usize
                })
                .sum();
            if entries <= budget || (nx == 1 && ny == 1) {
                break (nx, ny);
            }
            cell *= 1.5;
        };
        let cells = nx as usize * ny as usize;
        let mut start = vec![0u32; cells + 1];
        for (b, _) in &raw {
            let (i0, j0, i1, j1) = range(b, cell, nx, ny);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    start[(j * nx + i) as usize + 1] += 1;
                }
            }
        }
        for c in 0..cells {
            start[c + 1] += start[c];
        }
        let total = start[cells] as usize;
        let mut fill = start.clone();
        let mut ids = vec![0u32; total];
        for (id, (b, _)) in raw.iter().enumerate() {
            let (i0, j0, i1, j1) = range(b, cell, nx, ny);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let c = (j * nx + i) as usize;
                    ids[fill[c] as usize] = id as u32;
                    fill[c] += 1;
                }
            }
        }
        // Nearest the source first (ties by id: deterministic).
        for c in 0..cells {
            ids[start[c] as usize..start[c + 1] as usize].sort_unstable_by(|&a, &b| {
                raw[b as usize]
                    .1
                    .total_cmp(&raw[a as usize].1)
                    .then(a.cmp(&b))
            });
        }
        let top = ids
            .iter()
            .map(|&id| widen(raw[id as usize].1 + pad, 1.0))
            .collect();
        let boxes = raw
            .iter()
            .map(|(b, _)| {
                [
                    widen(b[0] - origin[0] - pad, -1.0),
                    widen(b[1] - origin[1] - pad, -1.0),
                    widen(b[2] - origin[0] + pad, 1.0),
                    widen(b[3] - origin[1] + pad, 1.0),
                ]
            })
            .collect();
        Some(DirectionalGrid {
            towards: t,
            u,
            v,
            origin,
            inv_cell: 1.0 / cell,
            nx,
            ny,
            start,
            ids,
            top,
            boxes,
            pad,
        })
    }

    /// True when this grid runs along `towards` (to f32 rounding).
    pub fn runs_along(&self, towards: Vec3) -> bool {
        let t = towards.as_dvec3();
        (t - self.towards).length_squared() < 1e-10
    }

    /// Calls `blocks` on every polygon that the segment `o + t w`, `0 < t < 1`, can cross (a
    /// superset), nearest the source first, until it returns true; `None` when the segment
    /// does not run along this grid's direction closely enough to be answered here.
    #[inline]
    pub fn any(&self, o: DVec3, w: DVec3, mut blocks: impl FnMut(u32) -> bool) -> Option<bool> {
        let along = w.dot(self.towards);
        if along.is_nan()
            || along <= 0.0
            || (w - self.towards * along).length_squared() > 0.25 * self.pad * self.pad
        {
            return None;
        }
        let (a, b) = (
            o.dot(self.u) - self.origin[0],
            o.dot(self.v) - self.origin[1],
        );
        let (fi, fj) = ((a * self.inv_cell).floor(), (b * self.inv_cell).floor());
        if !(fi >= 0.0 && fj >= 0.0 && fi < self.nx as f64 && fj < self.ny as f64) {
            // Outside every polygon's projection.
            return Some(false);
        }
        let c = fj as usize * self.nx as usize + fi as usize;
        let depth = o.dot(self.towards) as f32;
        let (a, b) = (a as f32, b as f32);
        let range = self.start[c] as usize..self.start[c + 1] as usize;
        for (&id, &top) in self.ids[range.clone()].iter().zip(&self.top[range]) {
            if top <= depth {
                break;
            }
            let bx = &self.boxes[id as usize];
            if a < bx[0] || b < bx[1] || a > bx[2] || b > bx[3] {
                continue;
            }
            if blocks(id) {
                return Some(true);
            }
        }
        Some(false)
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.start.len() * 4 + self.ids.len() * 8 + self.boxes.len() * 16
    }
}

/// `x` as f32, rounded away from it towards `sign` (a few ulps: boxes only grow).
fn widen(x: f64, sign: f32) -> f32 {
    let y = x as f32;
    y + sign * (y.abs() * 4.0 * f32::EPSILON + f32::MIN_POSITIVE)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(x: f32, y: f32, z: f32, s: f32) -> Vec<Vec3> {
        vec![
            Vec3::new(x, y, z),
            Vec3::new(x + s, y, z),
            Vec3::new(x + s, y + s, z),
            Vec3::new(x, y + s, z),
        ]
    }

    /// The candidates `any` offers, collected (it is told nothing blocks).
    fn offered(g: &DirectionalGrid, from: Vec3, to: Vec3) -> Option<Vec<u32>> {
        let mut seen = Vec::new();
        g.any(from.as_dvec3(), (to - from).as_dvec3(), |id| {
            seen.push(id);
            false
        })
        .map(|_| seen)
    }

    #[test]
    fn offers_what_lies_above_nearest_the_source_first() {
        // Three squares stacked over (0.5, 0.5) at heights 1, 2 and 3, one beside them.
        let polys = vec![
            square(0.0, 0.0, 1.0, 1.0),
            square(0.0, 0.0, 3.0, 1.0),
            square(0.0, 0.0, 2.0, 1.0),
            square(5.0, 5.0, 2.0, 1.0),
        ];
        let g = DirectionalGrid::new(&polys, Vec3::Z).unwrap();
        let up = |z: f32| {
            let from = Vec3::new(0.5, 0.5, z);
            offered(&g, from, from + Vec3::Z * 10.0).unwrap()
        };
        assert_eq!(up(0.0), vec![1, 2, 0]);
        assert_eq!(up(1.5), vec![1, 2]);
        assert_eq!(up(3.5), Vec::<u32>::new());
        // Outside every projection: nothing, without a lookup.
        let far = Vec3::new(-50.0, 0.5, 0.0);
        assert_eq!(offered(&g, far, far + Vec3::Z), Some(vec![]));
        // Another direction, or a backwards or empty segment: not answered here.
        let from = Vec3::new(0.5, 0.5, 0.0);
        assert_eq!(offered(&g, from, from + Vec3::new(0.1, 0.0, 1.0)), None);
        assert_eq!(offered(&g, from, from - Vec3::Z), None);
        assert_eq!(offered(&g, from, from), None);
        // A blocking answer stops the search.
        let mut calls = 0;
        let hit = g.any(from.as_dvec3(), DVec3::Z * 10.0, |_| {
            calls += 1;
            true
        });
        assert_eq!((hit, calls), (Some(true), 1));
        assert!(g.runs_along(Vec3::Z) && !g.runs_along(Vec3::X));
    }

    #[test]
    fn every_polygon_over_a_point_is_offered_in_any_direction() {
        // A field of small tilted squares; for points under each square's centre along the
        // direction, that square must be among the candidates.
        let mut polys = Vec::new();
        for i in 0..40 {
            for j in 0..40 {
                let (x, y) = (i as f32 * 0.25, j as f32 * 0.25);
                let z = 1.0 + ((i * 7 + j * 3) % 11) as f32 * 0.1;
                polys.push(vec![
                    Vec3::new(x, y, z),
                    Vec3::new(x + 0.2, y, z + 0.05),
                    Vec3::new(x + 0.2, y + 0.1, z + 0.1),
                    Vec3::new(x, y + 0.1, z + 0.05),
                ]);
            }
        }
        for d in [
            Vec3::Z,
            Vec3::new(0.5, 0.2, 1.0).normalize(),
            Vec3::new(-1.0, 0.3, 0.4).normalize(),
            Vec3::new(0.0, 1.0, 0.02).normalize(),
        ] {
            let g = DirectionalGrid::new(&polys, d).unwrap();
            for (id, p) in polys.iter().enumerate() {
                for c in p.iter().chain([&((p[0] + p[2]) * 0.5)]) {
                    let from = *c - d * 3.0;
                    let seen = offered(&g, from, from + d * 20.0).unwrap();
                    assert!(seen.contains(&(id as u32)), "{d} {id}");
                }
            }
        }
    }

    #[test]
    fn no_grid_without_polygons_or_direction() {
        let none: Vec<Vec<Vec3>> = Vec::new();
        assert!(DirectionalGrid::new(&none, Vec3::Z).is_none());
        let one = vec![square(0.0, 0.0, 0.0, 1.0)];
        assert!(DirectionalGrid::new(&one, Vec3::ZERO).is_none());
        assert!(DirectionalGrid::new(&one, Vec3::splat(f32::NAN)).is_none());
        let bad = vec![vec![Vec3::ZERO, Vec3::X, Vec3::splat(f32::INFINITY)]];
        assert!(DirectionalGrid::new(&bad, Vec3::Z).is_none());
    }
}
