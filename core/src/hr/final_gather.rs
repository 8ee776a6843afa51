//! The final gather: every input polygon's irradiance from rays of its own into the solved
//! scene, so that each polygon gets the light its own position, orientation and side see.
//!
//! The hierarchy gets radiosities right where they come from, but a polygon that receives
//! through a coarse link (a cluster's share by its cosine, a floor's mean beside a contact
//! shadow, a few visibility rays for a whole plant) gets its link's average: right on
//! average, wrong by tens of percent for one stem or one shaded leaf. Here each receiving
//! side of each polygon casts stratified, cosine-distributed rays from stratified points and
//! takes, for each, the solved radiosity of the patch it meets (its side; nothing from the
//! back of a one-sided polygon or from outside the scene). Emission is taken apart where
//! there are few emitting polygons: rays count only what the hit reflects, and each point
//! adds the light of the emitting polygons directly (exact unoccluded form factor times a
//! visibility ray), so a small bright lamp costs no noise. The light of suns and sky is the
//! patches' own direct light (see `direct`).
//!
//! Samples come from hashes of the polygon and the sample number: results never depend on
//! the thread count.

use super::emitters::{
    Emitters, MAX_DIRECT_EMITTERS, Receiver, Share, ToOuter, emitted_light, emitter_shares,
    level_of,
};
use super::gather_rays::{adaptive_rays, gathered_share, polygon_rays};
use super::ids::Elem;
use super::sample::{coprime_stride, cosine_direction, jacobian, mean_jacobian};
use super::state::State;
use super::vis::Ray;
use crate::limits::NONE;
use crate::sampling::{hash3, point_on, unit2};
use crate::visibility::Visibility;
use glam::Vec3;

/// Gathers polygon `poly`'s irradiance (W/m^2, per side and band, the mean over its whole
/// area) into `out[side * bands + band]`, without the direct light of suns and sky. In an
/// opened instance's level, the rays that leave it read the levels around (see
/// `Ray::gather_beyond`), so the light its patches' direct light took from links (see
/// `Strides::links_apart`) is taken off: the direct light plus this is then what the
/// polygon sees. Returns the rays cast.
///
/// The samples are spread over the polygon's leaf patches by area, at least one per leaf:
/// the hierarchy subdivided where the light varies (beside a lamp, at a shadow edge), so a
/// peak that uniform samples of a large polygon would miss gets its own.
pub(crate) fn polygon<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    vis: &Ray<'_, V>,
    poly: u32,
    rays: u32,
    em: &Emitters,
    out: &mut [f32],
) -> u32 {
    let nb = st.bands;
    out.fill(0.0);
    let rec = st.polygon(ws, poly);
    let root = Elem(rec.root);
    let total_area = st.patch(ws, root).area as f64;
    let normal = Vec3::from(rec.normal);
    let mut cast = 0u32;
    let mut sums = [[0.0f64; 8]; 2];
    let mut area = 0.0f64;
    let mut leaf_no = 0u32;
    let mut side_rays = [0u32; 2];
    for (side, r) in side_rays.iter_mut().enumerate().take(State::sides(root)) {
        *r = adaptive_rays(
            polygon_rays(st, rays, total_area as f32),
            gathered_share(st, ws, st.leaves(ws, root).map(|l| l.0), side),
        );
    }
    for (e, p) in st.leaves(ws, root) {
        let (corners, k) = patch_corners(st, ws, e);
        let a = p.area as f64;
        area += a;
        leaf_no += 1;
        for (side, sum) in sums.iter_mut().enumerate().take(State::sides(root)) {
            if side_rays[side] == 0 {
                continue;
            }
            let g = leaf_grid(side_rays[side], p.area, total_area as f32);
            let nrm = if side == 0 { normal } else { -normal };
            let seed = hash3(poly, leaf_no, 0xF1A1 + side as u32);
            let mut c = [0.0f64; 8];
            cast += leaf(
                st,
                ws,
                vis,
                poly,
                &corners[..k],
                nrm,
                g,
                seed,
                em,
                &mut c[..nb],
            );
            // Light through links was gathered through the levels around (see `linked`).
            if let Some(l) = st.linked(ws, e, side) {
                for (cb, lb) in c[..nb].iter_mut().zip(l) {
                    *cb -= *lb as f64;
                }
            }
            for (sb, cb) in sum[..nb].iter_mut().zip(&c[..nb]) {
                *sb += a * cb;
            }
        }
    }
    if area > 0.0 {
        for side in 0..State::sides(root) {
            for b in 0..nb {
                out[side * nb + b] = (sums[side][b] / area) as f32;
            }
        }
    }
    cast
}

