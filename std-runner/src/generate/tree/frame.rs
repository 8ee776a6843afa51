//! Frames of axes: the centre line of an axis in its canonical frame, where its laterals go,
//! and how a grown axis becomes an instance (its geometry rescaled into the instance's local
//! frame, the transform placing it on its parent).

use crate::generate::rng::Rng;
use crate::generate::shapes::frame;
use crate::scene::{Cluster, InstanceOf, Similarity};
use glam::{Mat3, Quat, Vec3};

/// The centre line of an axis: a polyline from the origin, along +z, bending towards +x.
#[derive(Clone, Debug)]
pub struct Centerline {
    /// `segments + 1` points (m).
    pub points: Vec<Vec3>,
}

impl Centerline {
    /// A line of `length` (m) in `segments` straight pieces, turning by `bend` radians in
    /// total towards +x, each piece jittered by up to `wobble` radians either way.
    pub fn new(length: f32, segments: u32, bend: f32, wobble: f32, rng: &mut Rng) -> Self {
        let segments = segments.max(1);
        let step = length / segments as f32;
        let mut points = Vec::with_capacity(segments as usize + 1);
        let mut p = Vec3::ZERO;
        points.push(p);
        for i in 0..segments {
            let phi = bend * (i as f32 + 0.5) / segments as f32;
            let d = Vec3::new(
                phi.sin() + rng.range(-wobble, wobble),
                rng.range(-wobble, wobble),
                phi.cos(),
            )
            .normalize();
            p += d * step;
            points.push(p);
        }
        Centerline { points }
    }

    /// Number of straight pieces.
    pub fn segments(&self) -> usize {
        self.points.len() - 1
    }

    /// The point and unit tangent at fraction `t` (0 = base, 1 = tip) of the length.
    pub fn at(&self, t: f32) -> (Vec3, Vec3) {
        let n = self.segments();
        let s = (t.clamp(0.0, 1.0) * n as f32).min(n as f32);
        let i = (s.floor() as usize).min(n - 1);
        let (a, b) = (self.points[i], self.points[i + 1]);
        (a.lerp(b, s - i as f32), (b - a).normalize())
    }
}

/// A rotation whose local +z is `d` (unit) and whose local +x points as much as possible
/// along `towards` (so that an axis that bends towards its local +x bends towards it).
pub fn basis(d: Vec3, towards: Vec3) -> Quat {
    let x = (towards - d * towards.dot(d))
        .try_normalize()
        .unwrap_or_else(|| frame(d).0);
    let y = d.cross(x);
    Quat::from_mat3(&Mat3::from_cols(x, y, d)).normalize()
}

/// Where a lateral goes in its parent's frame: the parent point (m) and the rotation.
#[derive(Clone, Copy, Debug)]
pub struct Placement {
    /// Insertion point on the parent's centre line (m).
    pub at: Vec3,
    /// Takes the lateral's canonical frame to the parent's.
    pub rotation: Quat,
}

impl Placement {
    /// The similarity that places a lateral drawn at `scale` times its local size.
    pub fn similarity(&self, scale: f32) -> Similarity {
        Similarity {
            rotation: self.rotation,
            translation: self.at,
            scale,
        }
    }
}

/// Multiplies the size of a node's content by `factor`: own vertices, plain sub-clusters,
/// and the placement (translation and scale) of every instance inside, whose own content is
/// in its own frame and stays as it is.
pub fn rescale(c: &mut Cluster, factor: f32) {
    for v in &mut c.vertices {
        *v *= factor;
    }
    for child in &mut c.children {
        match &mut child.instance {
            Some(i) => {
                i.transform.translation *= factor;
                i.transform.scale *= factor;
            }
            None => rescale(child, factor),
        }
    }
}

/// Turns an axis grown at full size (`length`, m) into an approximate instance of an
/// original whose axis is `original_length` long: the geometry is rescaled into the local
/// frame of the original's size, and the transform scales it back up on its parent.
pub fn approximate(
    mut grown: Cluster,
    length: f32,
    original: usize,
    original_length: f32,
    place: &Placement,
) -> Cluster {
    let scale = length / original_length;
    rescale(&mut grown, 1.0 / scale);
    grown.instance = Some(InstanceOf {
        original,
        exact: false,
        transform: place.similarity(scale),
    });
    grown
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centerline_length_and_bend() {
        let mut r = Rng::new(3);
        let c = Centerline::new(2.0, 5, 0.5, 0.0, &mut r);
        let len: f32 = c.points.windows(2).map(|w| (w[1] - w[0]).length()).sum();
        assert!((len - 2.0).abs() < 1e-5);
        let (p, t) = c.at(1.0);
        assert!(p.x > 0.0 && t.x > 0.0 && (t.length() - 1.0).abs() < 1e-5);
        assert_eq!(c.at(0.0).0, Vec3::ZERO);
    }

    #[test]
    fn basis_maps_z_and_x() {
        let d = Vec3::new(0.5, 0.2, 0.8).normalize();
        let q = basis(d, Vec3::Z);
        assert!((q * Vec3::Z - d).length() < 1e-5);
        let x = q * Vec3::X;
        assert!(x.dot(d).abs() < 1e-5 && x.dot(Vec3::Z) > 0.0);
        assert!((q.length_squared() - 1.0).abs() < 1e-5);
    }

    #[test]
    fn approximate_keeps_world_geometry() {
        let mut c = Cluster::default();
        c.vertex(Vec3::new(0.0, 0.0, 3.0));
        let place = Placement {
            at: Vec3::new(1.0, 0.0, 0.0),
            rotation: Quat::IDENTITY,
        };
        let inst = approximate(c, 3.0, 0, 1.5, &place);
        let t = inst.instance.unwrap().transform;
        assert!((t.point(inst.vertices[0]) - Vec3::new(1.0, 0.0, 3.0)).length() < 1e-6);
        assert_eq!(t.scale, 2.0);
    }
}
