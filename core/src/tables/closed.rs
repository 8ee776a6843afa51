//! A closed instance inside a level (DESIGN.md "Instances inside a level"): its original's
//! tables placed in the world by the instance's transform, and the light it has received,
//! kept in the form its outgoing intensity needs.
//!
//! Light reaches a closed instance as beams: a sun, a sky direction, a link from an element
//! of the level, each an irradiance on a plane facing the source (W/m^2 per band) and the
//! direction towards the source. Nothing is binned: each beam adds, at its own direction,
//! - to every polygon whose first scattering the tables keep (see [`super::single`]), the
//!   irradiance that reaches its lit side, `E |n.d| V_p(d)` (W/m^2, per side and band);
//! - to the phase table's incoming cells around its direction, by their interpolation
//!   weights, the power scattered more than once (W per unit response);
//! - to the power the contents intercept and scatter out (W, per band).
//!
//! The intensity towards any observer is then one sum over the polygons and the incoming
//! cells: exactly `sum_beams E DirectionalTables::intensity(d, o)`, at a cost that does not
//! grow with the number of beams. Areas and intensities scale with the square of the
//! instance's scale; directions turn with its rotation.

use super::directional::DirectionalTables;
use super::phase::{LIT_SHARE, TableError, side_lit};
use crate::geometry::{Aabb, Similarity};
use crate::limits::MAX_BANDS;
use glam::Vec3;

/// Floats of the light a closed instance receives (see [`Received`]) for tables of `bands`
/// bands, `scatterers` polygons kept apart and `incoming_cells` cells of the phase table's
/// incoming grid: per band the power intercepted and scattered, per polygon, cell, side and
/// band one value.
pub const fn received_floats(bands: usize, scatterers: usize, incoming_cells: usize) -> usize {
    2 * bands + 2 * bands * (scatterers + incoming_cells)
}

/// An original's tables placed in the world by an instance's transform.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placed<'a> {
    tables: DirectionalTables<'a>,
    place: Similarity,
    /// `place.scale` squared: how areas and intensities grow.
    area_scale: f32,
}

impl<'a> Placed<'a> {
    /// The tables of an original placed by `place` (the instance's transform to world).
    pub fn new(tables: DirectionalTables<'a>, place: Similarity) -> Self {
        Self {
            tables,
            place,
            area_scale: place.scale * place.scale,
        }
    }

