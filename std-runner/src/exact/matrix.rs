//! The full form factor matrix, one row per receiver element, computed in parallel with each
//! row independent and in a fixed order, so that the matrix is bit-identical for any thread
//! count.
//!
//! `F[(i, r), (j, s)] = sum_q w_q * point_polygon_f64(x_q, n_r, j) * V(x_q, j)` over the
//! quadrature points `x_q` of element `i` whose view of `j` shows side `s` of `j`, where `r`
//! is the receiving side of `i` (its front normal, or the opposite one for the back of a
//! two-sided element) and `V` is the fraction of jittered rays from `x_q` to `j` that pass.
//! Sides that cannot emit (the back of a one-sided element) get no entry. Rays go through
//! [`PairRays`], which may know a pair to be clear without casting any.
//!
//! Buried points of `i` have weight 0 and are skipped (the weights of the exposed ones sum
//! to 1), so a row is the exposed part's form factors. Nothing is removed on the emitting
//! side: `j`'s buried part lies behind the faces of the object it is buried in, so the rays
//! to it are blocked, or behind the receiver's own plane, which the form factor clips away.

use super::mesh::{Element, Mesh};
use super::quadrature::Quadrature;
use super::rays::{Pair, PairRays};
use glam::Vec3;
use hirad_core::formfactor::{facing_side, point_polygon_f64};
use hirad_core::geometry::Aabb;
use hirad_core::sampling::{hash3, point_on, unit2};
use rayon::prelude::*;

/// One non-zero form factor: the emitting slot and the value (dimensionless).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Entry {
    /// Radiosity slot of the emitting side.
    pub slot: u32,
    /// Form factor from the receiving side to that emitting side, accumulated in f64 and
    /// stored in f32 (about 1e-7 relative: a closed rho = 0.99 furnace then lands within
    /// 1e-6 of `E / (1 - rho)`).
    pub value: f32,
}

/// The form factors of one receiver element, per receiving side.
#[derive(Clone, Debug, Default)]
pub struct Row {
    /// Entries of the front side.
    pub front: Vec<Entry>,
    /// Entries of the back side (empty for one-sided elements).
    pub back: Vec<Entry>,
}

/// The matrix and what it cost.
#[derive(Clone, Debug, Default)]
pub struct Matrix {
    /// One row per element.
    pub rows: Vec<Row>,
    /// Element pairs whose form factor was evaluated.
    pub pairs: u64,
    /// Visibility rays cast.
    pub rays: u64,
    /// Pairs with a non-zero form factor known to be unoccluded without casting rays.
    pub clear_pairs: u64,
}

impl Matrix {
    /// Non-zero entries stored.
    pub fn entries(&self) -> u64 {
        self.rows
            .iter()
            .map(|r| (r.front.len() + r.back.len()) as u64)
            .sum()
    }

    /// Bytes of the stored entries (row headers included).
    pub fn bytes(&self) -> u64 {
        self.entries() * size_of::<Entry>() as u64 + (self.rows.len() * size_of::<Row>()) as u64
    }
}

/// What computing one row cost.
#[derive(Clone, Copy, Debug, Default)]
struct Cost {
    pairs: u64,
    rays: u64,
    clear_pairs: u64,
}

/// Computes every row; `rays` visibility rays per quadrature point and emitter. Each row done
/// advances `progress` by one.
pub fn build<R: PairRays + ?Sized>(
    mesh: &Mesh,
    quad: &Quadrature,
    rays: u32,
    visibility: &R,
    progress: &crate::output::Progress,
) -> Matrix {
    let results: Vec<(Row, Cost)> = (0..mesh.elements.len())
        .into_par_iter()
        .map(|i| {
            let r = row(mesh, quad, rays, visibility, i);
            progress.advance(1);
            r
        })
        .collect();
    progress.set(mesh.elements.len() as u64);
    let mut m = Matrix::default();
    m.rows.reserve(results.len());
    for (r, cost) in results {
        m.rows.push(r);
        m.pairs += cost.pairs;
        m.rays += cost.rays;
        m.clear_pairs += cost.clear_pairs;
    }
    m
}

