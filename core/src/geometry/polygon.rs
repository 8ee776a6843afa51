//! The shape of a triangle or quad: area, normal, and the checks that make a polygon usable.
//!
//! Front is the side from which the corners run counter-clockwise. A quad must be planar and
//! strictly convex so that it can be subdivided bilinearly. Tolerances are relative to the
//! polygon's own size, so the same polygon is accepted in millimetres and in kilometres.
//!
//! A polygon must also be large enough for 32-bit floats at its position: f32 spaces numbers
//! near `x` by 2^-24 to 2^-23 of `|x|`, so corners far from the origin can only sit on a
//! coarse grid. A polygon whose longest edge is below [`RESOLUTION_REL`] (2^-20) times the
//! largest absolute coordinate of its corners (an edge of fewer than 8 to 16 steps of that
//! grid), or whose area is below the smallest normal f32 ([`MIN_AREA`], about 1.2e-38 m^2),
//! is refused as [`ShapeError::TooSmall`]. The rule compares the polygon with its own
//! position, so it holds at every scale.

use glam::Vec3;

/// A polygon is degenerate when twice its area is at most this times its longest edge squared.
pub const DEGENERATE_REL: f32 = 1e-6;

/// A quad is planar when every corner lies within this fraction of its longest diagonal
/// from the plane through its centroid.
pub const PLANAR_REL: f32 = 1e-3;

/// A polygon is too small for f32 at its position when its longest edge is below this times
/// the largest absolute coordinate of its corners (2^-20, about 9.5e-7: a 1 m polygon is
/// accepted 1e6 m from the origin, where f32 coordinates are 0.0625 m apart; a 1 mm one is
/// not).
pub const RESOLUTION_REL: f32 = 1.0 / 1_048_576.0;

/// Smallest accepted polygon area (m^2): the smallest normal f32. Smaller areas underflow
/// or lose their precision.
pub const MIN_AREA: f32 = f32::MIN_POSITIVE;

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
    /// Too small for f32 at its position: the longest edge is below [`RESOLUTION_REL`] times
    /// the largest absolute corner coordinate (corners that coincide away from the origin
    /// included), or the area is below [`MIN_AREA`].
    TooSmall,
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
            ShapeError::TooSmall => {
                "the polygon is too small for 32-bit floats at its position: its longest edge \
                 is below 2^-20 (about 1e-6) of its largest corner coordinate, or its area is \
                 below 1.2e-38 m^2 (move the scene nearer the origin or enlarge the polygon)"
            }
            ShapeError::NonPlanar => "the quad is not planar; split it into two triangles",
            ShapeError::NonConvex => "the quad is not strictly convex; split it into two triangles",
        })
    }
}