    /// The original's tables.
    pub fn tables(&self) -> &DirectionalTables<'a> {
        &self.tables
    }

    /// The transform to world.
    pub fn place(&self) -> Similarity {
        self.place
    }

    /// A world direction in the original's frame (unit).
    pub fn local(&self, d: Vec3) -> Vec3 {
        (self.place.rotation.conjugate() * d).normalize_or_zero()
    }

    /// A world box that holds the placed box (m).
    pub fn bounds(&self) -> Aabb {
        let (lo, hi) = self.tables.bounds();
        self.place.aabb(&Aabb::new(lo, hi))
    }

    /// Uncollided transmittance along the world direction `d` (0..=1).
    pub fn tau(&self, d: Vec3) -> f32 {
        self.tables.tau(self.local(d))
    }

    /// The box's projected area along the world direction `d` (m^2).
    pub fn area(&self, d: Vec3) -> f32 {
        self.area_scale * self.tables.area(self.local(d))
    }

    /// The contents' cross-section along the world direction `d`, `(1 - tau) A` (m^2): the
    /// area that intercepts a beam from there, and the area an observer there sees glow.
    pub fn shadow(&self, d: Vec3) -> f32 {
        self.area_scale * self.tables.shadow(self.local(d))
    }

    /// Power scattered out in band `band` for a sun of 1 W/m^2 towards the world direction
    /// `source` (m^2).
    pub fn scattered(&self, source: Vec3, band: usize) -> f32 {
        self.area_scale * self.tables.scattered(self.local(source), band)
    }

    /// Intensity towards the world direction `observer` in band `band` for a sun of
    /// 1 W/m^2 towards `source` (m^2/sr).
    pub fn intensity(&self, source: Vec3, observer: Vec3, band: usize) -> f32 {
        self.area_scale
            * self
                .tables
                .intensity(self.local(source), self.local(observer), band)
    }

    /// The part of the line through `from` and `to` (world, m) inside the placed box, as
    /// parameters `(s0, s1)` (0 at `from`, 1 at `to`), or `None` when the line misses it.
    fn chord(&self, from: Vec3, to: Vec3) -> Option<(f32, f32)> {
        let (lo, hi) = self.tables.bounds();
        box_chord(lo, hi, &self.place, from, to)
    }

    /// True when the segment from `from` to `to` (world, m) crosses the placed box.
    pub fn crosses(&self, from: Vec3, to: Vec3) -> bool {
        self.chord(from, to)
            .is_some_and(|(s0, s1)| s0 <= 1.0 && s1 >= 0.0)
    }

    /// What the contents let through along the segment from `from` to `to` (world, m):
    /// `tau` of its direction where it crosses the whole box; where it starts or ends inside,
    /// `tau` to the power of the share of the box's chord it runs through (as light through
    /// a uniform medium), so that a point deep inside a neighbour's box is not shaded by all
    /// of it. 1 when it misses the box.
    pub fn transmittance(&self, from: Vec3, to: Vec3) -> f32 {
        let Some((s0, s1)) = self.chord(from, to) else {
            return 1.0;
        };
        let (a, b) = (s0.max(0.0), s1.min(1.0));
        if a > b {
            return 1.0;
        }
        let t = self.tau((to - from).normalize_or_zero());
        share_of(t, s0, s1, a, b)
    }
}

/// A world point in the frame `place` maps to world.
pub(crate) fn local_point(place: &Similarity, x: Vec3) -> Vec3 {
    place.rotation.conjugate() * (x - place.translation) / place.scale
}

/// The part of the line through `from` and `to` (world) inside the box `lo..hi` of the frame
/// `place` maps to world, as parameters `(s0, s1)` (0 at `from`, 1 at `to`), or `None`.
fn box_chord(lo: Vec3, hi: Vec3, place: &Similarity, from: Vec3, to: Vec3) -> Option<(f32, f32)> {
    let (a, b) = (local_point(place, from), local_point(place, to));
    let d = b - a;
    let (mut t0, mut t1) = (f32::NEG_INFINITY, f32::INFINITY);
    for k in 0..3 {
        if d[k] == 0.0 {
            if a[k] < lo[k] || a[k] > hi[k] {
                return None;
            }
            continue;
        }
        let (mut ta, mut tb) = ((lo[k] - a[k]) / d[k], (hi[k] - a[k]) / d[k]);
        if ta > tb {
            core::mem::swap(&mut ta, &mut tb);
        }
        t0 = t0.max(ta);
        t1 = t1.min(tb);
    }
    (t0 <= t1 && t0.is_finite() && t1.is_finite()).then_some((t0, t1))
}

/// Where the segment `from..to` (world) enters the box `lo..hi` placed by `place` (its
/// parameter, 0 at `from`) and what the contents let through along it when `tau` of its
/// direction is `t` (see [`Placed::transmittance`]); `None` when it does not run through.
pub fn box_crossing(
    lo: Vec3,
    hi: Vec3,
    place: &Similarity,
    from: Vec3,
    to: Vec3,
    t: f32,
) -> Option<(f32, f32)> {
    let (s0, s1) = box_chord(lo, hi, place, from, to)?;
    let (a, b) = (s0.max(0.0), s1.min(1.0));
    runs_through(s0, s1).then(|| (a, share_of(t, s0, s1, a, b)))
}

/// True when the segment's parameters `0..1` run through the chord `s0..s1` of a box: some
/// of it, or, for a flat box (a single leaf's, of no thickness), its plane within the
/// segment.
fn runs_through(s0: f32, s1: f32) -> bool {
    let (a, b) = (s0.max(0.0), s1.min(1.0));
    a < b || (s0 == s1 && a > 0.0 && a < 1.0)
}

