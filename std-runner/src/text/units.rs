//! Unit directions and rotation quaternions as written: a value whose squared length is
//! already within the core's tolerance of 1 is kept bit for bit (so that printing and
//! parsing again gives the same bits); anything else is normalised.

use glam::{Quat, Vec3, Vec4};

/// The tolerance on the squared length that the core accepts for stored rotations
/// (`Similarity::checked`) and light directions (`Scene::check`, image validation).
pub(crate) use hirad_core::geometry::UNIT_TOLERANCE;

/// `v` scaled to unit length, or `None` if it is zero. Scales by the largest component
/// first so that huge or tiny finite values normalise without overflow.
fn normalised(v: Vec4) -> Option<Vec4> {
    let m = v.abs().max_element();
    if m.is_nan() || m <= 0.0 {
        return None;
    }
    (v / m).try_normalize()
}

/// A direction: kept if already unit within tolerance, else normalised; `None` if zero.
pub(crate) fn unit_direction(v: Vec3) -> Option<Vec3> {
    if (v.length_squared() - 1.0).abs() <= UNIT_TOLERANCE {
        return Some(v);
    }
    normalised(v.extend(0.0)).map(Vec4::truncate)
}

/// A direction scaled to unit length (never kept as written), or `None` if it is zero: for
/// rotation axes, whose exact bits are never printed back.
pub(crate) fn normalised_direction(v: Vec3) -> Option<Vec3> {
    normalised(v.extend(0.0)).map(Vec4::truncate)
}

/// A rotation: kept if already unit within tolerance, else normalised; `None` if zero.
pub(crate) fn unit_quat(q: Quat) -> Option<Quat> {
    if (q.length_squared() - 1.0).abs() <= UNIT_TOLERANCE {
        return Some(q);
    }
    normalised(Vec4::from(q)).map(Quat::from_vec4)
}