/// True when the outline through `corners` (any number, closed) is too short for f32 at its
/// position: its longest edge is below [`RESOLUTION_REL`] times the largest absolute
/// coordinate of its corners. Corners that all coincide are too small unless they sit at the
/// origin. Non-finite corners give false (they are refused for that instead).
pub fn below_f32_resolution(corners: &[Vec3]) -> bool {
    if corners.iter().any(|c| !c.is_finite()) {
        return false;
    }
    // In f64, where squares of any f32 are exact enough and cannot overflow or underflow.
    let n = corners.len();
    let mut reach = 0.0f64;
    let mut longest2 = 0.0f64;
    for i in 0..n {
        let c = corners[i].as_dvec3();
        reach = reach.max(c.abs().max_element());
        longest2 = longest2.max((corners[(i + 1) % n].as_dvec3() - c).length_squared());
    }
    let limit = reach * f64::from(RESOLUTION_REL);
    longest2 < limit * limit
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
    if below_f32_resolution(corners) {
        return Err(ShapeError::TooSmall);
    }
    if m == 0.0 {
        // Every corner at the origin.
        return Err(ShapeError::Degenerate);
    }
    let s = f32::from_bits(m.to_bits() & 0x7F80_0000);
    if s == 0.0 {
        // Subnormal edges: the area underflows.
        return Err(ShapeError::TooSmall);
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
    if area < MIN_AREA {
        return Err(ShapeError::TooSmall);
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
        let small = [v(0., 0., 0.), v(1e-18, 0., 0.), v(0., 1e-18, 0.)];
        assert!((polygon_shape(&small).unwrap().area / 0.5e-36 - 1.0).abs() < 1e-5);
        // Its area, 0.5e-38 m^2, is below the smallest normal f32.
        let tiny = [v(0., 0., 0.), v(1e-19, 0., 0.), v(0., 1e-19, 0.)];
        assert_eq!(polygon_shape(&tiny), Err(ShapeError::TooSmall));
        let far = [
            v(1e6, 1e6, 0.),
            v(1e6 + 1.0, 1e6, 0.),
            v(1e6, 1e6 + 1.0, 0.),
        ];
        assert_eq!(polygon_shape(&far).unwrap().area, 0.5);
    }

    /// A right triangle with legs `size` at corner `at`, in the plane z = at.z.
    fn tri_at(at: Vec3, size: f32) -> [Vec3; 3] {
        [at, at + v(size, 0., 0.), at + v(0., size, 0.)]
    }

    #[test]
    fn too_small_for_f32_at_its_position() {
        // 1e-30 m at the origin: corners are distinct, but the area (5e-61) underflows.
        let t = tri_at(Vec3::ZERO, 1e-30);
        assert!(!below_f32_resolution(&t));
        assert_eq!(polygon_shape(&t), Err(ShapeError::TooSmall));
        // 1e-30 m at (1, 1, 1): the corners collapse onto one point, away from the origin.
        let t = tri_at(v(1., 1., 1.), 1e-30);
        assert!(below_f32_resolution(&t));
        assert_eq!(polygon_shape(&t), Err(ShapeError::TooSmall));
        // Every corner at the origin is plain degenerate.
        assert_eq!(polygon_shape(&[Vec3::ZERO; 3]), Err(ShapeError::Degenerate));
        // Subnormal edges at the origin.
        let t = tri_at(Vec3::ZERO, 1e-40);
        assert_eq!(polygon_shape(&t), Err(ShapeError::TooSmall));
        // 1 um near the origin is fine.
        let t = tri_at(v(1e-3, 2e-3, 0.), 1e-6);
        assert!((polygon_shape(&t).unwrap().area / 0.5e-12 - 1.0).abs() < 1e-3);
        // 1e6 m from the origin f32 steps are 0.0625 m: 1 mm is refused, 1 m accepted.
        let far = v(1e6, 0., 0.);
        assert_eq!(polygon_shape(&tri_at(far, 1e-3)), Err(ShapeError::TooSmall));
        assert_eq!(polygon_shape(&tri_at(far, 0.25)), Err(ShapeError::TooSmall));
        assert_eq!(polygon_shape(&tri_at(far, 1.0)).unwrap().area, 0.5);
        let q = [
            far,
            far + v(1., 0., 0.),
            far + v(1., 1., 0.),
            far + v(0., 1., 0.),
        ];
        assert_eq!(polygon_shape(&q).unwrap().area, 1.0);
        let q = q.map(|c| far + (c - far) * 0.125);
        assert_eq!(polygon_shape(&q), Err(ShapeError::TooSmall));
    }

    #[test]
    fn the_resolution_limit_is_relative_to_the_position() {
        // At the limit exactly (longest edge = 2^-20 x largest coordinate) the polygon is
        // accepted; one step of f32 below, refused. Powers of two keep everything exact.
        for k in [-40i32, -20, 0, 20, 60] {
            let at = 2f32.powi(k);
            let edge = at * RESOLUTION_REL;
            let flat = |e: f32| [v(at, 0., 0.), v(at, e, 0.), v(at, 0., e)];
            // Longest edge: the hypotenuse, sqrt(2) e.
            let e = edge / core::f32::consts::SQRT_2;
            let ok = polygon_shape(&flat(e * 1.0001));
            assert!(ok.is_ok(), "2^{k}: {ok:?}");
            assert_eq!(
                polygon_shape(&flat(e * 0.999)),
                Err(ShapeError::TooSmall),
                "2^{k}"
            );
        }
        // Independent of the scale: a polygon and its copy scaled by 2^k are judged alike
        // (while the area stays a normal f32).
        for (size, accepted) in [(1e-5, true), (1e-6, false)] {
            let base = tri_at(v(3., -5., 7.), size);
            assert_eq!(polygon_shape(&base).is_ok(), accepted, "{size}");
            for k in [-40i32, -1, 1, 40] {
                let f = 2f32.powi(k);
                let scaled = base.map(|c| c * f);
                assert_eq!(polygon_shape(&scaled).is_ok(), accepted, "{size} x 2^{k}");
            }
        }
    }
}