/// True when the segment `from..to` (world) runs through some of the box `lo..hi` placed by
/// `place` (more than touching it), or through the plane of a flat box.
pub fn box_crossed(lo: Vec3, hi: Vec3, place: &Similarity, from: Vec3, to: Vec3) -> bool {
    box_chord(lo, hi, place, from, to).is_some_and(|(s0, s1)| runs_through(s0, s1))
}

/// What the contents of the box `lo..hi` (placed by `place`) let through along the segment
/// `from..to` when `tau` of its direction is `t` (see [`Placed::transmittance`]): for callers
/// that know `t` and the box without the tables.
pub fn box_transmittance(
    lo: Vec3,
    hi: Vec3,
    place: &Similarity,
    from: Vec3,
    to: Vec3,
    t: f32,
) -> f32 {
    box_crossing(lo, hi, place, from, to, t).map_or(1.0, |(_, through)| through)
}

/// `t` to the power of the share `(b - a) / (s1 - s0)` of a chord (see
/// [`Placed::transmittance`]).
fn share_of(t: f32, s0: f32, s1: f32, a: f32, b: f32) -> f32 {
    let share = if s1 > s0 { (b - a) / (s1 - s0) } else { 1.0 };
    if share >= 1.0 {
        t
    } else if t <= 0.0 {
        if share > 0.0 { 0.0 } else { 1.0 }
    } else {
        libm::powf(t, share)
    }
}

impl Placed<'_> {
    /// Floats of storage the light received by this instance needs (see [`Received`]).
    pub fn received_len(&self) -> usize {
        received_floats(
            self.tables.phase().bands(),
            self.tables.single().map_or(0, |s| s.polygons()),
            self.tables.phase().incoming().cells() as usize,
        )
    }
}

/// The light a closed instance has received, over caller storage of
/// [`Placed::received_len`] floats: per band the power intercepted and scattered out (W),
/// per polygon kept apart and side lit the irradiance on it (W/m^2, original's units), per
/// incoming cell and side lit the scattered power's weight (W). `S` is the storage: a
/// mutable slice to receive light, a shared one to read it.
#[derive(Debug)]
pub struct Received<S> {
    values: S,
    bands: usize,
    polygons: usize,
}

impl<S: AsRef<[f32]>> Received<S> {
    /// The light `placed` received, kept in `values` (nothing is cleared).
    pub fn over(placed: &Placed<'_>, values: S) -> Result<Self, TableError> {
        let expected = placed.received_len();
        let given = values.as_ref().len();
        if given != expected {
            return Err(TableError::Length {
                expected: expected as u64,
                given: given as u64,
            });
        }
        Ok(Self {
            values,
            bands: placed.tables.phase().bands(),
            polygons: placed.tables.single().map_or(0, |s| s.polygons()),
        })
    }

    fn v(&self) -> &[f32] {
        self.values.as_ref()
    }

    fn polygon_at(&self, p: usize, side: usize, band: usize) -> usize {
        2 * self.bands + (p * 2 + side) * self.bands + band
    }

    fn cell_at(&self, cell: usize, side: usize, band: usize) -> usize {
        2 * self.bands + (self.polygons * 2 + cell * 2 + side) * self.bands + band
    }

    /// Power intercepted by the contents in band `band` (W).
    pub fn intercepted(&self, band: usize) -> f32 {
        self.v()[band]
    }

    /// Power scattered out of the box in band `band` (W).
    pub fn scattered(&self, band: usize) -> f32 {
        self.v()[self.bands + band]
    }

    /// Power absorbed inside in band `band` (W): intercepted less scattered out.
    pub fn absorbed(&self, band: usize) -> f32 {
        self.intercepted(band) - self.scattered(band)
    }

