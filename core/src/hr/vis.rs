//! Visibility for the solver: the caller's ray caster, or the core's own BVH built in the
//! workspace over the input polygons.

use super::ids::Elem;
use super::local_field::Inside;
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
    /// The core's BVH over an opened instance's level, and the levels it is open in: a ray
    /// goes on through them (their polygons and their other closed instances), as in the
    /// paper's stack of open levels.
    Nested(Bvh<'a>, &'a Outer<'a>),
}

/// The level an instance was opened in, as its contents' rays see it.
pub(crate) struct Outer<'a> {
    pub vis: &'a Vis<'a, crate::visibility::Unoccluded>,
    pub st: &'a State,
    pub ws: &'a [u8],
    /// The opened instance (its contents are the inner level, not a blocker).
    pub opened: u32,
}

/// A `skip` entry that limits how many outer levels a ray goes through: `DEPTH | n` (polygon
/// ids never have this bit, nor instance entries, see `blockers::SKIP_INSTANCE`).
pub(crate) const DEPTH: u32 = 1 << 30;

/// The `skip` entry for a ray towards a source whose rays go through `outer` outer levels
/// (see `records::Source::outer`).
pub(crate) fn depth_entry(outer: u32) -> u32 {
    if outer == crate::limits::NONE {
        crate::limits::NONE
    } else {
        DEPTH | outer.min(DEPTH - 1)
    }
}

/// How many outer levels a ray with `skip` may still go through (`None`: all).
fn depth_left(skip: [u32; 2]) -> Option<u32> {
    skip.iter()
        .find(|&&s| s != crate::limits::NONE && s & (DEPTH | (1 << 31)) == DEPTH)
        .map(|s| s & (DEPTH - 1))
}

impl<'a, V: ?Sized> Vis<'a, V> {
    /// The level `k` levels out from this one (1: the one it is open in), if there is one.
    pub(crate) fn outer_level(&self, k: u32) -> Option<&'a Outer<'a>> {
        match self {
            Vis::Nested(_, o) if k == 1 => Some(*o),
            Vis::Nested(_, o) if k > 1 => o.vis.outer_level(k - 1),
            _ => None,
        }
    }
}

impl Outer<'_> {
    fn ray(&self) -> Ray<'_, crate::visibility::Unoccluded> {
        Ray {
            vis: self.vis,
            polys: WsPolygons {
                st: self.st,
                ws: self.ws,
            },
        }
    }

    /// The `skip` of a ray that comes out of the opened instance with `skip`; `None` when
    /// it may go through no more outer levels.
    fn skip(&self, skip: [u32; 2]) -> Option<[u32; 2]> {
        let rest = match depth_left(skip) {
            None => crate::limits::NONE,
            Some(0) => return None,
            Some(d) => DEPTH | (d - 1),
        };
        Some([super::blockers::SKIP_INSTANCE | self.opened, rest])
    }
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

    /// [`Self::closed`] of a segment along a source's direction `towards`.
    fn closed_towards(&self, t: f32, from: Vec3, to: Vec3, towards: Vec3, skip: [u32; 2]) -> f32 {
        if t <= 0.0 || self.polys.st.instances == 0 {
            return t;
        }
        let (st, ws) = (self.polys.st, self.polys.ws);
        t * super::blockers::transmittance_towards(st, ws, from, to, towards, skip)
    }
}

