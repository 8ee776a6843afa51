//! Closed instances as blockers (DESIGN.md "Instances inside a level"): a ray that crosses a
//! closed instance's box meets the polygons it blocks with (`State::blocking_geometry`: an
//! approximate instance's own where the level loads them, else its original's placed, when
//! small enough, see `original_geometry`), else goes on with the weight `tau` of its
//! direction, the uncollided transmittance of the contents. A small BVH over the instances'
//! world boxes, built in the workspace when the level is loaded, finds the boxes a segment
//! may cross; each candidate is tested against its placed (oriented) box.

use super::error::HrError;
use super::local_field::Around;
use super::noted_radiance::{RADIANCE_GRID, height_bin, height_bin_at, profile_at, radiance};
pub(crate) use super::noted_radiance::{
    note_profiles, note_radiance, radiance_bytes, radiance_chunk_floats,
};
use super::state::State;
use crate::bvh::{Bvh, BvhNode};
use crate::limits::{MAX_BANDS, NONE};
use glam::Vec3;

/// A `skip` entry that names closed instance `i` is `SKIP_INSTANCE | i`: the segment starts
/// or ends inside it, and its own contents are not in the way (polygon ids never have this
/// bit).
pub(crate) const SKIP_INSTANCE: u32 = 1 << 31;

/// Bytes of the BVH over `instances` boxes: nodes, then the order.
pub(crate) fn bytes_needed(instances: u32) -> usize {
    if instances == 0 {
        return 0;
    }
    crate::bvh::nodes_needed(instances) * core::mem::size_of::<BvhNode>() + 4 * instances as usize
}

fn split(st: &State, instances: u32) -> (usize, usize, usize) {
    let nodes = crate::bvh::nodes_needed(instances) * core::mem::size_of::<BvhNode>();
    let at = st.lay.closed_bvh;
    (at, at + nodes, at + nodes + 4 * instances as usize)
}

/// Builds the BVH over the loaded instances' boxes.
pub(crate) fn build(st: &State, ws: &mut [u8]) -> Result<(), HrError> {
    let n = st.instances;
    if n == 0 {
        return Ok(());
    }
    let (a, b, c) = split(st, n);
    // The boxes first (the workspace cannot be read while the BVH's arrays are borrowed).
    let (head, tail) = ws.split_at_mut(a);
    let (nodes, rest) = tail.split_at_mut(b - a);
    let order = &mut rest[..c - b];
    let nodes: &mut [BvhNode] =
        bytemuck::try_cast_slice_mut(nodes).map_err(|_| HrError::SceneTooLarge)?;
    let order: &mut [u32] =
        bytemuck::try_cast_slice_mut(order).map_err(|_| HrError::SceneTooLarge)?;
    let head: &[u8] = head;
    crate::bvh::build(
        n,
        |i| {
            let leaf = st.instance(head, i);
            crate::geometry::Aabb::new(leaf.bbox_min.into(), leaf.bbox_max.into())
        },
        nodes,
        order,
    )
    .map_err(|_| HrError::SceneTooLarge)?;
    Ok(())
}

/// Notes every closed instance's `tau` towards every source: rays towards suns and sky
/// directions, most of all rays, then look it up (see [`transmittance_towards`]).
pub(crate) fn note_source_tau(st: &State, ws: &mut [u8]) {
    for k in 0..st.sources {
        let super::state::Shape::Source { towards } =
            st.shape(ws, super::ids::Elem::new(super::ids::Kind::Source, k))
        else {
            continue;
        };
        for i in 0..st.instances {
            let t = st.placed(ws, i).tau(towards);
            let at = st.lay.source_tau + 4 * (i as usize * st.sources as usize + k as usize);
            super::pool::write(ws, at, &t);
        }
    }
}

/// The source whose direction is exactly `towards`, if any.
fn source_of(st: &State, ws: &[u8], towards: Vec3) -> Option<u32> {
    (0..st.sources).find(|&k| {
        let at = st.at(ws, super::ids::Elem::new(super::ids::Kind::Source, k));
        let s: super::records::Source = super::pool::read(ws, at);
        Vec3::from(s.towards) == towards
    })
}