/// Samples along each side of the grid of a leaf patch of area `leaf` (m^2) in a polygon
/// of area `polygon`: its share by area of `rays`, at least one.
pub(crate) fn leaf_grid(rays: u32, leaf: f32, polygon: f32) -> u32 {
    let share = if polygon > 0.0 {
        rays as f64 * leaf as f64 / polygon as f64
    } else {
        rays as f64
    };
    libm::ceil(libm::sqrt(share)).max(1.0) as u32
}

/// The mean irradiance over one leaf patch (`corners`) on the side facing `nrm`, from
/// `g x g` samples: points on one stratified grid, cosine-distributed directions on another,
/// paired through a coprime stride. Returns the rays cast.
#[allow(clippy::too_many_arguments)]
pub(crate) fn leaf<V: Visibility + ?Sized>(
    st: &State,
    ws: &[u8],
    vis: &Ray<'_, V>,
    poly: u32,
    corners: &[Vec3],
    nrm: Vec3,
    g: u32,
    seed: u32,
    em: &Emitters,
    out: &mut [f64],
) -> u32 {
    let nb = st.bands;
    let n = g * g;
    let mj = mean_jacobian(corners);
    let stride = coprime_stride(n, hash3(seed, 1, 0x57));
    let spot_stride = coprime_stride(n, hash3(seed, 2, 0x5B));
    let mut weight = 0.0f64;
    let mut cast = 0u32;
    let mut shares = [Share::default(); MAX_DIRECT_EMITTERS];
    let total = if em.direct {
        emitter_shares(st, ws, vis.vis, poly, corners, nrm, em, &mut shares)
    } else {
        0.0
    };
    // The light cut: of this level's emitters, or of those of one level around it.
    let cut_level = if em.tree {
        Some(0)
    } else {
        (em.outer_tree > 0).then_some(em.outer_tree)
    };
    let cut = cut_level
        .and_then(|lv| level_of(st, ws, vis.vis, lv).map(|(cst, cws)| (lv, cst, cws)))
        .and_then(|(lv, cst, cws)| {
            let centre = corners.iter().copied().sum::<Vec3>() / corners.len() as f32;
            let skip = if lv == 0 { poly } else { NONE };
            let c = super::emitter_tree::cut(cst, cws, centre, nrm, skip);
            (!c.is_empty()).then_some((lv, cst, cws, c))
        });
    for j in 0..n {
        let cell = ((j as u64 * stride as u64) % n as u64) as u32;
        let (ju, jv) = unit2(hash3(seed, j, 0xA3));
        let u = ((cell % g) as f32 + ju) / g as f32;
        let v = ((cell / g) as f32 + jv) / g as f32;
        let x = point_on(corners, u, v);
        let w = (jacobian(corners, u, v) / mj) as f64;
        weight += w;
        let (du, dv) = unit2(hash3(seed, j, 0xD7));
        let du = ((j % g) as f32 + du) / g as f32;
        let dv = ((j / g) as f32 + dv) / g as f32;
        let d = cosine_direction(nrm, du, dv);
        let mut c = [0.0f32; 8];
        cast += 1;
        let end = st.beyond(x, d);
        let first = vis.first_hit(x, end, [poly, NONE]);
        // Closed instances on the way: their light, and what they let through to the rest.
        let through = if st.instances > 0 {
            let to = first.map_or(end, |(_, t)| x + (end - x) * t);
            super::blockers::light_along(st, ws, x, to, NONE, None, 1.0, &mut c[..nb])
        } else {
            1.0
        };
        if first.is_none() && through > 0.0 {
            // Out of this level: on through the levels it is open in.
            vis.gather_beyond(x, d, through, em.outer, None, &mut c[..nb]);
        }
        if let Some((hit, t)) = first
            && hit < st.polygons
        {
            let y = x + (end - x) * t;
            let hp = st.polygon(ws, hit);
            let front = Vec3::from(hp.normal).dot(d) < 0.0;
            let hroot = Elem(hp.root);
            let hside = if front { 0 } else { 1 };
            if hside < State::sides(hroot) {
                let at = leaf_at(st, ws, hroot, y, Vec3::from(hp.normal));
                let m = st.material(ws, hp.material);
                if let Some(b) = st.b(ws, at, hside) {
                    for k in 0..nb {
                        let e = if em.apart() { m.emit[hside][k] } else { 0.0 };
                        c[k] += through * (b[k] - e).max(0.0);
                    }
                }
            }
        }
        if let Some((lv, cst, cws, cut)) = &cut {
            let h = hash3(seed, j, 0xE3);
            let pick = (j as f64 + unit2(h).0 as f64) / n as f64;
            if *lv == 0 {
                let leaf = Receiver { poly, nrm, x };
                cast += super::emitter_tree::light(st, ws, vis, &leaf, cut, pick, h, &mut c[..nb]);
            } else {
                // An outer level's emitter: no polygon of that level is the receiver.
                let leaf = Receiver { poly: NONE, nrm, x };
                let to = ToOuter { ray: vis, poly };
                cast +=
                    super::emitter_tree::light(cst, cws, &to, &leaf, cut, pick, h, &mut c[..nb]);
            }
        } else if total > 0.0 {
            let h = hash3(seed, j, 0xE3);
            let pick = (j as f32 + unit2(h).0) / n as f32;
            // The point of the emitter on a third stratified grid: in a penumbra, where
            // each sample sees the lamp in part, random points left tiny polygons 17% off.
            let cell = ((j as u64 * spot_stride as u64) % n as u64) as u32;
            let (su, sv) = unit2(hash3(seed, j, 0xE7));
            let spot = (
                ((cell % g) as f32 + su) / g as f32,
                ((cell / g) as f32 + sv) / g as f32,
            );
            let leaf = Receiver { poly, nrm, x };
            cast += emitted_light(
                st,
                ws,
                vis,
                &leaf,
                em,
                &shares,
                total,
                (pick, spot),
                h,
                &mut c[..nb],
            );
        }
        for k in 0..nb {
            out[k] += w * c[k] as f64;
        }
    }
    if weight > 0.0 {
        for o in out.iter_mut() {
            *o /= weight;
        }
    }
    cast
}

