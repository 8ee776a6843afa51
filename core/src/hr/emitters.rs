//! The light of the emitting polygons in the final gather, taken directly: each sample point
//! draws one emitting polygon by its exitance times its exact unoccluded form factor (over
//! the level's own emitters and, in an opened instance's level, those of the levels around
//! it) and casts one visibility ray to a point of it. With more emitters than
//! [`MAX_DIRECT_EMITTERS`] each sample draws one down the cluster tree (`emitter_tree`).

use super::final_gather::patch_corners;
use super::ids::Elem;
use super::state::State;
use super::vis::{Ray, Vis};
use crate::formfactor::{facing_side, point_polygon};
use crate::limits::NONE;
use crate::sampling::{
    MAX_CLIPPED_QUADRATURE, area_in_front, clipped_quadrature, hash3, point_in_front, polygon_area,
    subdivide, unit2,
};
use crate::visibility::Visibility;
use glam::Vec3;

/// Emitting polygons up to which each leaf weighs every one of them; with more, each sample
/// draws one down the cluster tree (see `emitter_tree`).
pub(crate) const MAX_DIRECT_EMITTERS: usize = 64;

/// The emitting polygons whose light is added directly, each weighed by every leaf, or none
/// when there are more than [`MAX_DIRECT_EMITTERS`] (then `count` is 0, `direct` false and
/// `tree` true: each sample draws one emitter down the cluster tree).
///
/// In an opened instance's level, the emitting polygons of the levels it is open in count
/// too (`levels[i]` levels out, 0 for the level's own), while they all fit (`outer`): a lamp
/// a metre from an opened chair lights it polygon by polygon, not through the few gather
/// rays that happen to meet it (which left the chair's polygons a median 30% dark and a
/// few 50 times too bright, right on average only).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Emitters {
    pub ids: [u32; MAX_DIRECT_EMITTERS],
    pub levels: [u8; MAX_DIRECT_EMITTERS],
    pub count: usize,
    pub direct: bool,
    pub tree: bool,
    /// The outer levels' emitters are among `ids`, or drawn down the light cut of level
    /// `outer_tree` out: rays that go on through those levels read only what the polygons
    /// they meet there reflect.
    pub outer: bool,
    /// With more than [`MAX_DIRECT_EMITTERS`] emitting polygons around a level that has
    /// none, all in one level `outer_tree` levels out (0: none): each sample draws one down
    /// that level's light cut, as a level with many of its own does.
    pub outer_tree: u8,
}

impl Emitters {
    /// No emitter, none to draw either (the fields to set follow).
    const EMPTY: Emitters = Emitters {
        ids: [NONE; MAX_DIRECT_EMITTERS],
        levels: [0; MAX_DIRECT_EMITTERS],
        count: 0,
        direct: false,
        tree: false,
        outer: false,
        outer_tree: 0,
    };

    /// True when emission is added directly, not gathered by the rays.
    pub(super) fn apart(&self) -> bool {
        self.direct || self.tree
    }
}

/// The state and workspace of the level `level` levels out from (`st`, `ws`), whose
/// visibility is `vis` (0: that level itself).
pub(super) fn level_of<'a, V: ?Sized>(
    st: &'a State,
    ws: &'a [u8],
    vis: &Vis<'a, V>,
    level: u8,
) -> Option<(&'a State, &'a [u8])> {
    if level == 0 {
        return Some((st, ws));
    }
    vis.outer_level(level as u32).map(|o| (o.st, o.ws))
}