    /// Intensity (W/sr) that leaves the instance towards the world direction `observer` in
    /// band `band`, from all the light received.
    pub fn intensity(&self, placed: &Placed<'_>, observer: Vec3, band: usize) -> f32 {
        let (all, _) = self.intensity_parts(placed, observer, band);
        all
    }

    /// Where the irradiance of the polygons kept apart lies among the floats of storage (see
    /// [`Placed::received_len`]): every polygon's, side by side and band by band, in one
    /// range, so that a caller can add one instance's to another's as plain floats.
    pub fn first_range(&self) -> core::ops::Range<usize> {
        let start = 2 * self.bands;
        start..start + self.polygons * 2 * self.bands
    }

    /// The irradiance (W/m^2) on side `side` of polygon `p` kept apart in band `band`, 0
    /// when there is no such polygon.
    pub fn first_irradiance(&self, p: usize, side: usize, band: usize) -> f32 {
        if p < self.polygons && band < self.bands && side < 2 {
            self.v()[self.polygon_at(p, side, band)]
        } else {
            0.0
        }
    }

    /// Polygon `p`'s first-scattered radiosity on side `side` (0 front, 1 back) in band
    /// `band` (W/m^2): what it reflects and transmits of the light that reached it
    /// straight from the beams received; 0 when the tables keep no polygon apart.
    pub fn first_radiosity(&self, placed: &Placed<'_>, p: usize, side: usize, band: usize) -> f32 {
        let Some(single) = placed.tables.single() else {
            return 0.0;
        };
        if p >= self.polygons || band >= self.bands {
            return 0.0;
        }
        let (_, _, [rho_front, rho_back, tau]) = single.polygon(p, band);
        let v = self.v();
        let (front, back) = (
            v[self.polygon_at(p, 0, band)],
            v[self.polygon_at(p, 1, band)],
        );
        if side == 0 {
            rho_front * front + tau * back
        } else {
            rho_back * back + tau * front
        }
    }

    /// [`Self::intensity`] towards `observer` and its part scattered once (W/sr each).
    pub fn intensity_parts(&self, placed: &Placed<'_>, observer: Vec3, band: usize) -> (f32, f32) {
        if band >= self.bands {
            return (0.0, 0.0);
        }
        let (mut all, mut once) = ([0.0f32; MAX_BANDS], [0.0f32; MAX_BANDS]);
        self.intensity_bands(placed, observer, band..band + 1, &mut all, &mut once);
        (all[band], once[band])
    }

    /// [`Self::intensity`] towards `observer` in every band at once (W/sr), into
    /// `out[band]` for the bands `out` has room for (the rest of `out` is set to 0): the
    /// directions' weights and the polygons' visible fractions are found once for all bands,
    /// and each band's value is the one [`Self::intensity`] gives, to the bit.
    pub fn intensity_all(&self, placed: &Placed<'_>, observer: Vec3, out: &mut [f32]) {
        out.fill(0.0);
        let (mut all, mut once) = ([0.0f32; MAX_BANDS], [0.0f32; MAX_BANDS]);
        let n = out.len().min(self.bands);
        self.intensity_bands(placed, observer, 0..n, &mut all, &mut once);
        out[..n].copy_from_slice(&all[..n]);
    }

    /// [`Self::intensity_all`] and the part scattered once, per band (W/sr each).
    pub fn intensity_parts_all(
        &self,
        placed: &Placed<'_>,
        observer: Vec3,
        all: &mut [f32],
        once: &mut [f32],
    ) {
        all.fill(0.0);
        once.fill(0.0);
        let (mut a, mut o) = ([0.0f32; MAX_BANDS], [0.0f32; MAX_BANDS]);
        let n = all.len().min(once.len()).min(self.bands);
        self.intensity_bands(placed, observer, 0..n, &mut a, &mut o);
        all[..n].copy_from_slice(&a[..n]);
        once[..n].copy_from_slice(&o[..n]);
    }

