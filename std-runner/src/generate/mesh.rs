//! Curved shapes for the room and canopy generators, built from planar convex quads (or
//! triangles where a surface closes): surfaces of revolution (turned legs, pots), bent tubes
//! (stems), ribbons (leaves, petals), swept bars (curved chair slats and rails) and slabs
//! with rounded edges (seats, table tops). Every piece is made so that its quads are planar
//! by construction (coaxial rings, or cross-sections sharing one direction), and goes
//! through [`shapes::add_quad`], which splits or drops anything the format would refuse.
//! Lengths in metres.

use crate::generate::shapes::{self, frame};
use crate::scene::Cluster;
use glam::{Vec2, Vec3};
use hirad_core::geometry::Aabb;
use std::f32::consts::{FRAC_PI_2, TAU};

/// Adds a quad turned so that its front faces `outward` (as far as its normal allows).
pub fn quad_facing(c: &mut Cluster, mut p: [Vec3; 4], outward: Vec3, material: u32) -> usize {
    if (p[2] - p[0]).cross(p[3] - p[1]).dot(outward) < 0.0 {
        p.reverse();
    }
    shapes::add_quad(c, p, material)
}

/// A surface of revolution about the axis from `base` along `axis` (unit): `profile` lists
/// (height along the axis, radius) stations, `sides` facets around.
///
/// Fronts face to the outside of a profile that runs up the outside of a solid: a profile
/// going up faces out, one going inward at the top faces up, one going down an inside wall
/// faces the axis. A zero radius closes the surface with a fan of triangles.
pub fn lathe(
    c: &mut Cluster,
    base: Vec3,
    axis: Vec3,
    profile: &[(f32, f32)],
    sides: u32,
    material: u32,
) -> usize {
    if sides < 3 {
        return 0;
    }
    let (u, v) = frame(axis);
    let at = |(h, r): (f32, f32), k: u32| {
        let t = (k % sides) as f32 / sides as f32 * TAU;
        base + axis * h + (u * t.cos() + v * t.sin()) * r
    };
    let mut n = 0;
    for w in profile.windows(2) {
        let (a, b) = (w[0], w[1]);
        for k in 0..sides {
            // Counter-clockwise about the axis, then along the profile: around x profile
            // points out of the solid.
            let p = [at(a, k), at(a, k + 1), at(b, k + 1), at(b, k)];
            n += if a.1 == 0.0 {
                shapes::add_triangle(c, [p[0], p[2], p[3]], material) as usize
            } else if b.1 == 0.0 {
                shapes::add_triangle(c, [p[0], p[1], p[2]], material) as usize
            } else {
                shapes::add_quad(c, p, material)
            };
        }
    }
    n
}

/// A bent tube through `path` with radius `radii[i]` at `path[i]`: one frustum of `sides`
/// outward quads per segment (each with coaxial rings, so its quads are planar); no caps.
pub fn tube(c: &mut Cluster, path: &[Vec3], radii: &[f32], sides: u32, material: u32) -> usize {
    let mut n = 0;
    for (i, w) in path.windows(2).enumerate() {
        n += shapes::cylinder(c, w[0], w[1], radii[i], radii[i + 1], sides, material);
    }
    n
}

/// A ribbon along `spine`, `widths[i]` wide at `spine[i]`, its cross-sections all along
/// `side` (unit): each piece is a planar trapezoid (a triangle where a width is zero). The
/// fronts are the side `up` faces at the first segment, the same side all along, so a leaf
/// that arches over keeps its upper face as its front.
pub fn ribbon(
    c: &mut Cluster,
    spine: &[Vec3],
    widths: &[f32],
    side: Vec3,
    up: Vec3,
    material: u32,
) -> usize {
    if spine.len() < 2 {
        return 0;
    }
    // Quad (l_i, r_i, r_i+1, l_i+1) has normal side x along.
    let side = if side.cross(spine[1] - spine[0]).dot(up) < 0.0 {
        -side
    } else {
        side
    };
    let mut n = 0;
    for i in 0..spine.len() - 1 {
        let (w0, w1) = (widths[i] * 0.5, widths[i + 1] * 0.5);
        let (l0, r0) = (spine[i] - side * w0, spine[i] + side * w0);
        let (l1, r1) = (spine[i + 1] - side * w1, spine[i + 1] + side * w1);
        n += if w0 <= 0.0 {
            shapes::add_triangle(c, [l0, r1, l1], material) as usize
        } else if w1 <= 0.0 {
            shapes::add_triangle(c, [l0, r0, r1], material) as usize
        } else {
            shapes::add_quad(c, [l0, r0, r1, l1], material)
        };
    }
    n
}

