//! Axis-aligned bounding boxes.

use glam::Vec3;

/// An axis-aligned box; `min > max` on any axis means empty.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner (m).
    pub min: Vec3,
    /// Upper corner (m).
    pub max: Vec3,
}

impl Aabb {
    /// The empty box: the identity of [`Aabb::union`].
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// A box from its corners.
    pub const fn new(min: Vec3, max: Vec3) -> Self {
        Aabb { min, max }
    }

    /// True if the box contains no point.
    pub fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y && self.min.z <= self.max.z)
    }

    /// Grows the box to contain `p`.
    pub fn include(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// The smallest box containing both.
    pub fn union(self, o: Aabb) -> Aabb {
        if o.is_empty() {
            return self;
        }
        if self.is_empty() {
            return o;
        }
        Aabb::new(self.min.min(o.min), self.max.max(o.max))
    }

    /// True if `inner` lies inside `self` (an empty `inner` is inside everything).
    pub fn contains(&self, inner: &Aabb) -> bool {
        inner.is_empty() || (self.min.cmple(inner.min).all() && inner.max.cmple(self.max).all())
    }

    /// True if both corners are finite and `min <= max`.
    pub fn is_finite_nonempty(&self) -> bool {
        self.min.is_finite() && self.max.is_finite() && !self.is_empty()
    }

    /// Centre of the box.
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Half the extent along each axis.
    pub fn half_extent(&self) -> Vec3 {
        (self.max - self.min) * 0.5
    }

    /// Length of the diagonal (m); 0 for an empty box.
    pub fn diagonal(&self) -> f32 {
        if self.is_empty() {
            0.0
        } else {
            (self.max - self.min).length()
        }
    }
}