/// [`transmittance`] of a segment along `towards`, the direction of a source: each
/// instance's `tau` that way is looked up rather than interpolated.
pub(crate) fn transmittance_towards(
    st: &State,
    ws: &[u8],
    from: Vec3,
    to: Vec3,
    towards: Vec3,
    skip: [u32; 2],
) -> f32 {
    if st.instances == 0 {
        return 1.0;
    }
    // The source, found the first time an instance without polygons needs its tau.
    let mut source: Option<Option<u32>> = None;
    let mut t = 1.0f32;
    bvh(st, ws).any_hit(from, to, |i| {
        if skip.contains(&(SKIP_INSTANCE | i)) {
            return false;
        }
        let (lo, hi, place, _) = placed_box(st, ws, i);
        if let Some(g) = st.blocking_geometry(ws, i) {
            // Its own BVH tests its box first.
            if g.blocks(&place, from, to) {
                t = 0.0;
            }
            return t <= 0.0;
        }
        let k = *source.get_or_insert_with(|| source_of(st, ws, towards));
        t *= match k {
            Some(k) => {
                let at = st.lay.source_tau + 4 * (i as usize * st.sources as usize + k as usize);
                let tau: f32 = super::pool::read(ws, at);
                // The box and the transform alone: the tau is known.
                crate::tables::closed::box_transmittance(lo, hi, &place, from, to, tau)
            }
            None => {
                if crate::tables::closed::box_crossed(lo, hi, &place, from, to) {
                    st.placed(ws, i).transmittance(from, to)
                } else {
                    1.0
                }
            }
        };
        t <= 0.0
    });
    t.max(0.0)
}

/// Most closed instances one gather ray reads along its way (the nearest).
pub(crate) const MAX_ALONG: usize = 32;

/// The light the closed instances along the segment `from..to` send back towards `from`,
/// as radiosity (W/m^2 per band, `pi` times radiance: what a gather ray adds), nearer ones
/// first, each behind what the nearer let through; `out` gets it added times `weight`.
/// Instance `skip` (an opened one, or `NONE`) is not there. Returns what they let through
/// all together (the weight of whatever lies behind them, before `weight`). A polygon met
/// inside an opened level's box where `local` (the opened levels' light by place, innermost
/// first) knows the light around reads that instead of its instance's tables (see
/// `local_field`).
#[allow(clippy::too_many_arguments)]
pub(crate) fn light_along(
    st: &State,
    ws: &[u8],
    from: Vec3,
    to: Vec3,
    skip: u32,
    local: Option<&super::local_field::Inside<'_>>,
    weight: f32,
    out: &mut [f32],
) -> f32 {
    if st.instances == 0 {
        return 1.0;
    }
    let d = (to - from).normalize_or_zero();
    // The nearest polygon met (the instances' BVH skips boxes entered beyond it), and the
    // media before it: (entry, transmittance, instance, polygon met or NONE), nearest first.
    let mut media: heapless::Vec<(f32, f32, u32, u32), MAX_ALONG> = heapless::Vec::new();
    let mut polygon = NONE;
    let opaque = bvh(st, ws).closest_hit(from, to, |i, t_max| {
        if i == skip {
            return None;
        }
        match meets(st, ws, i, from, to, d, t_max, Blocking::Own)? {
            Met::Polygon(t, q) => {
                polygon = q;
                Some(t)
            }
            Met::Medium(entry, t) => {
                keep_nearest(&mut media, (entry, t, i, NONE));
                None
            }
        }
    });
    let mut met = media;
    if let Some((_, t_hit)) = opaque {
        met.retain(|m| m.0 < t_hit);
    }
    met.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.2.cmp(&b.2)));
    if let Some((i, t_hit)) = opaque {
        // Its own polygon ends the way: a medium entered beyond it was dropped above.
        if met.is_full() {
            met.pop();
        }
        let _ = met.push((t_hit, 0.0, i, polygon));
    }
    let mut through = 1.0f32;
    if met.is_empty() {
        return through;
    }
    let cells = RADIANCE_GRID.weights(-d);
    let noted = |i: u32, band: usize| -> f32 {
        let mut v = 0.0f32;
        for &(c, cw) in &cells {
            if cw > 0.0 {
                v += cw * radiance(st, ws, i, c, band);
            }
        }
        v
    };
    for &(at, t, i, q) in &met {
        if t < 1.0 {
            let w = weight * through * (1.0 - t);
            // The polygon met, where the tables keep it apart: its own first scattering
            // (the instance's mean would give a leaf deep inside a neighbour its sunlit
            // top's light), plus the instance's light scattered more than once that way
            // (which a shaded leaf shows too).
            let placed = st.placed(ws, i);
            let kept = st.slot(ws, st.instance(ws, i).slot).polygons_kept != 0;
            let own = (q != NONE && kept)
                .then(|| placed.tables().single())
                .flatten()
                .filter(|s| (q as usize) < s.polygons())
                .and_then(|s| {
                    let r =
                        crate::tables::closed::Received::over(&placed, st.received(ws, i)).ok()?;
                    let (n, _, _) = s.polygon(q as usize, 0);
                    let side = usize::from(n.dot(placed.local(-d)) < 0.0);
                    Some((r, side))
                });
            // The met polygon's height slice, once for every band: its original's polygon,
            // or where the ray met one of the instance's own (see `Blocking::Own`).
            let own_hit = q == NONE && st.instance(ws, i).own_polygons != 0;
            // A polygon of its original met among the opened level's polygons: their light.
            let mut around = [0.0f32; MAX_BANDS];
            let near = own.is_none()
                && q != NONE
                && local.is_some_and(|l| {
                    // Inside an opened instance's own box only (tested before the
                    // polygon's geometry is looked up).
                    let x = from + (to - from) * at;
                    if !l.any_holds(x) {
                        return false;
                    }
                    let Some(g) = st.original_geometry(ws, st.instance(ws, i).slot) else {
                        return false;
                    };
                    let two = g.two_sided(q);
                    match l.radiosity(x, two, &mut around[..st.bands]) {
                        Around::Outside => false,
                        // The back of a one-sided polygon shows nothing.
                        _ if !two && g.normal(q).dot(placed.local(-d)) < 0.0 => {
                            around.fill(0.0);
                            true
                        }
                        Around::Known => true,
                        Around::Unknown => false,
                    }
                });
            if near {
                for (band, o) in out.iter_mut().enumerate() {
                    *o += w * around[band];
                }
                through *= t;
                if through <= 0.0 {
                    break;
                }
                continue;
            }
            let bin = if own.is_some() {
                height_bin(st, ws, i, q)
            } else if own_hit {
                let x = from + (to - from) * at;
                height_bin_at(
                    st,
                    ws,
                    i,
                    crate::tables::closed::local_point(&placed.place(), x),
                )
            } else {
                0
            };
            for (band, o) in out.iter_mut().enumerate() {
                // (`noted` is the light scattered more than once where the polygon's own
                // first scattering is read, see `shows_polygons`, shaped by its height; all
                // its light, shaped so, where one of its own polygons is met.)
                let v = match &own {
                    Some((r, side)) => {
                        let shape: f32 = super::pool::read(ws, profile_at(st, i, bin, band));
                        r.first_radiosity(&placed, q as usize, *side, band) + noted(i, band) * shape
                    }
                    None if own_hit => {
                        let shape: f32 = super::pool::read(ws, profile_at(st, i, bin, band));
                        noted(i, band) * shape
                    }
                    _ => noted(i, band),
                };
                *o += w * v;
            }
        }
        through *= t;
        if through <= 0.0 {
            break;
        }
    }
    through
}

