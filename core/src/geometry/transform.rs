//! Similarity transforms (rotation, uniform scale, translation) that place an instance.

use super::Aabb;
use glam::{Mat3, Quat, Vec3};

/// `p -> translation + scale * rotation(p)`: places an original's local frame in its parent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Similarity {
    /// Unit quaternion.
    pub rotation: Quat,
    /// Translation (m).
    pub translation: Vec3,
    /// Uniform scale factor (dimensionless, > 0).
    pub scale: f32,
}

/// Why a transform is refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransformError {
    /// A component is NaN or infinite.
    NonFinite,
    /// The rotation quaternion is not of unit length.
    RotationNotUnit,
    /// The scale is not a positive normal number.
    Scale,
}

impl core::fmt::Display for TransformError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            TransformError::NonFinite => "a transform component is not a finite number",
            TransformError::RotationNotUnit => "the rotation quaternion is not of unit length",
            TransformError::Scale => "the scale must be a positive, finite, normal number",
        })
    }
}

/// How far from 1 the squared length of a stored unit vector or rotation quaternion may be.
/// Every loader uses this one value, so a value accepted anywhere is accepted everywhere.
pub const UNIT_TOLERANCE: f32 = 1e-5;

impl Similarity {
    /// The identity.
    pub const IDENTITY: Similarity = Similarity {
        rotation: Quat::IDENTITY,
        translation: Vec3::ZERO,
        scale: 1.0,
    };

    /// Checks a transform read from untrusted input.
    pub fn checked(rotation: Quat, translation: Vec3, scale: f32) -> Result<Self, TransformError> {
        if !rotation.is_finite() || !translation.is_finite() || !scale.is_finite() {
            return Err(TransformError::NonFinite);
        }
        if (rotation.length_squared() - 1.0).abs() > UNIT_TOLERANCE {
            return Err(TransformError::RotationNotUnit);
        }
        if scale <= 0.0 || !scale.is_normal() {
            return Err(TransformError::Scale);
        }
        Ok(Similarity {
            rotation,
            translation,
            scale,
        })
    }

    /// Maps a point of the local frame into the parent frame.
    pub fn point(&self, p: Vec3) -> Vec3 {
        self.translation + self.rotation * (p * self.scale)
    }

    /// Maps a direction (not normalised again: rotation only).
    pub fn direction(&self, d: Vec3) -> Vec3 {
        self.rotation * d
    }

    /// `self` after `inner`: first `inner`, then `self`.
    pub fn compose(&self, inner: &Similarity) -> Similarity {
        Similarity {
            rotation: (self.rotation * inner.rotation).normalize(),
            translation: self.point(inner.translation),
            scale: self.scale * inner.scale,
        }
    }

    /// A box in the parent frame that contains the image of `b`.
    pub fn aabb(&self, b: &Aabb) -> Aabb {
        if b.is_empty() {
            return Aabb::EMPTY;
        }
        let m = Mat3::from_quat(self.rotation);
        let abs = Mat3::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs());
        let c = self.point(b.center());
        let e = abs * (b.half_extent() * self.scale);
        Aabb::new(c - e, c + e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checks() {
        assert!(Similarity::checked(Quat::IDENTITY, Vec3::ZERO, 1.0).is_ok());
        assert_eq!(
            Similarity::checked(Quat::from_xyzw(0., 0., 0., 2.), Vec3::ZERO, 1.0),
            Err(TransformError::RotationNotUnit)
        );
        assert_eq!(
            Similarity::checked(Quat::IDENTITY, Vec3::ZERO, 0.0),
            Err(TransformError::Scale)
        );
        assert_eq!(
            Similarity::checked(Quat::IDENTITY, Vec3::ZERO, -1.0),
            Err(TransformError::Scale)
        );
        assert_eq!(
            Similarity::checked(Quat::IDENTITY, Vec3::new(f32::NAN, 0., 0.), 1.0),
            Err(TransformError::NonFinite)
        );
    }

    #[test]
    fn box_contains_transformed_corners() {
        let t = Similarity {
            rotation: Quat::from_axis_angle(Vec3::new(1., 2., 3.).normalize(), 0.7),
            translation: Vec3::new(5., -2., 1.),
            scale: 2.5,
        };
        let b = Aabb::new(Vec3::new(-1., 0., 2.), Vec3::new(3., 1., 4.));
        let tb = t.aabb(&b);
        for i in 0..8 {
            let p = Vec3::new(
                if i & 1 == 0 { b.min.x } else { b.max.x },
                if i & 2 == 0 { b.min.y } else { b.max.y },
                if i & 4 == 0 { b.min.z } else { b.max.z },
            );
            let q = t.point(p);
            let slack = 1e-5 * tb.diagonal();
            assert!(q.cmpge(tb.min - slack).all() && q.cmple(tb.max + slack).all());
        }
    }
}