/// Row of element `i`, and what it cost.
fn row<R: PairRays + ?Sized>(
    mesh: &Mesh,
    quad: &Quadrature,
    rays: u32,
    visibility: &R,
    i: usize,
) -> (Row, Cost) {
    let ei = &mesh.elements[i];
    let (points, weights) = quad.of(i);
    let mut out = Row::default();
    let mut cost = Cost::default();
    let mut candidates = Vec::new();
    for (j, ej) in mesh.elements.iter().enumerate() {
        // Pieces of one polygon are coplanar: they exchange nothing.
        if ej.polygon == ei.polygon {
            continue;
        }
        // acc[receiving side][emitting side]
        let mut acc = [[0.0f64; 2]; 2];
        let mut evaluated = false;
        let skip = [ei.polygon, ej.polygon];
        // Classified on the first point that needs rays.
        let mut pair = None;
        for (q, (&x, &w)) in points.iter().zip(weights).enumerate() {
            // Buried points (weight 0) receive nothing.
            if w == 0.0 {
                continue;
            }
            let Some(s) = facing_side(x, ej.corners[0], ej.normal) else {
                continue;
            };
            if s == 1 && !ej.two_sided() {
                continue;
            }
            evaluated = true;
            // The f64 form factor: sums over a closed surround close to 1 within 1e-9.
            let (xd, nd) = (x.as_dvec3(), ei.normal.as_dvec3());
            let ff = [
                point_polygon_f64(xd, nd, ej.corners()),
                if ei.two_sided() {
                    point_polygon_f64(xd, -nd, ej.corners())
                } else {
                    0.0
                },
            ];
            if ff[0] <= 0.0 && ff[1] <= 0.0 {
                continue;
            }
            let kind = *pair.get_or_insert_with(|| {
                let mut b = Aabb::EMPTY;
                for c in ei.corners().iter().chain(ej.corners()) {
                    b.include(*c);
                }
                visibility.pair(b.min, b.max, skip, &mut candidates)
            });
            for (r, f) in ff.iter().enumerate() {
                if *f <= 0.0 {
                    continue;
                }
                let v = if kind == Pair::Clear {
                    1.0
                } else {
                    let seed = hash3(i as u32, j as u32, q as u32 + 16 * r as u32);
                    let ray = |y: Vec3| visibility.cast(x, y, skip, kind, &candidates);
                    let side = if r == 0 { ei.normal } else { -ei.normal };
                    let (v, cast) = visible_fraction(ray, ej, x, side, seed, rays);
                    cost.rays += cast as u64;
                    v
                };
                acc[r][s] += w as f64 * f * v;
            }
        }
        cost.pairs += evaluated as u64;
        cost.clear_pairs += (pair == Some(Pair::Clear)) as u64;
        let slots = [j as u32, ej.back_slot];
        for (s, &slot) in slots.iter().enumerate() {
            if acc[0][s] > 0.0 {
                out.front.push(Entry {
                    slot,
                    value: acc[0][s] as f32,
                });
            }
            if acc[1][s] > 0.0 {
                out.back.push(Entry {
                    slot,
                    value: acc[1][s] as f32,
                });
            }
        }
    }
    (out, cost)
}

/// Fraction of `rays` segments from the receiving point `x` to jittered points on `ej` in
/// front of the receiving side (normal `n`) that `ray` lets through, and the rays cast. The
/// points are stratified on a `g x ceil(rays / g)` grid of the emitter's parameter square
/// (`g = ceil(sqrt(rays))`), jittered by `hash3(seed, k, ..)`; points behind the receiving
/// plane are skipped and the grid drawn again (up to 4 times) until `rays` are cast: the
/// part of an emitter straddling that plane which lies behind it is no shadow (counting it
/// darkened a block face lit at grazing angle by 3%).
fn visible_fraction(
    ray: impl Fn(Vec3) -> f32,
    ej: &Element,
    x: Vec3,
    n: Vec3,
    seed: u32,
    rays: u32,
) -> (f64, u32) {
    let g = (rays as f64).sqrt().ceil() as u32;
    let rows = rays.div_ceil(g);
    let (mut sum, mut cast) = (0.0f64, 0u32);
    'grids: for pass in 0..4 {
        for k in 0..rays {
            if cast == rays {
                break 'grids;
            }
            let (ju, jv) = unit2(hash3(seed, k + pass * rays, 0x0E1E_C7ED));
            let u = ((k % g) as f32 + ju) / g as f32;
            let v = ((k / g) as f32 + jv) / rows as f32;
            let y = point_on(ej.corners(), u.min(1.0), v.min(1.0));
            if n.dot(y - x) <= 0.0 {
                continue;
            }
            sum += ray(y) as f64;
            cast += 1;
        }
    }
    if cast == 0 {
        return (1.0, 0);
    }
    (sum / cast as f64, cast)
}