/// A patch's corners and their count.
pub(crate) fn patch_corners(st: &State, ws: &[u8], e: Elem) -> ([Vec3; 4], usize) {
    let p = st.patch(ws, e);
    let mut corners = [Vec3::ZERO; 4];
    for (c, src) in corners.iter_mut().zip(p.corners) {
        *c = src.into();
    }
    (corners, p.corner_count())
}

/// The leaf patch of the quadtree under `root` that holds the point `y` of its plane (front
/// normal `n`): at each level the child that `y` lies deepest inside.
pub(crate) fn leaf_at(st: &State, ws: &[u8], root: Elem, y: Vec3, n: Vec3) -> Elem {
    let mut e = root;
    loop {
        let p = st.patch(ws, e);
        if p.first_child == NONE {
            return e;
        }
        let mut best = (f32::NEG_INFINITY, Elem::new(e.kind(), p.first_child));
        for j in 0..4 {
            let child = Elem::new(e.kind(), p.first_child + j);
            let (corners, k) = patch_corners(st, ws, child);
            // The child's own orientation (children keep their parent's, but a flipped input
            // corner order must not send the point to the wrong child).
            let own = (corners[1] - corners[0]).cross(corners[k - 1] - corners[0]);
            let n = if own.dot(n) < 0.0 { -n } else { n };
            let mut inside = f32::INFINITY;
            for i in 0..k {
                let (a, b) = (corners[i], corners[(i + 1) % k]);
                let edge = b - a;
                let len = edge.length();
                if len > 0.0 {
                    inside = inside.min(edge.cross(y - a).dot(n) / len);
                }
            }
            if inside > best.0 {
                best = (inside, child);
            }
        }
        e = best.1;
    }
}
