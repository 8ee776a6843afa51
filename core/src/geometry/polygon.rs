//! The shape of a triangle or quad: area, normal, and the checks that make a polygon usable.
//!
//! Front is the side from which the corners run counter-clockwise. A quad must be planar and
//! strictly convex so that it can be subdivided bilinearly. Tolerances are relative to the
//! polygon's own size, so the same polygon is accepted in millimetres and in kilometres.

use glam::Vec3;

/// A polygon is degenerate when twice its area is at most this times its longest edge squared.
pub const DEGENERATE_REL: f32 = 1e-6;

/// A quad is planar when every corner lies within this fraction of its longest diagonal
/// from the plane through its centroid.
pub const PLANAR_REL: f32 = 1e-3;

/// Area and orientation of an accepted polygon.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PolygonShape {
    /// Area (m^2).
    pub area: f32,
    /// Unit normal on the front side.
    pub normal: Vec3,
}

/// Why a polygon is refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShapeError {
    /// A corner coordinate is NaN or infinite.
    NonFinite,
    /// Finite corners, but so far apart that edges or area overflow f32.
    TooLarge,
    /// Zero (or vanishing) area: repeated or collinear corners.
    Degenerate,
    /// A quad whose corners do not lie in one plane.
    NonPlanar,
    /// A quad that is not strictly convex (a dart, a bow-tie or a straight corner).
    NonConvex,
}

impl core::fmt::Display for ShapeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            ShapeError::NonFinite => "a corner is not a finite number",
            ShapeError::TooLarge => {
                "the polygon is too large to measure in f32 (rescale the scene)"
            }
            ShapeError::Degenerate => "the polygon has no area (repeated or collinear corners)",
            ShapeError::NonPlanar => "the quad is not planar; split it into two triangles",
            ShapeError::NonConvex => "the quad is not strictly convex; split it into two triangles",
        })
    }
}

/// Checks a triangle (3 corners) or quad (4 corners) and returns its area and normal.
///
/// Any other corner count is [`ShapeError::Degenerate`].
pub fn polygon_shape(corners: &[Vec3]) -> Result<PolygonShape, ShapeError> {
    if corners.iter().any(|c| !c.is_finite()) {
        return Err(ShapeError::NonFinite);
    }
    let n = corners.len();
    if n != 3 && n != 4 {
        return Err(ShapeError::Degenerate);
    }
    // Measure relative to the first corner, scaled by a power of two (exact) so that edges
    // lie within [-2, 2]: huge and tiny polygons are judged like unit ones.
    let mut d = [Vec3::ZERO; 4];
    let mut m = 0.0f32;
    for (di, c) in d.iter_mut().zip(corners) {
        *di = *c - corners[0];
        if !di.is_finite() {
            return Err(ShapeError::TooLarge);
        }
        m = m.max(di.abs().max_element());
    }
    let s = f32::from_bits(m.to_bits() & 0x7F80_0000);
    if s == 0.0 {
        return Err(ShapeError::Degenerate);
    }
    for di in d.iter_mut() {
        *di /= s;
    }
    let shape = match n {
        3 => triangle(d[0], d[1], d[2]),
        _ => quad(d[0], d[1], d[2], d[3]),
    }?;
    let area = shape.area * s * s;
    if !area.is_finite() {
        return Err(ShapeError::TooLarge);
    }
    Ok(PolygonShape {
        area,
        normal: shape.normal,
    })
}

fn triangle(a: Vec3, b: Vec3, c: Vec3) -> Result<PolygonShape, ShapeError> {
    let (e0, e1, e2) = (b - a, c - b, a - c);
    let longest2 = e0
        .length_squared()
        .max(e1.length_squared())
        .max(e2.length_squared());
    let n = e0.cross(c - a);
    shape_from(n, longest2)
}

