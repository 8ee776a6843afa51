//! Emission bins: what a large cluster radiates towards any direction, in a few floats.
//!
//! Towards a unit direction `w` a cluster radiates `sum_p P_p max(0, n_p . w) / pi` over its
//! polygons' emitting sides (outward normal `n_p`, power `P_p`, W per band; see
//! `oriented::emission`). Summed polygon by polygon for every link and every iteration, that
//! was most of a solve in a tree of 100,000 leaves (34 million terms per iteration on the
//! paper poplar). Binned by normal instead, each of [`BINS`] bins keeps, per band, its
//! power `S = sum P` (and `V = sum P n`), and a second record keeps the same of the
//! polygons' exposed areas (which do not change). Towards `w`, each bin's area record gives
//! the mean of `max(0, n . w)` over its area:
//! * a bin whose every normal faces `w` gives `V . w / S`, exactly;
//! * a bin whose every normal faces away gives nothing, exactly;
//! * a bin the terminator crosses is taken as a uniform cone of normals of collimation
//!   `|V| / S` about `V`: the mean of `max(0, n . w)` over such a cone is the irradiance of
//!   a plane facing `w` under a uniform spherical cap of light ([`cap_mean`], exact; the
//!   same integral with normals and light exchanged);
//!
//! and the bin's power times that mean is its emission. Taken from the areas, not from the
//! power-weighted normals, the emission is linear in the powers, so the solution's
//! iteration is a linear map (fitted to the powers, the mean facing radiosity of a white
//! room's furniture kept moving with the radiosities' own pattern and never settled).
//!
//! On crowns of leaves facing every way (powers uneven within a bin) and on soil-like
//! clusters (tests) the binned emission stays within 2% of the largest emission over all
//! directions of the exact sum.
//! Bins add up, so a cluster's bins are its children's plus its own polygons', one pass up
//! the tree per iteration.

use super::cone::cone_share;
use super::ids::{Elem, Kind};
use super::state::State;
use crate::limits::NONE;
use glam::Vec3;

/// Directions by which emitting sides are binned: a cube's 6 faces, 12 edges and 8 corners.
pub(crate) const BINS: usize = 26;

/// Clusters of more polygons than this keep emission bins; smaller ones sum their polygons
/// (as cheap, and exact).
pub(crate) const BINNED: u32 = 32;

/// Floats of a cluster's bins: per bin and band, `V` (3) and `S` (1).
pub(crate) const fn bin_floats(bands: usize) -> usize {
    BINS * bands * 4
}

/// The sine of the largest angle between a normal and the centre of its bin (32.74
/// degrees, at the corners of a face bin): a direction within 90 degrees less that of a
/// bin's centre is faced by every normal of the bin, one beyond 90 degrees more by none.
const SPREAD: f32 = 0.541;

/// The bin of a unit normal: each coordinate rounded to -1, 0 or 1 at +-sin 22.5 degrees
/// (no unit vector rounds to 0, 0, 0).
pub(crate) fn bin_of(n: Vec3) -> usize {
    const T: f32 = 0.382_683_43;
    let q = |x: f32| {
        if x > T {
            2
        } else if x < -T {
            0
        } else {
            1
        }
    };
    let i = q(n.x) * 9 + q(n.y) * 3 + q(n.z);
    match i {
        // Not a unit vector (a checked polygon's normal is): along its largest axis.
        13 => {
            let a = n.abs();
            let axis = if a.x >= a.y && a.x >= a.z {
                0
            } else if a.y >= a.z {
                1
            } else {
                2
            };
            let mut d = [1usize; 3];
            d[axis] = if n[axis] >= 0.0 { 2 } else { 0 };
            let i = d[0] * 9 + d[1] * 3 + d[2];
            if i > 13 { i - 1 } else { i }
        }
        i if i > 13 => i - 1,
        i => i,
    }
}

/// The unit direction at the centre of `bin` (see [`bin_of`]).
pub(crate) fn bin_centre(bin: usize) -> Vec3 {
    let i = if bin >= 13 { bin + 1 } else { bin } as i32;
    let d = Vec3::new(
        (i / 9 - 1) as f32,
        ((i / 3) % 3 - 1) as f32,
        (i % 3 - 1) as f32,
    );
    let k = d.x.abs() + d.y.abs() + d.z.abs();
    d * if k >= 3.0 {
        0.577_350_26
    } else if k >= 2.0 {
        core::f32::consts::FRAC_1_SQRT_2
    } else {
        1.0
    }
}