/// [`emitters`] of the level and, when it is an opened instance's, of the levels it is open
/// in: all of them one by one if they fit in [`MAX_DIRECT_EMITTERS`] (see
/// [`Emitters::outer`]), or, more and all in one level around a level without its own, that
/// level's light cut ([`Emitters::outer_tree`]); otherwise the level's own only.
pub(crate) fn emitters_through<V: ?Sized>(st: &State, ws: &[u8], vis: &Vis<'_, V>) -> Emitters {
    let own = emitters(st, ws);
    if !own.direct || vis.outer_level(1).is_none() {
        return own;
    }
    let mut out = own;
    out.outer = true;
    // The levels around that emit: the first and whether another does too.
    let (mut first, mut several) = (0u32, false);
    let mut k = 1u32;
    while let Some(o) = vis.outer_level(k) {
        if k > u8::MAX as u32 {
            return own;
        }
        for i in 0..o.st.polygons {
            if !emits(o.st, o.ws, i) {
                continue;
            }
            if first == 0 {
                first = k;
            } else if first != k {
                several = true;
            }
            if out.count < MAX_DIRECT_EMITTERS {
                out.ids[out.count] = i;
                out.levels[out.count] = k as u8;
            }
            out.count += 1;
        }
        k += 1;
    }
    if out.count <= MAX_DIRECT_EMITTERS {
        return out;
    }
    if own.count > 0 || several {
        // Too many, in several levels: the gather's rays read them (no light cut across
        // levels).
        return own;
    }
    Emitters {
        outer: true,
        outer_tree: first as u8,
        ..Emitters::EMPTY
    }
}

/// Visibility from a point of a level to a point of an emitting polygon of a level around
/// it: the ray stops just short of the emitter (a ten-thousandth of the way), which is no
/// polygon of this level's to skip, and goes through every level around.
pub(super) struct ToOuter<'r, 'a, V: ?Sized> {
    pub ray: &'r Ray<'a, V>,
    /// The receiving point's polygon (of this level).
    pub poly: u32,
}

impl<V: Visibility + ?Sized> Visibility for ToOuter<'_, '_, V> {
    fn transmittance(&self, from: Vec3, to: Vec3, _: [u32; 2]) -> f32 {
        self.ray
            .transmittance(from, to + (from - to) * 1e-4, [self.poly, NONE])
    }

    fn first_hit(&self, from: Vec3, to: Vec3, _: [u32; 2]) -> Option<(u32, f32)> {
        self.ray.first_hit(from, to, [self.poly, NONE])
    }
}

/// True when polygon `i` emits on either side in any band.
fn emits(st: &State, ws: &[u8], i: u32) -> bool {
    let m = st.material(ws, st.polygon(ws, i).material);
    (0..st.bands).any(|b| m.emit[0][b] > 0.0 || m.emit[1][b] > 0.0)
}

/// Finds the scene's emitting polygons (see [`Emitters`]).
pub(crate) fn emitters(st: &State, ws: &[u8]) -> Emitters {
    let mut out = Emitters {
        direct: true,
        ..Emitters::EMPTY
    };
    for i in 0..st.polygons {
        if emits(st, ws, i) {
            if out.count == MAX_DIRECT_EMITTERS {
                return Emitters {
                    tree: true,
                    ..Emitters::EMPTY
                };
            }
            out.ids[out.count] = i;
            out.count += 1;
        }
    }
    out
}

/// One emitting polygon as a leaf patch sees it: its importance (largest exitance x
/// estimated unoccluded form factor from the leaf, over the sides that reach the leaf), and
/// whether its light is integrated from the emitter's side (an emitter no larger than the
/// leaf: reciprocity, smooth where a point-by-point form factor would peak under a small
/// lamp).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Share {
    weight: f32,
    reciprocal: bool,
    /// For `reciprocal`, per emitting side: that side's form factor to the part of the leaf
    /// in front of it, times its area over the leaf's, over quadrature points of the part of
    /// the emitter in front of the leaf (the form factor to a leaf whose edge passes under a
    /// small lamp changes across the lamp). It does not depend on the sample point.
    f_leaf: [f32; 2],
}

/// A sample point of a receiving leaf patch of polygon `poly`, facing `nrm`.
pub(crate) struct Receiver {
    pub poly: u32,
    pub nrm: Vec3,
    pub x: Vec3,
}