/// What a segment meets of a closed instance (see [`meets`]).
enum Met {
    /// One of its own polygons: the parameter along the segment and the polygon.
    Polygon(f32, u32),
    /// Its box, as a medium: the parameter where the segment enters and what its contents
    /// let through along it.
    Medium(f32, f32),
}

/// Which polygons a closed instance that has them meets a segment with (see [`meets`]).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Blocking {
    /// Its own where it blocks with them (see `State::blocking_geometry`): a gather ray
    /// that meets one reads the instance's light, its original's polygons being elsewhere.
    Own,
    /// Its original's placed where it stands: the polygon met is one its tables know (the
    /// exchange lands its light there).
    Original,
}

/// What the segment `from..to` (of unit direction `d`) meets of closed instance `i` before
/// the parameter `t_max`: its first polygon where it has polygons to block with (its BVH
/// tests its box first; the polygon `NONE` where it is one of its own, which its tables do
/// not know), else its box as a medium of its `tau`; `None` when neither.
#[allow(clippy::too_many_arguments)]
fn meets(
    st: &State,
    ws: &[u8],
    i: u32,
    from: Vec3,
    to: Vec3,
    d: Vec3,
    t_max: f32,
    blocking: Blocking,
) -> Option<Met> {
    let (lo, hi, place, slot) = placed_box(st, ws, i);
    let own = match blocking {
        Blocking::Own => st.own_geometry(ws, i),
        Blocking::Original => None,
    };
    if let Some(g) = own {
        return g
            .first_hit(&place, from, to, t_max)
            .map(|(_, t)| Met::Polygon(t, NONE));
    }
    if let Some(g) = st.original_geometry(ws, slot) {
        return g
            .first_hit(&place, from, to, t_max)
            .map(|(q, t)| Met::Polygon(t, q));
    }
    let tau = st.placed(ws, i).tau(d);
    crate::tables::closed::box_crossing(lo, hi, &place, from, to, tau)
        .filter(|&(entry, _)| entry < t_max)
        .map(|(entry, t)| Met::Medium(entry, t))
}