impl<V: Visibility + ?Sized> Ray<'_, V> {
    /// A gather ray from `x` along the unit direction `d` that left this level without
    /// meeting anything: what it reads in the levels this one is open in (figure 2's
    /// render through the stack), times `weight`, added to `out` (radiosity per band,
    /// W/m^2): the patch of an outer level's polygon it meets (its side's radiosity, its
    /// emission included), and the light of the outer levels' closed instances on the way
    /// (the opened one aside), nearest first; on through the next outer level if it meets
    /// no polygon. Nothing in a level not opened from another.
    /// With `reflected`, a polygon met reads only what it reflects (its radiosity less its
    /// emission): the outer levels' emitters are then added directly (see
    /// `emitters::Emitters`). `inner`: the opened levels the ray came out of before this
    /// one (`None` from the level it was cast in).
    pub(crate) fn gather_beyond(
        &self,
        x: Vec3,
        d: Vec3,
        weight: f32,
        reflected: bool,
        inner: Option<&Inside<'_>>,
        out: &mut [f32],
    ) {
        let Vis::Nested(_, outer) = self.vis else {
            return;
        };
        let (st, ws) = (outer.st, outer.ws);
        let ray = outer.ray();
        let end = st.beyond(x, d);
        let first = ray.first_hit(x, end, [crate::limits::NONE; 2]);
        // This level's own light where rays meet siblings inside its box, and the light of
        // the levels the ray came out of before inside theirs.
        let inside = (outer.opened < st.instances).then(|| {
            let (lo, hi, place, _) = super::blockers::placed_box(st, ws, outer.opened);
            Inside {
                field: super::local_field::LocalField::of(self.polys.st, self.polys.ws),
                lo,
                hi,
                place,
                inner,
            }
        });
        let through = if st.instances > 0 {
            let to = first.map_or(end, |(_, t)| x + (end - x) * t);
            let opened = outer.opened;
            super::blockers::light_along(st, ws, x, to, opened, inside.as_ref(), weight, out)
        } else {
            1.0
        };
        let w = weight * through;
        if w <= 0.0 {
            return;
        }
        match first {
            Some((hit, t)) if hit < st.polygons => {
                let y = x + (end - x) * t;
                let hp = st.polygon(ws, hit);
                let n = Vec3::from(hp.normal);
                let side = if n.dot(d) < 0.0 { 0 } else { 1 };
                let root = Elem(hp.root);
                if side < State::sides(root) {
                    let at = super::final_gather::leaf_at(st, ws, root, y, n);
                    if let Some(b) = st.b(ws, at, side) {
                        let emit = &st.material(ws, hp.material).emit[side];
                        for (k, (o, v)) in out.iter_mut().zip(b).enumerate() {
                            let e = if reflected { emit[k] } else { 0.0 };
                            *o += w * (v - e).max(0.0);
                        }
                    }
                }
            }
            Some(_) => {}
            None => ray.gather_beyond(x, d, w, reflected, inside.as_ref().or(inner), out),
        }
    }
}

impl<V: Visibility + ?Sized> Visibility for Ray<'_, V> {
    fn transmittance(&self, from: Vec3, to: Vec3, skip: [u32; 2]) -> f32 {
        let t = match self.vis {
            Vis::External(v) => v.transmittance(from, to, skip),
            Vis::Internal(bvh) | Vis::Nested(bvh, _) => {
                BvhVisibility::new(*bvh, self.polys).transmittance(from, to, skip)
            }
        };
        let t = self.closed(t, from, to, skip);
        match self.vis {
            // Between two points of an opened instance: what of the outer levels lies
            // between them (the parts of neighbours' boxes that overlap its own).
            Vis::Nested(_, outer) if t > 0.0 => match outer.skip(skip) {
                Some(s) => t * outer.ray().transmittance(from, to, s),
                None => t,
            },
            _ => t,
        }
    }

    fn transmittance_towards(&self, from: Vec3, to: Vec3, towards: Vec3, skip: [u32; 2]) -> f32 {
        match self.vis {
            Vis::External(v) => {
                let t = v.transmittance_towards(from, to, towards, skip);
                self.closed_towards(t, from, to, towards, skip)
            }
            Vis::Internal(bvh) => {
                let t = BvhVisibility::new(*bvh, self.polys).transmittance(from, to, skip);
                self.closed_towards(t, from, to, towards, skip)
            }
            Vis::Nested(bvh, outer) => {
                let t = BvhVisibility::new(*bvh, self.polys).transmittance(from, to, skip);
                let t = self.closed_towards(t, from, to, towards, skip);
                if t <= 0.0 {
                    return 0.0;
                }
                // On out of the outer levels, as far as they reach.
                let Some(s) = outer.skip(skip) else {
                    return t;
                };
                let end = outer.st.beyond(from, towards);
                t * outer.ray().transmittance_towards(from, end, towards, s)
            }
        }
    }

    fn first_hit(&self, from: Vec3, to: Vec3, skip: [u32; 2]) -> Option<(u32, f32)> {
        match self.vis {
            Vis::External(v) => v.first_hit(from, to, skip),
            Vis::Internal(bvh) | Vis::Nested(bvh, _) => {
                BvhVisibility::new(*bvh, self.polys).first_hit(from, to, skip)
            }
        }
    }
}
