//! Splits an OBJ face into the triangles and quads the scene model accepts.
//!
//! Triangles stay triangles and quads stay quads when [`polygon_shape`] accepts them. Other
//! faces lose their corners on straight edges first (a rectangle with extra corners along its
//! sides is a quad). A refused quad is cut along the diagonal that gives two valid triangles.
//! Larger polygons are fanned from their first corner when convex and planar, otherwise
//! ear-clipped in the plane of their Newell normal. Every piece returned passes
//! [`polygon_shape`] and faces the same side as the face; pieces that would not are dropped
//! and counted. Tolerances are relative to the
//! polygon's own size (the core's [`DEGENERATE_REL`] and [`PLANAR_REL`]).

use super::vec64::{D2, D3};
use glam::Vec3;
use hirad_core::geometry::{DEGENERATE_REL, PLANAR_REL, polygon_shape};
use std::f64::consts::TAU;

/// Most corners of a face that is ear-clipped (neither a triangle, a quad, nor convex and
/// planar). Ear clipping costs up to the cube of the corner count, so larger faces are refused
/// rather than left to run for hours.
pub const MAX_CLIPPED_CORNERS: usize = 4096;

/// A piece of a face: corner positions in the face's corner list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Piece {
    /// A triangle.
    Tri([usize; 3]),
    /// A quad (only a face that is itself an accepted quad).
    Quad([usize; 4]),
}

impl Piece {
    /// The corner positions.
    pub fn corners(&self) -> &[usize] {
        match self {
            Piece::Tri(c) => c,
            Piece::Quad(c) => c,
        }
    }
}

/// The face is not convex and planar and has more than [`MAX_CLIPPED_CORNERS`] corners.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct TooManyCorners;

/// Splits the face with corners `pts` (at least 3) into `out` (cleared first). Returns the
/// number of degenerate or flipped parts that were dropped. An empty `out` means the whole
/// face is degenerate.
pub(crate) fn split(pts: &[Vec3], out: &mut Vec<Piece>) -> Result<usize, TooManyCorners> {
    out.clear();
    match pts.len() {
        0..=2 => Ok(0),
        3 => {
            if polygon_shape(pts).is_ok() {
                out.push(Piece::Tri([0, 1, 2]));
            }
            Ok(0)
        }
        4 if polygon_shape(pts).is_ok() => {
            out.push(Piece::Quad([0, 1, 2, 3]));
            Ok(0)
        }
        _ => split_polygon(pts, out),
    }
}

/// Whether triangle `t` is accepted by the core and faces the side of `normal`.
fn valid_tri(pts: &[Vec3], t: [usize; 3], normal: D3) -> bool {
    match polygon_shape(&[pts[t[0]], pts[t[1]], pts[t[2]]]) {
        Ok(s) => D3::from_vec3(s.normal).dot(normal) > 0.0,
        Err(_) => false,
    }
}

/// Newell's normal: twice the vector area of the polygon, for any corner count.
fn newell(pts: &[D3]) -> D3 {
    let c = D3::mean(pts);
    let mut n = D3::default();
    for (i, p) in pts.iter().enumerate() {
        let q = pts[(i + 1) % pts.len()];
        n = n + (*p - c).cross(q - c);
    }
    n
}

/// Longest edge squared.
fn longest_edge2(pts: &[D3]) -> f64 {
    (0..pts.len())
        .map(|i| (pts[(i + 1) % pts.len()] - pts[i]).length_squared())
        .fold(0.0, f64::max)
}

/// The face normal of a polygon, or `None` when it has (almost) no area.
fn face_normal(pts: &[D3]) -> Option<D3> {
    let n = newell(pts);
    let len = n.length();
    if !len.is_finite() || len == 0.0 || len <= DEGENERATE_REL as f64 * longest_edge2(pts) {
        return None;
    }
    Some(n / len)
}

