//! Random leaf canopies over a soil of quads, and the exact direct light on the soil computed
//! by projection, apart from every ray caster: a soil point is lit by a directional source
//! iff its position misses the shadow of every leaf, the leaf's corners projected along the
//! source onto the soil plane (a convex quadrilateral).

use crate::Rng;
use glam::{DVec2, DVec3};

/// A random canopy: square leaves with normals uniform on the sphere (the spherical leaf
/// angle distribution), centres uniform in a box, over a soil of square quads.
#[derive(Clone, Debug)]
pub struct RandomCanopy {
    /// Side of a leaf (m).
    pub leaf: f64,
    /// Leaf area index: leaf area over the leaves' ground area.
    pub lai: f64,
    /// Half width of the square over which leaf centres and soil spread (m).
    pub half: f64,
    /// Height range of leaf centres (m).
    pub slab: (f64, f64),
    /// Side of a soil quad (m).
    pub soil_quad: f64,
    /// Seed of the leaves.
    pub seed: u32,
    /// Directions towards the sources (unit, z > 0) and their irradiance on a plane facing
    /// them (W/m^2): the first `suns` are written as suns, the rest as sky directions.
    pub sources: Vec<(DVec3, f64)>,
    /// How many of `sources` are suns.
    pub suns: usize,
}

impl RandomCanopy {
    /// Leaves of `leaf` m at LAI 2 over a square of half width `half` (soil quads of 0.5 m,
    /// leaves 0.5 to 1.1 m up), lit by one sun of 1000 W/m^2 at `zenith` degrees, azimuth
    /// `azimuth` degrees.
    pub fn new(leaf: f64, half: f64, zenith: f64, azimuth: f64, seed: u32) -> Self {
        RandomCanopy {
            leaf,
            lai: 2.0,
            half,
            slab: (0.5, 1.1),
            soil_quad: 0.5,
            seed,
            sources: vec![(direction(zenith, azimuth), 1000.0)],
            suns: 1,
        }
    }

    /// The number of leaves.
    pub fn leaf_count(&self) -> usize {
        let ground = (2.0 * self.half) * (2.0 * self.half);
        (self.lai * ground / (self.leaf * self.leaf)).round() as usize
    }

    /// Soil quads along a side.
    pub fn soil_side(&self) -> usize {
        (2.0 * self.half / self.soil_quad).round() as usize
    }

    /// Every leaf's four corners (counter-clockwise about its normal).
    pub fn leaves(&self) -> Vec<[DVec3; 4]> {
        let mut r = Rng(self.seed, 0);
        let h = 0.5 * self.leaf;
        (0..self.leaf_count())
            .map(|_| {
                let cz = r.range(-1.0, 1.0) as f64;
                let phi = r.range(0.0, std::f32::consts::TAU) as f64;
                let s = (1.0 - cz * cz).max(0.0).sqrt();
                let n = DVec3::new(s * phi.cos(), s * phi.sin(), cz);
                let (u, v) = n.any_orthonormal_pair();
                let spin = r.range(0.0, std::f32::consts::TAU) as f64;
                let (u, v) = (
                    u * spin.cos() + v * spin.sin(),
                    v * spin.cos() - u * spin.sin(),
                );
                let c = DVec3::new(
                    r.range(-1.0, 1.0) as f64 * self.half,
                    r.range(-1.0, 1.0) as f64 * self.half,
                    self.slab.0 + (self.slab.1 - self.slab.0) * r.unit() as f64,
                );
                [
                    c - u * h - v * h,
                    c + u * h - v * h,
                    c + u * h + v * h,
                    c - u * h + v * h,
                ]
            })
            .collect()
    }