    /// The intensity towards `observer` and its part scattered once in each band of
    /// `bands` (W/sr), into `all[band]` and `once[band]`; each band summed in the same order
    /// whichever bands are asked.
    fn intensity_bands(
        &self,
        placed: &Placed<'_>,
        observer: Vec3,
        bands: core::ops::Range<usize>,
        all: &mut [f32; MAX_BANDS],
        once: &mut [f32; MAX_BANDS],
    ) {
        let o = placed.local(observer);
        let bands = bands.start..bands.end.min(self.bands);
        if o == Vec3::ZERO || bands.is_empty() {
            return;
        }
        let t = &placed.tables;
        let phase = t.phase();
        let v = self.v();
        // The rest: what the incoming cells hold, through the response towards `o`.
        let out = phase.outgoing().weights(o);
        let mut rest = [0.0f32; MAX_BANDS];
        for c in 0..phase.incoming().cells() {
            for side in 0..2 {
                for band in bands.clone() {
                    let w = v[self.cell_at(c as usize, side, band)];
                    if w == 0.0 {
                        continue;
                    }
                    let r: f32 = out
                        .iter()
                        .map(|&(co, wo)| wo * phase.response_at(c, co, side, band))
                        .sum();
                    rest[band] += w * r;
                }
            }
        }
        let shadow = t.shadow(o);
        // The first scattering: each polygon's lit sides as the observer sees them.
        if let Some(single) = t.single() {
            let wo = single.grid().weights(o);
            for p in 0..self.polygons {
                let (n, area) = single.normal_area(p);
                let co = n.dot(o);
                if co == 0.0 {
                    continue;
                }
                let mut fraction = None;
                for band in bands.clone() {
                    let [rho_front, rho_back, tau] = single.optics(p, band);
                    let front = v[self.polygon_at(p, 0, band)];
                    let back = v[self.polygon_at(p, 1, band)];
                    let k = if co > 0.0 {
                        rho_front * front + tau * back
                    } else {
                        rho_back * back + tau * front
                    };
                    if k > 0.0 {
                        let f = *fraction.get_or_insert_with(|| single.fraction(&wo, p));
                        once[band] += area * co.abs() * f * k / core::f32::consts::PI;
                    }
                }
            }
        }
        for band in bands {
            let sum = rest[band] * shadow + once[band];
            all[band] = placed.area_scale * sum;
            once[band] *= placed.area_scale;
        }
    }
}

impl<S: AsRef<[f32]> + AsMut<[f32]>> Received<S> {
    /// Storage for the light `placed` receives, cleared.
    pub fn new(placed: &Placed<'_>, values: S) -> Result<Self, TableError> {
        let mut r = Self::over(placed, values)?;
        r.clear();
        Ok(r)
    }

    /// Forgets all light received.
    pub fn clear(&mut self) {
        self.values.as_mut().fill(0.0);
    }

    /// Adds all the light `other` (of the same instance) received.
    pub fn add<T: AsRef<[f32]>>(&mut self, other: &Received<T>) {
        for (a, b) in self.values.as_mut().iter_mut().zip(other.v()) {
            *a += b;
        }
    }

    /// Adds a beam: `irradiance` (W/m^2 per band, on a plane facing the source) from the
    /// world direction `towards` (towards the source). Non-finite or negative values and a
    /// zero direction add nothing.
    pub fn receive(&mut self, placed: &Placed<'_>, towards: Vec3, irradiance: &[f32]) {
        self.receive_parts(placed, towards, irradiance, true, false);
    }

    /// [`Self::receive`] without the first scattering polygon by polygon: for a caller that
    /// knows where the beam's light lands on the polygons and adds it with
    /// [`Self::add_first`] (the light between neighbours whose boxes overlap does not come
    /// from beyond the box).
    pub fn receive_spread(&mut self, placed: &Placed<'_>, towards: Vec3, irradiance: &[f32]) {
        self.receive_parts(placed, towards, irradiance, false, false);
    }