/// A refused quad or a larger polygon. Corners on straight edges are dropped first (they add
/// no area; the solver's polygons are independent, so the T-junction left behind is
/// harmless); what remains is a triangle, a quad, or fanned / ear-clipped.
fn split_polygon(pts: &[Vec3], out: &mut Vec<Piece>) -> Result<usize, TooManyCorners> {
    let d: Vec<D3> = pts.iter().map(|p| D3::from_vec3(*p)).collect();
    let Some(n) = face_normal(&d) else {
        return Ok(0);
    };
    let flat = project(&d, n);
    let keep = drop_straight(&flat);
    let mut skipped = 0;
    let mut emit = |t: [usize; 3]| {
        let t = t.map(|k| keep[k]);
        if valid_tri(pts, t, n) {
            out.push(Piece::Tri(t));
        } else {
            skipped += 1;
        }
    };
    match keep.len() {
        0..=2 => {}
        3 => emit([0, 1, 2]),
        4 => {
            let q = [keep[0], keep[1], keep[2], keep[3]];
            if polygon_shape(&q.map(|k| pts[k])).is_ok() {
                out.push(Piece::Quad(q));
            } else {
                split_quad(&keep, pts, n, &mut emit);
            }
        }
        m => {
            let kept: Vec<D2> = keep.iter().map(|&k| flat[k]).collect();
            let kept3: Vec<D3> = keep.iter().map(|&k| d[k]).collect();
            if is_planar(&kept3, n) && is_convex(&kept) {
                for i in 1..m - 1 {
                    emit([0, i, i + 1]);
                }
            } else if m > MAX_CLIPPED_CORNERS {
                return Err(TooManyCorners);
            } else if ear_clip(&kept, &mut emit) {
                skipped += 1;
            }
        }
    }
    // A face of which no piece survives is degenerate as a whole, not in parts.
    Ok(if out.is_empty() { 0 } else { skipped })
}

/// Cuts the quad `keep` (corner positions of `pts`) along the diagonal that gives more valid
/// triangles, 0-2 on a tie; `emit` takes triangles of positions in `keep`.
fn split_quad(keep: &[usize], pts: &[Vec3], n: D3, emit: &mut dyn FnMut([usize; 3])) {
    let diagonals = [[[0, 1, 2], [0, 2, 3]], [[0, 1, 3], [1, 2, 3]]];
    let valid = |t: [usize; 3]| valid_tri(pts, t.map(|k| keep[k]), n);
    let count = |pair: &[[usize; 3]; 2]| pair.iter().filter(|t| valid(**t)).count();
    let best = if count(&diagonals[1]) > count(&diagonals[0]) {
        &diagonals[1]
    } else {
        &diagonals[0]
    };
    for t in best {
        emit(*t);
    }
}

/// Positions of the corners that are not on a straight edge (or repeated in place), in
/// order. A corner is dropped when the triangle it makes with its current neighbours has no
/// area by the core's rule and the outline goes on forward through it; checking against the
/// current neighbours means a finely curved outline is never flattened beyond that rule.
fn drop_straight(p: &[D2]) -> Vec<usize> {
    let straight = |a: D2, b: D2, c: D2| {
        a == b || b == c || {
            let area = cross(a, b, c);
            area.abs() <= area_tol(a, b, c) && (b - a).dot(c - b) > 0.0
        }
    };
    let mut keep: Vec<usize> = Vec::with_capacity(p.len());
    for k in 0..p.len() {
        while keep.len() >= 2 && straight(p[keep[keep.len() - 2]], p[keep[keep.len() - 1]], p[k]) {
            keep.pop();
        }
        keep.push(k);
    }
    // Around the seam: the last corners against the first, then the first against the last.
    let mut first = 0;
    loop {
        let m = keep.len() - first;
        if m < 3 {
            return Vec::new();
        }
        let last = keep.len() - 1;
        if straight(p[keep[last - 1]], p[keep[last]], p[keep[first]]) {
            keep.pop();
        } else if straight(p[keep[last]], p[keep[first]], p[keep[first + 1]]) {
            first += 1;
        } else {
            break;
        }
    }
    keep.drain(..first);
    keep
}

/// Coordinates in the plane through the centroid perpendicular to `n`, in a right-handed
/// basis `(u, v, n)`: a polygon counter-clockwise about `n` is counter-clockwise in 2D.
fn project(pts: &[D3], n: D3) -> Vec<D2> {
    let u = n.any_orthonormal();
    let v = n.cross(u);
    let c = D3::mean(pts);
    pts.iter()
        .map(|p| D2 {
            x: (*p - c).dot(u),
            y: (*p - c).dot(v),
        })
        .collect()
}