    /// The soil quad `(i, j)`'s corners (z = 0).
    pub fn soil(&self, i: usize, j: usize) -> [DVec3; 4] {
        let (x0, y0) = (
            -self.half + i as f64 * self.soil_quad,
            -self.half + j as f64 * self.soil_quad,
        );
        let q = self.soil_quad;
        [
            DVec3::new(x0, y0, 0.0),
            DVec3::new(x0 + q, y0, 0.0),
            DVec3::new(x0 + q, y0 + q, 0.0),
            DVec3::new(x0, y0 + q, 0.0),
        ]
    }

    /// The scene in the text format: black soil quads (row `j * side + i`, in one cluster),
    /// then the black leaves (two-sided, in a cluster), one band.
    pub fn text(&self) -> String {
        let mut t = String::from(
            "hirad 1\nbands 1\nmaterial soil rho 0\nmaterial leaf rho 0 back_rho 0 tau 0\n",
        );
        for (k, (d, e)) in self.sources.iter().enumerate() {
            let kind = if k < self.suns { "sun" } else { "sky" };
            t += &format!("{kind} from {} {} {} irradiance {e}\n", d.x, d.y, d.z);
        }
        t += "scene {\n  cluster soil {\n";
        let n = self.soil_side();
        for j in 0..n {
            for i in 0..n {
                t += &quad_line("soil", &self.soil(i, j));
            }
        }
        t += "  }\n  cluster canopy {\n";
        for l in self.leaves() {
            t += &quad_line("leaf", &l);
        }
        t += "  }\n}\n";
        t
    }

    /// The soil quads whose shadows come from leaves on every side: at least the farthest
    /// shadow's reach (the highest leaf along the lowest source) plus a leaf from the edge.
    pub fn central(&self) -> Vec<(usize, usize)> {
        let reach = self
            .sources
            .iter()
            .map(|(d, _)| {
                let slope = (d.x * d.x + d.y * d.y).sqrt() / d.z;
                (self.slab.1 + self.leaf) * slope
            })
            .fold(0.0f64, f64::max)
            + self.leaf;
        let n = self.soil_side();
        let inside = |k: usize| {
            let lo = -self.half + k as f64 * self.soil_quad;
            lo >= -self.half + reach && lo + self.soil_quad <= self.half - reach
        };
        let mut out = Vec::new();
        for j in 0..n {
            for i in 0..n {
                if inside(i) && inside(j) {
                    out.push((i, j));
                }
            }
        }
        out
    }
}

/// The unit direction at `zenith` degrees from +z, `azimuth` degrees from +x towards +y.
pub fn direction(zenith: f64, azimuth: f64) -> DVec3 {
    let (z, a) = (zenith.to_radians(), azimuth.to_radians());
    DVec3::new(z.sin() * a.cos(), z.sin() * a.sin(), z.cos())
}

fn quad_line(mat: &str, c: &[DVec3; 4]) -> String {
    let mut s = format!("    quad {mat}");
    for p in c {
        s += &format!("  {} {} {}", p.x as f32, p.y as f32, p.z as f32);
    }
    s + "\n"
}

/// Shadows of polygons on the plane z = 0 along one direction, bucketed on a grid.
pub struct Shadows {
    /// Convex shadow polygons, counter-clockwise.
    polys: Vec<Vec<DVec2>>,
    lo: DVec2,
    cell: f64,
    nx: usize,
    ny: usize,
    buckets: Vec<Vec<u32>>,
}