/// Fills `shares` for a leaf patch (`corners`, receiving normal `nrm`); returns their sum.
/// An emitter's side counts where any corner of the leaf lies in front of it: a leaf across
/// an emitter's plane gets the light of the part of it in front, whichever side its centre
/// is on.
#[allow(clippy::too_many_arguments)]
pub(super) fn emitter_shares<V: ?Sized>(
    st: &State,
    ws: &[u8],
    vis: &Vis<'_, V>,
    poly: u32,
    corners: &[Vec3],
    nrm: Vec3,
    em: &Emitters,
    shares: &mut [Share; MAX_DIRECT_EMITTERS],
) -> f32 {
    let nb = st.bands;
    let centre = corners.iter().copied().sum::<Vec3>() / corners.len() as f32;
    let area = polygon_area(corners);
    let mut total = 0.0f32;
    for ((s, &l), &level) in shares.iter_mut().zip(&em.ids[..em.count]).zip(&em.levels) {
        *s = Share::default();
        if l == poly && level == 0 {
            continue;
        }
        let Some((lst, lws)) = level_of(st, ws, vis, level) else {
            continue;
        };
        let lp = lst.polygon(lws, l);
        let (lc, k) = patch_corners(lst, lws, Elem(lp.root));
        let l_normal = Vec3::from(lp.normal);
        let m = lst.material(lws, lp.material);
        let l_area = polygon_area(&lc[..k]);
        let reciprocal = l_area <= area && area > 0.0;
        s.reciprocal = reciprocal;
        for side in 0..2 {
            let e_max = m.emit[side][..nb].iter().copied().fold(0.0f32, f32::max);
            let reaches = corners
                .iter()
                .any(|&c| facing_side(c, lc[0], l_normal) == Some(side));
            if e_max <= 0.0 || !reaches {
                continue;
            }
            let ln = if side == 0 { l_normal } else { -l_normal };
            let f = if reciprocal {
                // Over the part of the emitter in front of the leaf: a point behind the
                // leaf's plane sees its back (a lamp straddling the plane of a block's face
                // lit that face 2.7 times too brightly). The emitter in 4 pieces, each
                // clipped: the form factor to a leaf a few emitter sizes away varies too
                // much over it for one low-order rule.
                let mut pieces = [[Vec3::ZERO; 4]; 4];
                // (4 pieces of the emitter's corner count, which `subdivide` returns.)
                subdivide(&lc[..k], &mut pieces);
                let mut fq = 0.0f32;
                for piece in &pieces {
                    let (mut pts, mut wts) = (
                        [Vec3::ZERO; MAX_CLIPPED_QUADRATURE],
                        [0.0f32; MAX_CLIPPED_QUADRATURE],
                    );
                    let c = &piece[..k];
                    let q = clipped_quadrature(c, corners[0], nrm, &mut pts, &mut wts);
                    let share = polygon_area(c) / l_area;
                    for (p, w) in pts[..q].iter().zip(&wts[..q]) {
                        fq += share * w * point_polygon(*p, ln, corners);
                    }
                }
                let f = l_area * fq / area;
                s.f_leaf[side] = if f.is_finite() { f } else { 0.0 };
                s.f_leaf[side]
            } else if facing_side(centre, lc[0], l_normal) == Some(side) {
                point_polygon(centre, nrm, &lc[..k])
            } else {
                0.0
            };
            // Seen at the centre or not, a part of the emitter may show elsewhere on the
            // leaf: keep a floor so that it can still be drawn.
            let f = if f.is_finite() { f.max(1e-6) } else { 0.0 };
            s.weight += e_max * f;
        }
        total += s.weight;
    }
    total
}

