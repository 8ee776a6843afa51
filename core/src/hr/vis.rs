//! Visibility for the solver: the caller's ray caster, or the core's own BVH built in the
//! workspace over the input polygons.

use super::ids::Elem;
use super::state::State;
use crate::bvh::{Bvh, BvhVisibility, PolygonSet};
use crate::visibility::Visibility;
use glam::Vec3;

/// Where visibility comes from.
pub(crate) enum Vis<'a, V: ?Sized> {
    /// The caller's.
    External(&'a V),
    /// The core's BVH over the polygons in the workspace.
    Internal(Bvh<'a>),
}

/// The input polygons as the root patches in the workspace hold them.
#[derive(Clone, Copy)]
pub(crate) struct WsPolygons<'a> {
    pub st: &'a State,
    pub ws: &'a [u8],
}

impl PolygonSet for WsPolygons<'_> {
    fn count(&self) -> u32 {
        self.st.polygons
    }

    fn corners(&self, id: u32, out: &mut [Vec3; 4]) -> usize {
        if id >= self.st.polygons {
            return 0;
        }
        let root = Elem(self.st.polygon(self.ws, id).root);
        let p = self.st.patch(self.ws, root);
        for (o, c) in out.iter_mut().zip(p.corners) {
            *o = c.into();
        }
        p.corner_count()
    }
}

/// Visibility during one phase: the source plus what the internal BVH reads.
pub(crate) struct Ray<'a, V: ?Sized> {
    pub vis: &'a Vis<'a, V>,
    pub polys: WsPolygons<'a>,
}

impl<V: Visibility + ?Sized> Ray<'_, V> {
    /// What the closed instances the segment crosses let through (1 without any).
    fn closed(&self, t: f32, from: Vec3, to: Vec3, skip: [u32; 2]) -> f32 {
        if t <= 0.0 || self.polys.st.instances == 0 {
            return t;
        }
        t * super::blockers::transmittance(self.polys.st, self.polys.ws, from, to, skip)
    }
}

impl<V: Visibility + ?Sized> Visibility for Ray<'_, V> {
    fn transmittance(&self, from: Vec3, to: Vec3, skip: [u32; 2]) -> f32 {
        let t = match self.vis {
            Vis::External(v) => v.transmittance(from, to, skip),
            Vis::Internal(bvh) => {
                BvhVisibility::new(*bvh, self.polys).transmittance(from, to, skip)
            }
        };
        self.closed(t, from, to, skip)
    }

    fn transmittance_towards(&self, from: Vec3, to: Vec3, towards: Vec3, skip: [u32; 2]) -> f32 {
        match self.vis {
            Vis::External(v) => {
                let t = v.transmittance_towards(from, to, towards, skip);
                self.closed(t, from, to, skip)
            }
            Vis::Internal(_) => self.transmittance(from, to, skip),
        }
    }

    fn first_hit(&self, from: Vec3, to: Vec3, skip: [u32; 2]) -> Option<(u32, f32)> {
        match self.vis {
            Vis::External(v) => v.first_hit(from, to, skip),
            Vis::Internal(bvh) => BvhVisibility::new(*bvh, self.polys).first_hit(from, to, skip),
        }
    }
}