impl Shadows {
    /// The shadows of `polygons` (planar convex, corners as written by the scene, so
    /// exactly the f32 values the solver sees) cast along `towards` (unit, z > 0).
    pub fn new(polygons: &[[DVec3; 4]], towards: DVec3) -> Self {
        let mut polys = Vec::with_capacity(polygons.len());
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        let mut size = 0.0f64;
        for p in polygons {
            let mut q: Vec<DVec2> = p
                .iter()
                .map(|c| {
                    let c = c.as_vec3().as_dvec3();
                    let t = c.z / towards.z;
                    DVec2::new(c.x - t * towards.x, c.y - t * towards.y)
                })
                .collect();
            // Counter-clockwise (the projection of a leaf seen from below is clockwise).
            let area2: f64 = (0..q.len())
                .map(|k| q[k].perp_dot(q[(k + 1) % q.len()]))
                .sum();
            if area2 < 0.0 {
                q.reverse();
            }
            let (mut a, mut b) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
            for c in &q {
                a = a.min(*c);
                b = b.max(*c);
            }
            lo = lo.min(a);
            hi = hi.max(b);
            size = size.max((b - a).max_element());
            polys.push(q);
        }
        let cell = size.max(1e-9);
        let nx = (((hi.x - lo.x) / cell).ceil() as usize).clamp(1, 4096);
        let ny = (((hi.y - lo.y) / cell).ceil() as usize).clamp(1, 4096);
        let cell = ((hi.x - lo.x) / nx as f64)
            .max((hi.y - lo.y) / ny as f64)
            .max(1e-9);
        let mut buckets = vec![Vec::new(); nx * ny];
        for (k, q) in polys.iter().enumerate() {
            let (mut a, mut b) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
            for c in q {
                a = a.min(*c);
                b = b.max(*c);
            }
            let (i0, j0) = cell_of(a, lo, cell, nx, ny);
            let (i1, j1) = cell_of(b, lo, cell, nx, ny);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    buckets[j * nx + i].push(k as u32);
                }
            }
        }
        Shadows {
            polys,
            lo,
            cell,
            nx,
            ny,
            buckets,
        }
    }

    /// True when `x` lies inside no shadow (edges count as shadow).
    pub fn lit(&self, x: DVec2) -> bool {
        let rel = (x - self.lo) / self.cell;
        if rel.x < 0.0 || rel.y < 0.0 || rel.x >= self.nx as f64 || rel.y >= self.ny as f64 {
            return true;
        }
        let (i, j) = cell_of(x, self.lo, self.cell, self.nx, self.ny);
        !self.buckets[j * self.nx + i].iter().any(|&k| {
            let q = &self.polys[k as usize];
            (0..q.len()).all(|e| (q[(e + 1) % q.len()] - q[e]).perp_dot(x - q[e]) >= 0.0)
        })
    }

    /// The lit fraction of the axis-aligned rectangle `lo..hi` on the plane, from `n x n`
    /// cell centres.
    pub fn lit_fraction(&self, lo: DVec2, hi: DVec2, n: usize) -> f64 {
        let mut lit = 0usize;
        for b in 0..n {
            for a in 0..n {
                let t = DVec2::new((a as f64 + 0.5) / n as f64, (b as f64 + 0.5) / n as f64);
                lit += self.lit(lo + (hi - lo) * t) as usize;
            }
        }
        lit as f64 / (n * n) as f64
    }
}

fn cell_of(x: DVec2, lo: DVec2, cell: f64, nx: usize, ny: usize) -> (usize, usize) {
    let r = (x - lo) / cell;
    (
        (r.x.max(0.0) as usize).min(nx - 1),
        (r.y.max(0.0) as usize).min(ny - 1),
    )
}

/// The exact direct irradiance (W/m^2) of every central soil quad of `c`, in `central()`
/// order: per source, its irradiance times the cosine times the lit fraction from `n x n`
/// points.
pub fn soil_reference(c: &RandomCanopy, n: usize) -> Vec<f64> {
    let leaves = c.leaves();
    let shadows: Vec<(Shadows, f64)> = c
        .sources
        .iter()
        .map(|(d, e)| (Shadows::new(&leaves, *d), e * d.z))
        .collect();
    c.central()
        .iter()
        .map(|&(i, j)| {
            let q = c.soil(i, j);
            let (lo, hi) = (q[0].truncate(), q[2].truncate());
            shadows
                .iter()
                .map(|(s, e)| e * s.lit_fraction(lo, hi, n))
                .sum()
        })
        .collect()
}
