//! What makes a polygon too small for 32-bit floats at its position, in numbers, for the
//! loaders' messages. The rule itself is the core's ([`polygon_shape`] refuses such a polygon
//! as [`ShapeError::TooSmall`](hirad_core::geometry::ShapeError::TooSmall)): its longest edge
//! is below 2^-20 of the largest absolute coordinate of its corners, or its area is below the
//! smallest normal f32.
//!
//! [`polygon_shape`]: hirad_core::geometry::polygon_shape

use crate::numbers::short;
use glam::{DVec3, Vec3};
use hirad_core::geometry::{MIN_AREA, below_f32_resolution};

/// "`what` is too small for 32-bit floats at its position: " and [`too_small_detail`], with
/// the remedy; `what` names the polygon ("this triangle").
pub fn too_small_message(what: &str, corners: &[Vec3]) -> String {
    format!(
        "{what} is too small for 32-bit floats at its position: {}; move the scene nearer \
         the origin or make the polygon larger",
        too_small_detail(corners)
    )
}

/// Why the polygon with `corners` is too small, e.g. "its longest edge, 0.1 m, is less than
/// 2^-20 (about 1e-6) of its largest corner coordinate, 1e6 m, where 32-bit floats are
/// 0.0625 m apart", or "its area, 5e-61 m^2, is below the smallest normal 32-bit float,
/// 1.175e-38 m^2".
pub fn too_small_detail(corners: &[Vec3]) -> String {
    let d: Vec<DVec3> = corners.iter().map(|c| c.as_dvec3()).collect();
    let n = d.len();
    if below_f32_resolution(corners) {
        let longest = (0..n)
            .map(|i| (d[(i + 1) % n] - d[i]).length())
            .fold(0.0, f64::max);
        let reach = d.iter().map(|c| c.abs().max_element()).fold(0.0, f64::max);
        let at = format!(
            "its largest corner coordinate, {} m, where 32-bit floats are {} m apart",
            short(reach),
            short(spacing(reach as f32))
        );
        return if longest == 0.0 {
            format!("its corners round to one point at {at}")
        } else {
            format!(
                "its longest edge, {} m, is less than 2^-20 (about 1e-6) of {at}",
                short(longest)
            )
        };
    }
    // Twice the vector area, by the fan from the first corner.
    let mut twice = DVec3::ZERO;
    for i in 1..n.saturating_sub(1) {
        twice += (d[i] - d[0]).cross(d[i + 1] - d[0]);
    }
    format!(
        "its area, {} m^2, is below the smallest normal 32-bit float, {} m^2",
        short(0.5 * twice.length()),
        short(f64::from(MIN_AREA))
    )
}

/// Distance from `x` (finite, >= 0) to the next larger f32 (to the next smaller at the top).
fn spacing(x: f32) -> f64 {
    let x = x.abs();
    let up = f32::from_bits(x.to_bits() + 1);
    if up.is_finite() {
        f64::from(up) - f64::from(x)
    } else {
        f64::from(x) - f64::from(f32::from_bits(x.to_bits() - 1))
    }
}

#[cfg(test)]
mod tests {
    use super::too_small_detail;
    use glam::Vec3;

    #[test]
    fn names_the_edge_the_position_and_the_spacing() {
        let at = Vec3::new(1e6, 0.0, 0.0);
        let t = [
            at,
            at + Vec3::new(0.125, 0.0, 0.0),
            at + Vec3::new(0.0, 0.125, 0.0),
        ];
        assert_eq!(
            too_small_detail(&t),
            "its longest edge, 0.1768 m, is less than 2^-20 (about 1e-6) of its largest \
             corner coordinate, 1e6 m, where 32-bit floats are 0.0625 m apart"
        );
        let t = [
            at,
            at + Vec3::new(1e-3, 0.0, 0.0),
            at + Vec3::new(0.0, 1e-3, 0.0),
        ];
        // Only x is coarse there: the edge along y survives.
        assert!(
            too_small_detail(&t).starts_with("its longest edge, 0.001 m, is less than"),
            "{}",
            too_small_detail(&t)
        );
        let far = Vec3::splat(1e6);
        let t = [
            far,
            far + Vec3::new(1e-3, 0.0, 0.0),
            far + Vec3::new(0.0, 1e-3, 0.0),
        ];
        assert_eq!(
            too_small_detail(&t),
            "its corners round to one point at its largest corner coordinate, 1e6 m, where \
             32-bit floats are 0.0625 m apart"
        );
        let t = [
            Vec3::ZERO,
            Vec3::new(1e-30, 0.0, 0.0),
            Vec3::new(0.0, 1e-30, 0.0),
        ];
        let d = too_small_detail(&t);
        assert!(d.starts_with("its area, 5e-61 m^2, is below"), "{d}");
    }
}