/// A bar of rectangular section swept along `spine`, a curve in a plane whose normal is
/// `binormal` (unit): `width` along the binormal, `thickness` across it in the plane.
/// Outward fronts, both ends capped; 4 quads per segment plus 2.
pub fn bar(
    c: &mut Cluster,
    spine: &[Vec3],
    binormal: Vec3,
    width: f32,
    thickness: f32,
    material: u32,
) -> usize {
    let m = spine.len();
    if m < 2 {
        return 0;
    }
    let tangent = |i: usize| (spine[(i + 1).min(m - 1)] - spine[i.saturating_sub(1)]).normalize();
    let normals: Vec<Vec3> = (0..m)
        .map(|i| binormal.cross(tangent(i)).normalize())
        .collect();
    let (b, h) = (binormal * (width * 0.5), thickness * 0.5);
    let corner = |i: usize, sb: f32, sn: f32| spine[i] + b * sb + normals[i] * (h * sn);
    let mut n = 0;
    for i in 0..m - 1 {
        let out_n = (normals[i] + normals[i + 1]).normalize();
        for (sb, sn, out) in [
            (1.0, 0.0, binormal),
            (-1.0, 0.0, -binormal),
            (0.0, 1.0, out_n),
            (0.0, -1.0, -out_n),
        ] {
            // Two edges of the face: along the binormal (sn fixed) or across it (sb fixed).
            let p = if sb != 0.0 {
                [
                    corner(i, sb, -1.0),
                    corner(i, sb, 1.0),
                    corner(i + 1, sb, 1.0),
                    corner(i + 1, sb, -1.0),
                ]
            } else {
                [
                    corner(i, -1.0, sn),
                    corner(i, 1.0, sn),
                    corner(i + 1, 1.0, sn),
                    corner(i + 1, -1.0, sn),
                ]
            };
            n += quad_facing(c, p, out, material);
        }
    }
    for (i, out) in [(0, -tangent(0)), (m - 1, tangent(m - 1))] {
        let p = [
            corner(i, -1.0, -1.0),
            corner(i, 1.0, -1.0),
            corner(i, 1.0, 1.0),
            corner(i, -1.0, 1.0),
        ];
        n += quad_facing(c, p, out, material);
    }
    n
}

/// A horizontal slab with a rounded-rectangle outline and rounded edges (seat, table top).
#[derive(Clone, Copy, Debug)]
pub struct Slab {
    /// Centre of the bottom face (m).
    pub bottom: Vec3,
    /// Half length (x) and half depth (y) of the outline (m).
    pub half: Vec2,
    /// Radius of the outline's corners (m); at least `edge_radius`.
    pub corner_radius: f32,
    /// Height (m).
    pub thickness: f32,
    /// Radius of the rounded edges (m); below half the thickness.
    pub edge_radius: f32,
    /// Facets per outline corner.
    pub corner_segments: u32,
    /// Facets per rounded edge (each of the lower and upper one).
    pub edge_segments: u32,
}

