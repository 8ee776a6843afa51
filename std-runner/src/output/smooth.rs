//! Radiosity at patch corners for smooth (Gouraud) pictures, as radiosity renderers draw
//! them: the value of a corner is the area-weighted mean radiosity (W/m^2) of the patches
//! that meet at its position on the same surface.
//!
//! Patches meet at a vertex when one of their corners is there (corners are welded, see
//! [`super::weld`]) or when the vertex lies inside one of their edges (a T-junction, common
//! because the hierarchy subdivides neighbours differently). They share a surface, and so
//! blend, only when they have the same material, the same side is seen (front with front,
//! back with back) and their normals differ by at most [`CREASE_DEG`]; a box's edges, a
//! leaf's two faces and a wall meeting a floor of another material stay sharp.
//!
//! A patch with T-junctions on its edges is drawn as a fan of triangles from its centre
//! (value: the mean of its corners') through its corners and junctions, so that its values
//! along such an edge are those of the small neighbours: no crack in value at the junction.

use super::weld::{OnEdges, weld};
use glam::{DVec3, Vec3};
use hirad_core::sink::PatchResult;

/// Normals further apart than this (degrees) make a crease that values do not cross.
pub const CREASE_DEG: f64 = 30.0;

/// A patch kept for smoothing.
#[derive(Clone, Copy, Debug)]
pub struct StoredPatch {
    /// Global id of its polygon.
    pub id: u64,
    /// Corners (m); the first `count` are used.
    pub corners: [Vec3; 4],
    /// 3 or 4.
    pub count: u8,
    /// Unit front normal.
    pub normal: Vec3,
    /// Material index in the scene.
    pub material: u32,
    /// Whether the back has values (a two-sided material).
    pub two_sided: bool,
}

impl StoredPatch {
    /// The used corners (m).
    pub fn corners(&self) -> &[Vec3] {
        &self.corners[..usize::from(self.count)]
    }

    /// Area (m^2) of the planar convex patch.
    pub fn area(&self) -> f64 {
        let c: Vec<DVec3> = self.corners().iter().map(|c| c.as_dvec3()).collect();
        let cross = if c.len() == 3 {
            (c[1] - c[0]).cross(c[2] - c[0])
        } else {
            (c[2] - c[0]).cross(c[3] - c[1])
        };
        0.5 * cross.length()
    }
}

/// Every patch of an image with its radiosity, in the order drawn.
#[derive(Clone, Debug, Default)]
pub struct PatchStore {
    bands: usize,
    patches: Vec<StoredPatch>,
    /// Per patch `2 * bands` values (W/m^2): front, then back (zeros when one-sided).
    radiosity: Vec<f32>,
}

impl PatchStore {
    /// An empty store for `bands` bands.
    pub fn new(bands: usize) -> Self {
        PatchStore {
            bands,
            ..Self::default()
        }
    }

    /// Keeps a patch of 3 or 4 corners whose radiosity has `bands` values per side (the
    /// back may be empty); others are ignored (the rasteriser refuses them first).
    pub fn push(&mut self, p: &PatchResult<'_>) {
        let n = p.corners.len();
        if !(3..=4).contains(&n) || p.radiosity[0].len() != self.bands {
            return;
        }
        let mut corners = [Vec3::ZERO; 4];
        corners[..n].copy_from_slice(p.corners);
        let two_sided = p.radiosity[1].len() == self.bands;
        self.patches.push(StoredPatch {
            id: p.id,
            corners,
            count: n as u8,
            normal: p.normal,
            material: p.material,
            two_sided,
        });
        self.radiosity.extend_from_slice(p.radiosity[0]);
        if two_sided {
            self.radiosity.extend_from_slice(p.radiosity[1]);
        } else {
            self.radiosity.extend(std::iter::repeat_n(0.0, self.bands));
        }
    }

    /// Patches kept.
    pub fn len(&self) -> usize {
        self.patches.len()
    }

    /// True when no patch is kept.
    pub fn is_empty(&self) -> bool {
        self.patches.is_empty()
    }

    /// Patch `i` in the order pushed.
    pub fn patch(&self, i: usize) -> &StoredPatch {
        &self.patches[i]
    }

    /// Radiosity (W/m^2) of side `side` (0 front, 1 back) of patch `i`.
    pub fn radiosity(&self, i: usize, side: usize) -> &[f32] {
        let at = (2 * i + side) * self.bands;
        &self.radiosity[at..at + self.bands]
    }