/// Adds an emitting side (outward unit normal `d`, power per band `power`, W) to `bins`.
pub(crate) fn add(bins: &mut [f32], bands: usize, d: Vec3, power: &[f32]) {
    let at = bin_of(d) * bands * 4;
    for (k, &p) in power.iter().enumerate().take(bands) {
        if p > 0.0 {
            let a = &mut bins[at + 4 * k..at + 4 * k + 4];
            a[0] += p * d.x;
            a[1] += p * d.y;
            a[2] += p * d.z;
            a[3] += p;
        }
    }
}

/// The mean of `max(0, n . w)` over unit vectors `n` spread uniformly (by solid angle) over
/// a cone of collimation `c` (mean length of the vectors: half-angle `acos(2c - 1)`) whose
/// axis makes cosine `t` with `w`. For cones of at most 90 degrees (`c >= 1/2`, as every
/// bin's) this is the irradiance of a uniform spherical cap on a tilted plane, in closed
/// form (Snyder 1996, as in Lagarde's "Moving Frostbite to PBR", 4.7.2), over the cap's
/// solid angle; wider cones take the integrated table [`cone_share`].
pub(crate) fn cap_mean(c: f32, t: f32) -> f32 {
    let c = c.clamp(0.0, 1.0) as f64;
    let t = t.clamp(-1.0, 1.0) as f64;
    if c < 0.5 {
        return cone_share(c as f32, t as f32);
    }
    let cos_a = 2.0 * c - 1.0;
    let sin2 = 1.0 - cos_a * cos_a;
    if sin2 <= 1e-12 || t * t >= sin2 {
        // A beam, or a cone wholly on one side of the plane.
        return (c * t.max(0.0)) as f32;
    }
    let sin_t = libm::sqrt(1.0 - t * t);
    let x = cos_a / libm::sqrt(sin2);
    let y = (-x * t / sin_t).clamp(-1.0, 1.0);
    let sy = sin_t * libm::sqrt(1.0 - y * y);
    let e = (t * libm::acos(y) - x * sy) * sin2 + libm::atan(sy / x);
    let solid_angle = 2.0 * core::f64::consts::PI * (1.0 - cos_a);
    (e.max(0.0) / solid_angle) as f32
}

/// Gives every cluster of more than [`BINNED`] polygons its bins, while the workspace has
/// room (a cluster without them sums its polygons: slower, and exact): two records, its
/// power (see [`update`]) and its exposed area by normal, which does not change (see
/// [`mean_facing`]).
pub(crate) fn allocate(st: &mut State, ws: &mut [u8]) {
    for i in 0..st.clusters {
        let mut c = st.cluster(ws, i);
        if c.polygons <= BINNED {
            continue;
        }
        let mut blocks = st.blocks;
        let Some(k) = st.bins.alloc_run(ws, &mut blocks, 2) else {
            break;
        };
        st.blocks = blocks;
        c.bins = k;
        st.set_cluster(ws, i, &c);
    }
}

/// Fills the area bins (once the polygons' exposed parts are known; they do not change).
pub(crate) fn areas(st: &State, ws: &mut [u8]) {
    fill(st, ws, true, 1);
}

/// Recomputes the bins of every cluster that has them from its polygons' powers (with
/// `unit`, their exposed areas: every emitting side at radiosity 1, see `closure`).
/// Children come after their parents in cluster order, so one reverse pass adds each
/// child's bins to its parent's.
pub(crate) fn update(st: &State, ws: &mut [u8], unit: bool) {
    fill(st, ws, unit, 0);
}

/// [`update`] into record `record` of each cluster's two (0 power, 1 area).
fn fill(st: &State, ws: &mut [u8], unit: bool, record: u32) {
    let nb = st.bands;
    let len = bin_floats(nb);
    let mut acc = [0.0f32; BINS * crate::limits::MAX_BANDS * 4];
    for i in (0..st.clusters).rev() {
        let c = st.cluster(ws, i);
        if c.bins == NONE {
            continue;
        }
        acc[..len].fill(0.0);
        for k in 0..c.child_count {
            let child = st.child(ws, c.children + k);
            match child.kind() {
                Kind::Cluster => {
                    let cc = st.cluster(ws, child.index());
                    if cc.bins != NONE {
                        for (a, v) in acc[..len].iter_mut().zip(of(st, ws, cc.bins + record)) {
                            *a += v;
                        }
                    } else {
                        for j in cc.first_polygon..cc.first_polygon + cc.polygons {
                            add_polygon(st, ws, st.ordered(ws, j), unit, &mut acc[..len]);
                        }
                    }
                }
                // Its polygons' only (see `refine::must_open`).
                Kind::Instance => {}
                _ => {
                    let poly = st.patch(ws, child).poly;
                    add_polygon(st, ws, poly, unit, &mut acc[..len]);
                }
            }
        }
        let at = st.bins.at(ws, &st.blocks, c.bins + record);
        super::pool::floats_mut(ws, at, len).copy_from_slice(&acc[..len]);
    }
}