impl Slab {
    /// The outline inset by `d` (m), counter-clockwise seen from above.
    fn outline(&self, d: f32, z: f32) -> Vec<Vec3> {
        let rc = self.corner_radius;
        let cs = self.corner_segments.max(1);
        let mut pts = Vec::with_capacity(4 * (cs as usize + 1));
        for (q, (sx, sy)) in [(1.0, -1.0), (1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0)]
            .into_iter()
            .enumerate()
        {
            let centre = Vec2::new(sx * (self.half.x - rc), sy * (self.half.y - rc));
            for k in 0..=cs {
                let t = -FRAC_PI_2 + (q as f32 + k as f32 / cs as f32) * FRAC_PI_2;
                let p = centre + Vec2::new(t.cos(), t.sin()) * (rc - d);
                pts.push(self.bottom + Vec3::new(p.x, p.y, z));
            }
        }
        pts
    }

    /// Adds the slab; returns the polygons added.
    pub fn build(&self, c: &mut Cluster, material: u32) -> usize {
        let (er, m) = (self.edge_radius, self.edge_segments.max(1));
        // Profile stations (inset, height): the lower rounded edge, then the upper one.
        let mut rings = Vec::new();
        for (centre, from) in [(er, -FRAC_PI_2), (self.thickness - er, 0.0)] {
            for i in 0..=m {
                let a = from + FRAC_PI_2 * i as f32 / m as f32;
                rings.push(self.outline(er * (1.0 - a.cos()), centre + er * a.sin()));
            }
        }
        let mut n = 0;
        for w in rings.windows(2) {
            let (a, b) = (&w[0], &w[1]);
            for k in 0..a.len() {
                let k1 = (k + 1) % a.len();
                n += shapes::add_quad(c, [a[k], a[k1], b[k1], b[k]], material);
            }
        }
        // Top and bottom faces: strips between the outline's back half (+y, running from
        // +x to -x) and its mirror image, each strip a planar convex trapezoid.
        let cs = self.corner_segments.max(1) as usize + 1;
        let mirror = |p: Vec3| Vec3::new(p.x, 2.0 * self.bottom.y - p.y, p.z);
        for (ring, up) in [(&rings[rings.len() - 1], true), (&rings[0], false)] {
            for w in ring[cs..3 * cs].windows(2) {
                let (a, b) = (w[0], w[1]);
                let mut q = [mirror(a), a, b, mirror(b)];
                if !up {
                    q.reverse();
                }
                n += shapes::add_quad(c, q, material);
            }
        }
        n
    }
}

/// Profile of a turned (lathe-made) leg of `height` (m) and base radius `radius` (m):
/// `stations + 1` heights, a slight taper, and smooth beads of 25% extra radius centred at
/// the given fractions of the height.
pub fn turned_profile(height: f32, radius: f32, stations: u32, beads: &[f32]) -> Vec<(f32, f32)> {
    let stations = stations.max(1);
    (0..=stations)
        .map(|i| {
            let t = i as f32 / stations as f32;
            let bump: f32 = beads
                .iter()
                .map(|&b| {
                    let x = (t - b) / 0.06;
                    if x.abs() < 1.0 {
                        0.25 * (0.5 + 0.5 * (x * std::f32::consts::PI).cos())
                    } else {
                        0.0
                    }
                })
                .sum();
            (height * t, radius * (1.0 - 0.2 * t + bump))
        })
        .collect()
}

/// Box of every vertex of a tree of plain clusters (instances inside are not followed).
pub fn bounds(c: &Cluster) -> Aabb {
    let mut b = Aabb::EMPTY;
    for v in &c.vertices {
        b.include(*v);
    }
    c.children.iter().fold(b, |b, ch| b.union(bounds(ch)))
}

/// Number of polygons in a tree of plain clusters.
pub fn polygon_count(c: &Cluster) -> usize {
    c.polygons.len() + c.children.iter().map(polygon_count).sum::<usize>()
}

#[cfg(test)]
mod tests {
    use super::*;
    use hirad_core::geometry::polygon_shape;

    /// Corners and unit normal of every polygon of `c`.
    fn faces(c: &Cluster) -> Vec<(Vec<Vec3>, Vec3)> {
        c.polygons
            .iter()
            .map(|p| {
                let k: Vec<Vec3> = p.corners[..p.corner_count()]
                    .iter()
                    .map(|&i| c.vertices[i as usize])
                    .collect();
                let n = polygon_shape(&k).unwrap().normal;
                (k, n)
            })
            .collect()
    }