    /// The smoothed radiosity at every corner (see the module).
    pub fn corner_values(&self) -> CornerValues {
        let bands = self.bands;
        let n = self.patches.len();
        let mut values = vec![0.0f32; n * 2 * 4 * bands];
        // Welded corners.
        let mut first = Vec::with_capacity(n + 1);
        let mut points = Vec::new();
        for p in &self.patches {
            first.push(points.len());
            points.extend(p.corners().iter().map(|c| c.as_dvec3()));
        }
        first.push(points.len());
        let welded = weld(&points);
        let areas: Vec<f64> = self.patches.iter().map(StoredPatch::area).collect();
        // Per vertex, the patches that meet there: (vertex, patch, corner or EDGE + edge).
        let mut meets: Vec<(u32, u32, u8)> = Vec::new();
        for i in 0..n {
            for k in 0..first[i + 1] - first[i] {
                meets.push((welded.vertex_of[first[i] + k], i as u32, k as u8));
            }
        }
        let mut lengths: Vec<f64> = (0..n)
            .flat_map(|i| {
                let c = &points[first[i]..first[i + 1]];
                (0..c.len()).map(move |k| c[k].distance(c[(k + 1) % c.len()]))
            })
            .collect();
        if !lengths.is_empty() {
            let mid = lengths.len() / 2;
            let (_, &mut typical, _) = lengths.select_nth_unstable_by(mid, f64::total_cmp);
            let on_edges = OnEdges::new(&welded, typical);
            let mut inside = Vec::new();
            for i in 0..n {
                let c = &points[first[i]..first[i + 1]];
                let own = &welded.vertex_of[first[i]..first[i + 1]];
                for k in 0..c.len() {
                    on_edges.inside(c[k], c[(k + 1) % c.len()], &mut inside);
                    for &v in inside.iter().filter(|v| !own.contains(v)) {
                        meets.push((v, i as u32, EDGE + k as u8));
                    }
                }
            }
        }
        meets.sort_unstable();
        let cos_crease = CREASE_DEG.to_radians().cos();
        let mut sum = vec![0.0f64; bands];
        let mut junctions = Vec::new();
        for group in meets.chunk_by(|a, b| a.0 == b.0) {
            for &(v, i, k) in group {
                let mut junction = (k >= EDGE).then(|| {
                    let c = self.patches[i as usize].corners();
                    let e = usize::from(k - EDGE);
                    let (a, b) = (c[e].as_dvec3(), c[(e + 1) % c.len()].as_dvec3());
                    let at = welded.positions[v as usize];
                    Junction {
                        patch: i,
                        edge: k - EDGE,
                        t: (at - a).dot(b - a) / (b - a).length_squared(),
                        at: at.as_vec3(),
                        values: vec![0.0; 2 * bands],
                    }
                });
                let p = &self.patches[i as usize];
                let sides = if p.two_sided { 2 } else { 1 };
                for side in 0..sides {
                    sum.fill(0.0);
                    let mut weight = 0.0f64;
                    for &(_, j, _) in group {
                        let q = &self.patches[j as usize];
                        let same = q.material == p.material
                            && (side == 0 || q.two_sided)
                            && f64::from(q.normal.dot(p.normal)) >= cos_crease;
                        if !same {
                            continue;
                        }
                        let w = areas[j as usize];
                        weight += w;
                        for (s, v) in sum.iter_mut().zip(self.radiosity(j as usize, side)) {
                            *s += w * f64::from(*v);
                        }
                    }
                    let own = self.radiosity(i as usize, side);
                    let out = match &mut junction {
                        Some(j) => &mut j.values[side * bands..(side + 1) * bands],
                        None => {
                            let at = ((i as usize * 2 + side) * 4 + usize::from(k)) * bands;
                            &mut values[at..at + bands]
                        }
                    };
                    for b in 0..bands {
                        out[b] = if weight > 0.0 {
                            (sum[b] / weight) as f32
                        } else {
                            own[b]
                        };
                    }
                }
                junctions.extend(junction);
            }
        }
        junctions.sort_by(|a: &Junction, b: &Junction| {
            (a.patch, a.edge)
                .cmp(&(b.patch, b.edge))
                .then(a.t.total_cmp(&b.t))
        });
        let mut first_junction = vec![0usize; n + 1];
        for j in &junctions {
            first_junction[j.patch as usize + 1] += 1;
        }
        for i in 0..n {
            first_junction[i + 1] += first_junction[i];
        }
        CornerValues {
            bands,
            values,
            junctions,
            first_junction,
        }
    }
}

/// Codes a patch's edge `k` (it meets a vertex inside that edge) as `EDGE + k`; corners
/// are `0..4`.
const EDGE: u8 = 4;

/// A vertex inside a patch's edge (a T-junction) with the patch's smoothed value there.
#[derive(Clone, Debug, PartialEq)]
pub struct Junction {
    /// The patch.
    pub patch: u32,
    /// Its edge, from corner `edge` to the next.
    pub edge: u8,
    /// Where along the edge, in (0, 1).
    pub t: f64,
    /// The vertex (m).
    pub at: Vec3,
    /// Radiosity (W/m^2), `bands` for the front, then `bands` for the back (zeros when
    /// one-sided).
    pub values: Vec<f32>,
}

/// Radiosity (W/m^2) per patch, side and corner, and at the T-junctions on patch edges.
#[derive(Clone, Debug)]
pub struct CornerValues {
    bands: usize,
    values: Vec<f32>,
    /// By patch, edge and position along it.
    junctions: Vec<Junction>,
    /// Per patch, its first junction; one more entry at the end.
    first_junction: Vec<usize>,
}

impl CornerValues {
    /// Side `side` of patch `i`: 4 corners of `bands` values each (unused corners 0).
    pub fn get(&self, i: usize, side: usize) -> &[f32] {
        let at = (i * 2 + side) * 4 * self.bands;
        &self.values[at..at + 4 * self.bands]
    }

    /// The T-junctions on patch `i`'s edges, in order around it.
    pub fn junctions(&self, i: usize) -> &[Junction] {
        &self.junctions[self.first_junction[i]..self.first_junction[i + 1]]
    }
}