/// Every corner within `PLANAR_REL` times the polygon's extent of its mean plane.
fn is_planar(pts: &[D3], n: D3) -> bool {
    let c = D3::mean(pts);
    let (lo, hi) = pts
        .iter()
        .fold((pts[0], pts[0]), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    let size = (hi - lo).length();
    pts.iter()
        .all(|p| (*p - c).dot(n).abs() <= PLANAR_REL as f64 * size)
}

/// Twice the signed area of the 2D triangle `abc` (positive counter-clockwise).
fn cross(a: D2, b: D2, c: D2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// How much area a triangle needs not to count as a straight line: the core's degeneracy
/// rule, relative to the triangle's own longest edge.
fn area_tol(a: D2, b: D2, c: D2) -> f64 {
    let l2 = (b - a)
        .length_squared()
        .max((c - b).length_squared())
        .max((a - c).length_squared());
    DEGENERATE_REL as f64 * l2
}

/// Strictly convex at every corner and turning once around (no star shapes).
fn is_convex(p: &[D2]) -> bool {
    let n = p.len();
    let mut turning = 0.0;
    for i in 0..n {
        let (a, b, c) = (p[(i + n - 1) % n], p[i], p[(i + 1) % n]);
        if cross(a, b, c) <= area_tol(a, b, c) {
            return false;
        }
        let (e0, e1) = (b - a, c - b);
        turning += e0.perp_dot(e1).atan2(e0.dot(e1));
    }
    (turning - TAU).abs() < 1.0
}

/// Ear clipping of a counter-clockwise polygon; `emit` receives each triangle. Zero-area
/// corners are removed without a triangle once no proper ear is left; when no ear exists at
/// all (a self-intersecting face) the most convex corner is cut regardless. Returns true when
/// a remainder that turns the wrong way had to be given up.
fn ear_clip(p: &[D2], emit: &mut dyn FnMut([usize; 3])) -> bool {
    let n = p.len();
    let mut prev: Vec<usize> = (0..n).map(|i| (i + n - 1) % n).collect();
    let mut next: Vec<usize> = (0..n).map(|i| (i + 1) % n).collect();
    let mut remaining = n;
    let mut cur = 0;
    let mut fails = 0;
    let unlink = |prev: &mut Vec<usize>, next: &mut Vec<usize>, b: usize| {
        let (a, c) = (prev[b], next[b]);
        next[a] = c;
        prev[c] = a;
    };
    while remaining > 3 {
        let (a, b, c) = (prev[cur], cur, next[cur]);
        if is_ear(p, &prev, &next, a, b, c) {
            emit([a, b, c]);
            unlink(&mut prev, &mut next, b);
            remaining -= 1;
            cur = c;
            fails = 0;
            continue;
        }
        cur = next[cur];
        fails += 1;
        if fails < remaining {
            continue;
        }
        // A full turn without an ear.
        fails = 0;
        let mut straight = None;
        let mut most_convex: Option<(usize, f64)> = None;
        let mut k = cur;
        for _ in 0..remaining {
            let (a, c) = (p[prev[k]], p[next[k]]);
            let area = cross(a, p[k], c);
            if area.abs() <= area_tol(a, p[k], c) {
                straight = Some(k);
                break;
            }
            if area > 0.0 && most_convex.is_none_or(|(_, best)| area > best) {
                most_convex = Some((k, area));
            }
            k = next[k];
        }
        let victim = match (straight, most_convex) {
            (Some(k), _) => k,
            (None, Some((k, _))) => {
                emit([prev[k], k, next[k]]);
                k
            }
            // Only reflex corners are left: the remainder winds the wrong way.
            (None, None) => return true,
        };
        cur = next[victim];
        unlink(&mut prev, &mut next, victim);
        remaining -= 1;
    }
    let (a, b, c) = (prev[cur], cur, next[cur]);
    if cross(p[a], p[b], p[c]).abs() > area_tol(p[a], p[b], p[c]) {
        emit([a, b, c]);
    }
    false
}

/// `b` is an ear: strictly convex, and no other corner that is not strictly convex lies in
/// (or on) the triangle `abc`. Corners at the same place as `a`, `b` or `c` do not block.
fn is_ear(p: &[D2], prev: &[usize], next: &[usize], a: usize, b: usize, c: usize) -> bool {
    let (pa, pb, pc) = (p[a], p[b], p[c]);
    if cross(pa, pb, pc) <= area_tol(pa, pb, pc) {
        return false;
    }
    let mut k = next[c];
    while k != a {
        let q = p[k];
        let (qa, qc) = (p[prev[k]], p[next[k]]);
        let convex = cross(qa, q, qc) > area_tol(qa, q, qc);
        if !convex
            && q != pa
            && q != pb
            && q != pc
            && cross(pa, pb, q) >= 0.0
            && cross(pb, pc, q) >= 0.0
            && cross(pc, pa, q) >= 0.0
        {
            return false;
        }
        k = next[k];
    }
    true
}