/// Per bin, the mean of `max(0, n . w)` over the bin's exposed area (its normals taken as
/// in [`emission`]), from a cluster's area bins `area`; 0 for an empty bin or one wholly
/// turned away. Geometry only: it does not change while the solution iterates.
fn facing_factors(area: &[f32], bands: usize, w: Vec3, g: &mut [f32; BINS]) {
    for (bin, gb) in g.iter_mut().enumerate() {
        *gb = 0.0;
        let cw = bin_centre(bin).dot(w);
        if cw <= -SPREAD {
            continue;
        }
        let a = &area[bin * bands * 4..bin * bands * 4 + 4];
        let s = a[3];
        if s <= 0.0 {
            continue;
        }
        let v = Vec3::new(a[0], a[1], a[2]);
        let vw = v.dot(w);
        let len = v.length();
        let e = if cw >= SPREAD {
            vw
        } else if len > 0.0 {
            s * cap_mean(len / s, vw / len)
        } else {
            0.25 * s
        };
        *gb = (e / s).max(0.0);
    }
}

/// `sum_p P_p max(0, n_p . w)` per band (W; the caller scales) of a binned cluster whose
/// bins start at record `bins` (see [`emission`]).
pub(crate) fn emission_of(st: &State, ws: &[u8], bins: u32, w: Vec3, out: &mut [f32]) {
    emission(of(st, ws, bins), of(st, ws, bins + 1), st.bands, w, out);
}

/// `sum_p P_p max(0, n_p . w)` per band (W) from a cluster's power bins `power` and area
/// bins `area`: each bin's power times its [`facing_factors`], so that the result is linear
/// in the polygons' powers and the solution's iteration a linear map (cones fitted to the
/// power-weighted normals made it depend on the radiosities' own pattern, and a white room
/// never settled).
pub(crate) fn emission(power: &[f32], area: &[f32], bands: usize, w: Vec3, out: &mut [f32]) {
    let mut g = [0.0f32; BINS];
    facing_factors(area, bands, w, &mut g);
    weighted(power, bands, &g, out);
}

/// `sum_bin S_bin g_bin` per band of the bins `bins` (`out` overwritten).
fn weighted(bins: &[f32], bands: usize, g: &[f32; BINS], out: &mut [f32]) {
    out.fill(0.0);
    for (bin, &gb) in g.iter().enumerate() {
        if gb <= 0.0 {
            continue;
        }
        for (k, o) in out.iter_mut().enumerate().take(bands) {
            *o += bins[(bin * bands + k) * 4 + 3] * gb;
        }
    }
}

/// The mean radiosity (per band) of a binned cluster's emitting sides facing `w`, weighted
/// by exposed area times cosine: its power bins over its area bins towards `w`, both
/// weighted by the same [`facing_factors`] (see `oriented::mean_facing`, which sums the
/// polygons). Linear in the powers and never above the brightest bin's mean radiosity.
/// Zero when nothing faces `w`; 1 for every band with `unit` where something does.
pub(crate) fn mean_facing(st: &State, ws: &[u8], bins: u32, w: Vec3, unit: bool, out: &mut [f32]) {
    let nb = st.bands;
    let mut g = [0.0f32; BINS];
    let area = of(st, ws, bins + 1);
    facing_factors(area, nb, w, &mut g);
    let mut a = [0.0f32; crate::limits::MAX_BANDS];
    weighted(area, nb, &g, &mut a[..nb]);
    let a = a[0];
    out.fill(0.0);
    if a.is_nan() || a <= 0.0 {
        return;
    }
    if unit {
        out.fill(1.0);
        return;
    }
    weighted(of(st, ws, bins), nb, &g, out);
    for o in out.iter_mut() {
        *o /= a;
    }
}

/// The bins stored at record `k` of the bins pool.
pub(crate) fn of<'a>(st: &State, ws: &'a [u8], k: u32) -> &'a [f32] {
    let at = st.bins.at(ws, &st.blocks, k);
    super::pool::floats(ws, at, bin_floats(st.bands))
}