/// Adds to `c` the irradiance at the leaf's sample from the emitting polygons: one emitter
/// drawn by its share (`pick` in [0, 1)), a point of it from `spot` (in the unit square),
/// its light at the point (exact unoccluded form factor from the point) or over the leaf
/// (from a point of the emitter, by reciprocity), times what one visibility ray lets
/// through (see [`hidden_share`]). Returns the rays cast.
#[allow(clippy::too_many_arguments)]
pub(super) fn emitted_light<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    vis: &Ray<'_, V>,
    leaf: &Receiver,
    em: &Emitters,
    shares: &[Share; MAX_DIRECT_EMITTERS],
    total: f32,
    (pick, spot): (f32, (f32, f32)),
    h: u32,
    c: &mut [f32],
) -> u32 {
    let nb = st.bands;
    let target = pick * total;
    let mut acc = 0.0f32;
    let mut chosen = NONE as usize;
    for (i, s) in shares[..em.count].iter().enumerate() {
        if s.weight > 0.0 {
            acc += s.weight;
            chosen = i;
            if target < acc {
                break;
            }
        }
    }
    if chosen == NONE as usize {
        return 0;
    }
    let share = shares[chosen];
    let (l, level) = (em.ids[chosen], em.levels[chosen]);
    let Some((lst, lws)) = level_of(st, ws, vis.vis, level) else {
        return 0;
    };
    let lp = lst.polygon(lws, l);
    let (lc, k) = patch_corners(lst, lws, Elem(lp.root));
    let m = lst.material(lws, lp.material);
    let (x, n) = (leaf.x, leaf.nrm);
    // A point of the part of the emitter in front of x (an emitter that straddles the plane
    // of x shows only part of itself; its share above integrates over that part).
    let (u, v) = spot;
    let pick = unit2(hash3(h, 1, 0x9E)).0;
    let Some(y) = point_in_front(&lc[..k], x, n, pick, u, v) else {
        return 0;
    };
    // Per emitting side, the form factor that multiplies its exitance.
    let mut f = [0.0f32; 2];
    if share.reciprocal {
        f = share.f_leaf;
    } else if let Some(side) = facing_side(x, lc[0], Vec3::from(lp.normal)) {
        // Only the side x lies in front of sends it light (a leaf across the plane of a
        // lamp, its centre in front, has points behind it).
        f[side] = point_polygon(x, n, &lc[..k]);
    }
    if !f.iter().any(|v| v.is_finite() && *v > 0.0) {
        return 0;
    }
    let t = if level == 0 {
        vis.transmittance(x, y, [leaf.poly, l])
    } else {
        let to = ToOuter {
            ray: vis,
            poly: leaf.poly,
        };
        to.transmittance(x, y, [NONE; 2])
    };
    // The form factor times the visibility of one point of the emitter weighs that point by
    // area, not by how much it sends x: in a penumbra the lamp's nearer, brighter half seen
    // or hidden counted as much as its far half (+25% on a square half in a board's shadow,
    // beside a double integral). Unbiased instead: the form factor less what the blocked
    // point would have sent (its kernel over the area the point was drawn on), which is the
    // form factor itself, noise-free, wherever nothing blocks.
    let blocked = if t < 1.0 {
        let side = facing_side(x, lc[0], Vec3::from(lp.normal));
        side.map(|s| {
            (
                s,
                hidden_share(x, n, y, &lc[..k], Vec3::from(lp.normal), s, t),
            )
        })
    } else {
        None
    };
    let scale = total / share.weight;
    for (side, fs) in f.iter().enumerate() {
        if !(fs.is_finite() && *fs > 0.0) {
            continue;
        }
        let fs = match blocked {
            Some((s, b)) if s == side && b.is_finite() => *fs - b,
            _ if t > 0.0 => *fs * t,
            _ => continue,
        };
        for (ck, e) in c.iter_mut().zip(&m.emit[side][..nb]) {
            *ck += scale * fs * e;
        }
    }
    1
}

/// What a point `y` of an emitting polygon (`corners`, front normal `normal`, emitting side
/// `side` towards `x`) drawn uniformly over its part in front of the receiving plane at `x`
/// (normal `n`) and seen with transmittance `t` takes off the unoccluded form factor: its
/// kernel `cos cos / (pi r^2)` times that part's area times `1 - t`. The form factor less
/// this is an unbiased estimate of the visible form factor, and exactly the form factor
/// wherever nothing blocks.
pub(super) fn hidden_share(
    x: Vec3,
    n: Vec3,
    y: Vec3,
    corners: &[Vec3],
    normal: Vec3,
    side: usize,
    t: f32,
) -> f32 {
    let ln = if side == 0 { normal } else { -normal };
    let r = y - x;
    let r2 = r.length_squared();
    let kernel = n.dot(r).max(0.0) * (-ln.dot(r)).max(0.0) / (core::f32::consts::PI * r2 * r2);
    let a = area_in_front(corners, x, n);
    a * kernel * (1.0 - t)
}