fn quad(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> Result<PolygonShape, ShapeError> {
    let p = [a, b, c, d];
    let mut longest2 = 0.0f32;
    for i in 0..4 {
        longest2 = longest2.max((p[(i + 1) % 4] - p[i]).length_squared());
    }
    // The cross product of the diagonals is twice the vector area of any quad.
    let (d0, d1) = (c - a, d - b);
    let n = d0.cross(d1);
    let shape = shape_from(n, longest2)?;
    let size = d0.length().max(d1.length());
    let centroid = (a + b + c + d) * 0.25;
    for q in p {
        if (q - centroid).dot(shape.normal).abs() > PLANAR_REL * size {
            return Err(ShapeError::NonPlanar);
        }
    }
    for i in 0..4 {
        let e_in = p[i] - p[(i + 3) % 4];
        let e_out = p[(i + 1) % 4] - p[i];
        if e_in.cross(e_out).dot(shape.normal) <= DEGENERATE_REL * longest2 {
            return Err(ShapeError::NonConvex);
        }
    }
    Ok(shape)
}

fn shape_from(n: Vec3, longest2: f32) -> Result<PolygonShape, ShapeError> {
    let len = n.length();
    if !len.is_finite() || !longest2.is_finite() {
        return Err(ShapeError::NonFinite);
    }
    if len <= DEGENERATE_REL * longest2 || len == 0.0 {
        return Err(ShapeError::Degenerate);
    }
    Ok(PolygonShape {
        area: 0.5 * len,
        normal: n / len,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f32, y: f32, z: f32) -> Vec3 {
        Vec3::new(x, y, z)
    }

    #[test]
    fn unit_square_and_triangle() {
        let s =
            polygon_shape(&[v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)]).unwrap();
        assert_eq!(s.area, 1.0);
        assert_eq!(s.normal, v(0., 0., 1.));
        let t = polygon_shape(&[v(0., 0., 0.), v(0., 1., 0.), v(1., 0., 0.)]).unwrap();
        assert_eq!(t.area, 0.5);
        assert_eq!(t.normal, v(0., 0., -1.));
    }

    #[test]
    fn scale_free() {
        for s in [1e-3f32, 1.0, 1e3, 1e6] {
            let q = [v(0., 0., 0.), v(s, 0., 0.), v(s, s, 0.), v(0., s, 0.)];
            let shape = polygon_shape(&q).unwrap();
            assert!((shape.area / (s * s) - 1.0).abs() < 1e-6);
            let sliver = [v(0., 0., 0.), v(s, 0., 0.), v(s, s * 1e-8, 0.)];
            assert_eq!(polygon_shape(&sliver), Err(ShapeError::Degenerate));
            let bent = [v(0., 0., 0.), v(s, 0., 0.), v(s, s, s * 0.1), v(0., s, 0.)];
            assert_eq!(polygon_shape(&bent), Err(ShapeError::NonPlanar));
        }
    }

    #[test]
    fn refuses_bad_quads() {
        let dart = [v(0., 0., 0.), v(2., 0., 0.), v(0.5, 0.5, 0.), v(0., 2., 0.)];
        assert_eq!(polygon_shape(&dart), Err(ShapeError::NonConvex));
        let bowtie = [v(0., 0., 0.), v(1., 1., 0.), v(1., 0., 0.), v(0., 1., 0.)];
        assert!(polygon_shape(&bowtie).is_err());
        let straight = [v(0., 0., 0.), v(1., 0., 0.), v(2., 0., 0.), v(0., 1., 0.)];
        assert_eq!(polygon_shape(&straight), Err(ShapeError::NonConvex));
        let repeated = [v(0., 0., 0.), v(0., 0., 0.), v(1., 0., 0.)];
        assert_eq!(polygon_shape(&repeated), Err(ShapeError::Degenerate));
        let nan = [v(f32::NAN, 0., 0.), v(1., 0., 0.), v(0., 1., 0.)];
        assert_eq!(polygon_shape(&nan), Err(ShapeError::NonFinite));
        let huge = [v(-3e38, 0., 0.), v(3e38, 0., 0.), v(0., 3e38, 0.)];
        assert_eq!(polygon_shape(&huge), Err(ShapeError::TooLarge));
        let big = [v(0., 0., 0.), v(1e19, 0., 0.), v(0., 1e19, 0.)];
        assert_eq!(polygon_shape(&big).unwrap().area, 0.5e38);
        let tiny = [v(0., 0., 0.), v(1e-19, 0., 0.), v(0., 1e-19, 0.)];
        assert!((polygon_shape(&tiny).unwrap().area / 0.5e-38 - 1.0).abs() < 1e-5);
        let far = [
            v(1e6, 1e6, 0.),
            v(1e6 + 1.0, 1e6, 0.),
            v(1e6, 1e6 + 1.0, 0.),
        ];
        assert_eq!(polygon_shape(&far).unwrap().area, 0.5);
    }
}