    /// Changes a beam's light by `change` (W/m^2 per band, of either sign): what was received
    /// from `towards` becomes what it is now, by linearity, without keeping the beams apart
    /// (a level's closed instances keep their light from one gather to the next and take
    /// only the change). `first`: as [`Self::receive`] (true) or [`Self::receive_spread`].
    pub fn change(&mut self, placed: &Placed<'_>, towards: Vec3, change: &[f32], first: bool) {
        self.receive_parts(placed, towards, change, first, true);
    }

    /// Adds `irradiance` (W/m^2) in band `band` to side `side` of polygon `p` kept apart
    /// (its first scattering's light; nothing when there is no such polygon).
    pub fn add_first(&mut self, p: usize, side: usize, band: usize, irradiance: f32) {
        if p < self.polygons && band < self.bands && side < 2 && irradiance.is_finite() {
            let at = self.polygon_at(p, side, band);
            self.values.as_mut()[at] += irradiance;
        }
    }

    fn receive_parts(
        &mut self,
        placed: &Placed<'_>,
        towards: Vec3,
        irradiance: &[f32],
        first: bool,
        signed: bool,
    ) {
        let d = placed.local(towards);
        if d == Vec3::ZERO {
            return;
        }
        let t = &placed.tables;
        let bands = self.bands.min(irradiance.len());
        let scale = placed.area_scale;
        let shadow = t.shadow(d);
        let weights = t.phase().incoming().weights(d);
        let single = t.single();
        let wd = single.map(|s| s.grid().weights(d));
        for (band, &e) in irradiance.iter().enumerate().take(bands) {
            if !(e.is_finite() && (e > 0.0 || signed && e != 0.0)) {
                continue;
            }
            let (nb, polygons) = (self.bands, self.polygons);
            let scattered_at = nb + band;
            let by_side = [t.scattered_by(d, 0, band), t.scattered_by(d, 1, band)];
            let total = by_side[0] + by_side[1];
            let cells: heapless::Vec<(usize, f32), 8> =
                lit_cells(t, &weights, &by_side, total, band)
                    .map(|(c, side, w)| (self.cell_at(c as usize, side, band), w))
                    .collect();
            let v = self.values.as_mut();
            v[band] += e * scale * shadow;
            v[scattered_at] += e * scale * total;
            for (at, w) in cells {
                v[at] += e * w;
            }
            // The first scattering, polygon by polygon.
            if let (true, Some(single), Some(wd)) = (first, single, wd.as_ref()) {
                for p in 0..polygons {
                    let (n, _, _) = single.polygon(p, band);
                    let cd = n.dot(d);
                    if cd == 0.0 {
                        continue;
                    }
                    let side = usize::from(cd < 0.0);
                    let at = 2 * nb + (p * 2 + side) * nb + band;
                    v[at] += e * cd.abs() * single.fraction(wd, p);
                }
            }
        }
    }
}

/// The incoming cells around a direction of weights `weights` where each side is lit, with
/// the scattered power (per unit irradiance, m^2) each holds of the light scattered more
/// than once: as `PhaseTable::response` weighs them, renormalised over the lit cells.
fn lit_cells<'t>(
    t: &'t DirectionalTables<'_>,
    weights: &'t [(u32, f32); 4],
    by_side: &'t [f32; 2],
    total: f32,
    band: usize,
) -> impl Iterator<Item = (u32, usize, f32)> + 't {
    (0..2usize).flat_map(move |side| {
        let s = by_side[side];
        let lit = move |c: u32| t.phase().share_at(c, side, band) >= LIT_SHARE;
        let sum: f32 = if side_lit(s, total) {
            weights
                .iter()
                .filter(|&&(c, w)| w > 0.0 && lit(c))
                .map(|&(_, w)| w)
                .sum()
        } else {
            0.0
        };
        weights
            .iter()
            .filter(move |&&(c, w)| sum > 0.0 && w > 0.0 && lit(c))
            .map(move |&(c, w)| (c, side, s * w / sum))
    })
}