/// Adds polygon `poly`'s emitting sides to `acc`.
fn add_polygon(st: &State, ws: &[u8], poly: u32, unit: bool, acc: &mut [f32]) {
    let nb = st.bands;
    let rec = st.polygon(ws, poly);
    let n = Vec3::from(rec.normal);
    let root = Elem(rec.root);
    let sides = State::sides(root);
    let mut seen = [0.0f32; crate::limits::MAX_BANDS];
    if unit {
        let p = st.patch(ws, root);
        seen[..nb].fill(p.area * p.exposed);
    }
    for side in 0..2 {
        let d = if side == 0 { n } else { -n };
        let power = if !unit {
            st.polygon_power(ws, poly, side)
        } else if side < sides {
            &seen[..nb]
        } else {
            continue;
        };
        add(acc, nb, d, power);
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::sampling::{hash3, unit2};
    use std::vec::Vec;

    fn unit(h: u32) -> Vec3 {
        let (a, b) = unit2(h);
        let z = 2.0 * a - 1.0;
        let r = libm::sqrtf((1.0 - z * z).max(0.0));
        let phi = core::f32::consts::TAU * b;
        Vec3::new(r * libm::cosf(phi), r * libm::sinf(phi), z)
    }

    /// The polygon-by-polygon sum the bins stand for.
    fn exact(sides: &[(Vec3, [f32; 2])], w: Vec3) -> [f32; 2] {
        let mut out = [0.0f32; 2];
        for (n, p) in sides {
            let c = n.dot(w).max(0.0);
            out[0] += c * p[0];
            out[1] += c * p[1];
        }
        out
    }

    /// The bins' answer, every side of area `area(i)`.
    fn binned(sides: &[(Vec3, [f32; 2])], w: Vec3) -> [f32; 2] {
        let (mut power, mut area) = ([0.0f32; BINS * 2 * 4], [0.0f32; BINS * 2 * 4]);
        for (i, (n, p)) in sides.iter().enumerate() {
            add(&mut power, 2, *n, p);
            let a = side_area(i);
            add(&mut area, 2, *n, &[a, a]);
        }
        let mut out = [0.0f32; 2];
        emission(&power, &area, 2, w, &mut out);
        out
    }

    fn side_area(i: usize) -> f32 {
        0.5 + unit2(hash3(i as u32, 5, 5)).0
    }

    #[test]
    fn every_unit_vector_has_a_bin_within_the_spread_of_its_centre() {
        let mut seen = [false; BINS];
        for i in 0..200_000 {
            let n = unit(hash3(i, 1, 2));
            let b = bin_of(n);
            seen[b] = true;
            assert!(
                bin_centre(b).dot(n) >= libm::sqrtf(1.0 - SPREAD * SPREAD) - 1e-4,
                "{n:?} in bin {b}"
            );
        }
        assert!(seen.iter().all(|&s| s), "every bin is used");
        // The six axes, and a vector too short to be a normal.
        for (n, axis) in [
            (Vec3::X, Vec3::X),
            (-Vec3::X, -Vec3::X),
            (Vec3::Y, Vec3::Y),
            (-Vec3::Y, -Vec3::Y),
            (Vec3::Z, Vec3::Z),
            (-Vec3::Z, -Vec3::Z),
            (Vec3::new(0.0, -0.1, 0.05), -Vec3::Y),
        ] {
            assert_eq!(bin_centre(bin_of(n)), axis, "{n:?}");
        }
    }

    #[test]
    fn the_cap_mean_is_the_mean_over_the_cone() {
        // Monte Carlo over uniform cones (a million vectors each) against the closed form.
        for (c, seed) in [(0.5f32, 1u32), (0.75, 2), (0.95, 3), (0.999, 4)] {
            let cos_a = 2.0 * c - 1.0;
            let axis = Vec3::Z;
            for t in [-0.9f32, -0.3, -0.05, 0.0, 0.02, 0.2, 0.6, 1.0] {
                let w = Vec3::new(libm::sqrtf(1.0 - t * t), 0.0, t);
                let n = 1_000_000u32;
                let mut sum = 0.0f64;
                for i in 0..n {
                    let (a, b) = unit2(hash3(i, seed, 11));
                    let z = 1.0 - a * (1.0 - cos_a);
                    let r = libm::sqrtf((1.0 - z * z).max(0.0));
                    let phi = core::f32::consts::TAU * b;
                    let v = Vec3::new(r * libm::cosf(phi), r * libm::sinf(phi), z);
                    sum += v.dot(w).max(0.0) as f64;
                }
                let mc = (sum / n as f64) as f32;
                let _ = axis;
                assert!(
                    (cap_mean(c, t) - mc).abs() < 2e-3 * c.max(0.05),
                    "c {c} t {t}: {} vs {mc}",
                    cap_mean(c, t)
                );
            }
        }
        // The collimation's own identity: F(c, t) - F(c, -t) = c t.
        for c in [0.5f32, 0.7, 0.9, 0.99] {
            for t in [0.0f32, 0.1, 0.3, 0.7] {
                let d = cap_mean(c, t) - cap_mean(c, -t);
                assert!((d - c * t).abs() < 1e-5, "c {c} t {t}: {d}");
            }
        }
    }

    #[test]
    fn one_orientation_is_exact_in_every_direction() {
        // A flat soil cluster: every polygon faces the same way (one bin, collimation 1).
        let n = Vec3::new(0.3, 0.2, 0.93).normalize();
        let sides: Vec<_> = (0..50).map(|i| (n, [1.0 + i as f32, 2.0])).collect();
        for i in 0..2000 {
            let w = unit(hash3(i, 7, 7));
            let (e, b) = (exact(&sides, w), binned(&sides, w));
            for k in 0..2 {
                let total: f32 = sides.iter().map(|s| s.1[k]).sum();
                assert!((e[k] - b[k]).abs() <= 1e-3 * total, "{w:?}: {e:?} vs {b:?}");
            }
        }
    }

    #[test]
    fn leaves_facing_every_way_are_within_a_few_percent() {
        // A crown of leaves (two-sided: both sides emit, with different powers), and a
        // soil-like cluster of normals within 20 degrees of up: the binned emission against
        // the exact sum, relative to the largest emission over all directions.
        for (spread, seed) in [(1.0f32, 1u32), (0.06, 2), (0.3, 3), (0.01, 4)] {
            let sides: Vec<_> = (0..3000u32)
                .flat_map(|i| {
                    let mut n = unit(hash3(i, seed, 3));
                    if spread < 1.0 {
                        n = (Vec3::Z + n * libm::sqrtf(spread)).normalize();
                    }
                    let (a, b) = unit2(hash3(i, seed, 4));
                    [(n, [a, 0.5 * a]), (-n, [0.3 * b, b])]
                })
                .collect();
            let dirs: Vec<Vec3> = (0..4000).map(|i| unit(hash3(i, seed, 9))).collect();
            let peak = dirs
                .iter()
                .map(|&w| exact(&sides, w)[0].max(exact(&sides, w)[1]))
                .fold(0.0f32, f32::max);
            let mut worst = 0.0f32;
            for &w in &dirs {
                let (e, b) = (exact(&sides, w), binned(&sides, w));
                for k in 0..2 {
                    worst = worst.max((e[k] - b[k]).abs() / peak);
                }
            }
            std::eprintln!("spread {spread}: worst {worst}");
            assert!(worst < 0.025, "spread {spread}: worst {worst}");
        }
    }

    #[test]
    fn the_mean_facing_radiosity_is_linear_and_never_above_the_brightest_side() {
        // Radiosity p / area per side; the binned mean towards any direction stays within
        // the sides' range, and doubling every power doubles it.
        for seed in 0..4u32 {
            let sides: Vec<_> = (0..500u32)
                .map(|i| {
                    let n = unit(hash3(i, seed, 21));
                    let (a, _) = unit2(hash3(i, seed, 22));
                    (n, [a * side_area(i as usize), 2.0 * side_area(i as usize)])
                })
                .collect();
            let (mut power, mut area, mut double) = (
                [0.0f32; BINS * 2 * 4],
                [0.0f32; BINS * 2 * 4],
                [0.0f32; BINS * 2 * 4],
            );
            for (i, (n, p)) in sides.iter().enumerate() {
                add(&mut power, 2, *n, p);
                add(&mut double, 2, *n, &[2.0 * p[0], 2.0 * p[1]]);
                let a = side_area(i);
                add(&mut area, 2, *n, &[a, a]);
            }
            for i in 0..2000 {
                let w = unit(hash3(i, seed, 23));
                let (mut e, mut a, mut d) = ([0.0f32; 2], [0.0f32; 2], [0.0f32; 2]);
                emission(&power, &area, 2, w, &mut e);
                emission(&area, &area, 2, w, &mut a);
                emission(&double, &area, 2, w, &mut d);
                if a[0] <= 0.0 {
                    continue;
                }
                let mean = e[0] / a[0];
                assert!((-1e-6..=1.0 + 1e-4).contains(&mean), "{w:?}: {mean}");
                assert!((e[1] / a[0] - 2.0).abs() < 1e-4, "{w:?}: {}", e[1] / a[0]);
                for k in 0..2 {
                    assert!((d[k] - 2.0 * e[k]).abs() <= 1e-5 * d[k].abs().max(1e-6));
                }
            }
        }
    }
}