/// Adds `m` to `met`, which keeps the [`MAX_ALONG`] nearest by entry: when full, `m`
/// takes the place of the farthest if it is nearer.
fn keep_nearest(met: &mut heapless::Vec<(f32, f32, u32, u32), MAX_ALONG>, m: (f32, f32, u32, u32)) {
    if let Err(m) = met.push(m) {
        let far = (0..met.len()).fold(0, |f, k| if met[k].0 > met[f].0 { k } else { f });
        if m.0 < met[far].0 {
            met[far] = m;
        }
    }
}

/// Closed instance `i`'s original's box, its transform to world and its table slot.
pub(crate) fn placed_box(
    st: &State,
    ws: &[u8],
    i: u32,
) -> (Vec3, Vec3, crate::geometry::Similarity, u32) {
    let leaf = st.instance(ws, i);
    let r = st.slot(ws, leaf.slot).record;
    let place = leaf.place();
    (Vec3::from(r.lo), Vec3::from(r.hi), place, leaf.slot)
}

/// The BVH over the level's closed instances (empty without).
fn bvh<'a>(st: &State, ws: &'a [u8]) -> Bvh<'a> {
    let n = st.instances;
    if n == 0 {
        return Bvh::EMPTY;
    }
    let (a, b, c) = split(st, n);
    match (
        bytemuck::try_cast_slice::<u8, BvhNode>(&ws[a..b]),
        bytemuck::try_cast_slice::<u8, u32>(&ws[b..c]),
    ) {
        (Ok(nodes), Ok(order)) => Bvh::new_unchecked(nodes, order),
        _ => Bvh::EMPTY,
    }
}

/// The product of `tau` along the segment `from..to` over the closed instances whose boxes
/// it crosses, but those `skip` names (see [`SKIP_INSTANCE`]).
pub(crate) fn transmittance(st: &State, ws: &[u8], from: Vec3, to: Vec3, skip: [u32; 2]) -> f32 {
    if st.instances == 0 {
        return 1.0;
    }
    let mut t = 1.0f32;
    bvh(st, ws).any_hit(from, to, |i| {
        if skip.contains(&(SKIP_INSTANCE | i)) {
            return false;
        }
        let (lo, hi, place, _) = placed_box(st, ws, i);
        match st.blocking_geometry(ws, i) {
            // Its own BVH tests its box first.
            Some(g) => {
                if g.blocks(&place, from, to) {
                    t = 0.0;
                }
            }
            // The box first: the tables only for a segment that crosses it.
            None => {
                if crate::tables::closed::box_crossed(lo, hi, &place, from, to) {
                    t *= st.placed(ws, i).transmittance(from, to);
                }
            }
        }
        t <= 0.0
    });
    t.max(0.0)
}

/// The closed instance the segment `from..to` meets first, but `skip`, and the parameter
/// where: one with polygons of its own where the segment meets one of them, one without at
/// its box's entry with probability `1 - t`, `t` what its contents let through along the
/// segment (decided by the hash `h`, so that the answer is repeatable); and the polygon met
/// (`NONE` for one without polygons).
pub(crate) fn first_instance(
    st: &State,
    ws: &[u8],
    from: Vec3,
    to: Vec3,
    skip: u32,
    h: u32,
) -> Option<(u32, f32, u32)> {
    if st.instances == 0 {
        return None;
    }
    let d = (to - from).normalize_or_zero();
    // The polygon met by the nearest hit so far (the BVH skips boxes entered beyond it).
    let mut polygon = NONE;
    let (i, t) = bvh(st, ws).closest_hit(from, to, |i, t_max| {
        if i == skip {
            return None;
        }
        let (t, q) = match meets(st, ws, i, from, to, d, t_max, Blocking::Original)? {
            Met::Polygon(t, q) => (t, q),
            Met::Medium(entry, t) => {
                let (u, _) = crate::sampling::unit2(crate::sampling::hash3(h, i, 0xF1));
                (u >= t).then_some((entry, NONE))?
            }
        };
        polygon = q;
        Some(t)
    })?;
    Some((i, t, polygon))
}
