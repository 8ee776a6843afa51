//! Visibility behind one trait, so that the solver runs with the core's own BVH, the runner's,
//! or an engine's ray caster.

use glam::Vec3;

/// Fraction of light that passes between two points.
///
/// `skip` names up to two polygons to ignore (the surfaces the segment starts and ends on;
/// [`crate::limits::NONE`] for none), so that no absolute offset is needed. Polygon ids are
/// the solver's polygon indices (for a fully expanded scene, the global ids).
pub trait Visibility: Sync {
    /// 1.0 when nothing blocks the open segment `from`..`to`, 0.0 when it is blocked.
    fn transmittance(&self, from: Vec3, to: Vec3, skip: [u32; 2]) -> f32;

    /// The polygon that the segment `from..to` meets first (not one in `skip`) and the
    /// segment parameter t (0 at `from`, 1 at `to`) where it does, or `None` when nothing
    /// blocks. Nearest up to rounding: of polygons crossed at nearly the same t (coplanar
    /// ones), any may be named. The solver uses it to tell light that leaves the scene from
    /// light that is absorbed by the back of a one-sided polygon (the power balance, and
    /// points buried inside closed objects).
    fn first_hit(&self, from: Vec3, to: Vec3, skip: [u32; 2]) -> Option<(u32, f32)>;

    /// [`Visibility::transmittance`] of a segment that runs from `from` along `towards`, the
    /// unit direction of a sun or sky source, to `to` beyond the scene. Every such ray is
    /// parallel to one of a few directions, so a caster may answer it from a structure built
    /// for that direction (the runner projects the polygons along it onto a grid); the
    /// answer must be the same. The default casts the segment.
    fn transmittance_towards(&self, from: Vec3, to: Vec3, towards: Vec3, skip: [u32; 2]) -> f32 {
        let _ = towards;
        self.transmittance(from, to, skip)
    }
}

/// Nothing ever blocks: for scenes known to be convex, and for tests.
#[derive(Clone, Copy, Debug, Default)]
pub struct Unoccluded;

impl Visibility for Unoccluded {
    fn transmittance(&self, _: Vec3, _: Vec3, _: [u32; 2]) -> f32 {
        1.0
    }

    fn first_hit(&self, _: Vec3, _: Vec3, _: [u32; 2]) -> Option<(u32, f32)> {
        None
    }
}

impl<V: Visibility + ?Sized> Visibility for &V {
    fn transmittance(&self, from: Vec3, to: Vec3, skip: [u32; 2]) -> f32 {
        (**self).transmittance(from, to, skip)
    }

    fn transmittance_towards(&self, from: Vec3, to: Vec3, towards: Vec3, skip: [u32; 2]) -> f32 {
        (**self).transmittance_towards(from, to, towards, skip)
    }

    fn first_hit(&self, from: Vec3, to: Vec3, skip: [u32; 2]) -> Option<(u32, f32)> {
        (**self).first_hit(from, to, skip)
    }
}