    fn centroid(k: &[Vec3]) -> Vec3 {
        k.iter().copied().sum::<Vec3>() / k.len() as f32
    }

    #[test]
    fn lathe_faces_out_and_closes_with_fans() {
        let mut c = Cluster::default();
        // A spindle: pole, bulge, pole.
        let n = lathe(
            &mut c,
            Vec3::ONE,
            Vec3::Z,
            &[(0.0, 0.0), (0.5, 0.2), (1.0, 0.2), (1.5, 0.0)],
            8,
            0,
        );
        assert_eq!(n, 24);
        assert_eq!(
            c.polygons.iter().filter(|p| p.corner_count() == 4).count(),
            8
        );
        for (k, nrm) in faces(&c) {
            let m = centroid(&k);
            let radial = m - Vec3::new(1.0, 1.0, m.z);
            assert!(nrm.dot(radial) > 0.0);
        }
    }

    #[test]
    fn slab_and_bar_are_closed_outward_solids() {
        for (c, centre) in [
            {
                let mut c = Cluster::default();
                let s = Slab {
                    bottom: Vec3::new(0.0, 0.0, 0.5),
                    half: Vec2::new(0.9, 0.45),
                    corner_radius: 0.06,
                    thickness: 0.04,
                    edge_radius: 0.012,
                    corner_segments: 4,
                    edge_segments: 3,
                };
                let n = s.build(&mut c, 0);
                // 7 bands of 20 quads, and 9 strips on each of the top and the bottom.
                assert_eq!(n, 7 * 20 + 18);
                (c, Vec3::new(0.0, 0.0, 0.52))
            },
            {
                let mut c = Cluster::default();
                let spine: Vec<Vec3> = (0..=8)
                    .map(|i| {
                        let t = i as f32 / 8.0 - 0.5;
                        Vec3::new(t, 0.1 * (1.0 - 4.0 * t * t), 0.0)
                    })
                    .collect();
                assert_eq!(bar(&mut c, &spine, Vec3::Z, 0.05, 0.02, 0), 34);
                (c, Vec3::new(0.0, 0.0, 0.0))
            },
        ] {
            // Convex-ish solids: every face's normal points away from an interior point
            // near the face (its centroid pushed inward along the normal).
            let b = bounds(&c);
            assert!(b.contains(&Aabb::new(centre, centre)));
            for (k, nrm) in faces(&c) {
                let m = centroid(&k);
                let inside = m - nrm * 1e-3;
                assert!(b.contains(&Aabb::new(inside, inside)), "{k:?} {nrm}");
            }
        }
    }

    #[test]
    fn ribbon_keeps_one_front() {
        let mut c = Cluster::default();
        // Arches over: up, then out, then down.
        let spine = [
            Vec3::ZERO,
            Vec3::new(0.1, 0.0, 0.3),
            Vec3::new(0.3, 0.0, 0.4),
            Vec3::new(0.5, 0.0, 0.3),
            Vec3::new(0.6, 0.0, 0.1),
        ];
        let n = ribbon(
            &mut c,
            &spine,
            &[0.0, 0.05, 0.06, 0.04, 0.0],
            Vec3::Y,
            Vec3::Z,
            0,
        );
        assert_eq!(n, 4);
        // The front faces up on the way up (-x side) and out on the way down (+x side):
        // every normal points away from the arch's inside at (0.3, 0, 0).
        for (k, nrm) in faces(&c) {
            assert!(nrm.y.abs() < 1e-5);
            assert!(
                nrm.dot(centroid(&k) - Vec3::new(0.3, 0.0, 0.0)) > 0.0,
                "{nrm}"
            );
        }
    }

    #[test]
    fn turned_profile_has_beads() {
        let p = turned_profile(0.5, 0.02, 20, &[0.5]);
        assert_eq!(p.len(), 21);
        assert!(p[10].1 > p[8].1 && p[10].1 > p[12].1);
        assert_eq!(p[20].0, 0.5);
    }
}
