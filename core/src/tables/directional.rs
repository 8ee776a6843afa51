//! All the tables of one original together: what a closed instance of it does with light
//! (DESIGN.md "Instances inside a level"): it blocks by `tau`, intercepts by the
//! cross-section `(1 - tau) A`, scatters out the albedo's share of what it intercepts, and
//! spreads that either by the uniform form (the paper's) or by the bidirectional response.
//!
//! `tau` and the albedo share a grid, refined until the cross-section meets its target: the
//! albedo changes sharply wherever the cross-section does (a sun that crosses the plane of a
//! leaf moves from its front, which reflects one way, to its back), and both come from the
//! same rays.
//! Units: m^2 for areas and powers per unit irradiance (W per W/m^2), m^2/sr for intensities
//! per unit irradiance.

use super::grid::DirectionGrid;
use super::phase::{PhaseTable, TableError, check_values, side_lit};
use super::single::SingleScatter;
use super::tau::{interpolate_scattered, interpolate_tau, projected_area};
use glam::Vec3;

/// An original's `tau` and phase tables, over caller storage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectionalTables<'a> {
    /// The original's box in its own frame (m).
    lo: Vec3,
    /// Upper corner.
    hi: Vec3,
    /// Grid of `tau`.
    tau_grid: DirectionGrid,
    /// `tau` per cell (0..=1).
    tau: &'a [f32],
    /// `[(cell * 2 + side) * bands + band]` on the `tau` grid: of the power the contents
    /// intercept from a sun in that cell, the fraction that leaves the box scattered after
    /// falling on the fronts (side 0) or on the backs (side 1) of the polygons (0..=1 each,
    /// their sum too).
    albedo: &'a [f32],
    /// The phase table: all the scattered light, or, with `single`, the light scattered
    /// more than once.
    phase: PhaseTable<'a>,
    /// The polygons' first scattering, kept per polygon (see [`super::single`]).
    single: Option<SingleScatter<'a>>,
}

impl<'a> DirectionalTables<'a> {
    /// Checks the box, `tau` and the albedo and puts them together with the phase table.
    pub fn new(
        lo: Vec3,
        hi: Vec3,
        tau_grid: DirectionGrid,
        tau: &'a [f32],
        albedo: &'a [f32],
        phase: PhaseTable<'a>,
    ) -> Result<Self, TableError> {
        if !lo.is_finite() || !hi.is_finite() || lo.cmpgt(hi).any() {
            return Err(TableError::Box);
        }
        check_values(tau, tau_grid.cells() as u64, 1.0)?;
        check_values(
            albedo,
            tau_grid.cells() as u64 * 2 * phase.bands() as u64,
            1.0 + 1e-3,
        )?;
        Ok(Self {
            lo,
            hi,
            tau_grid,
            tau,
            albedo,
            phase,
            single: None,
        })
    }

    /// The tables of `record` over storage that [`Self::from_record`] accepted before
    /// (nothing is checked again: a solve checks its tables once, when it loads them).
    /// Storage too short for the record gives empty tables rather than a panic.
    pub(crate) fn trusted(
        record: &crate::image::TableRecord,
        values: &'a [f32],
        visible: &'a [u8],
    ) -> Self {
        let mut rest = values;
        let mut take = |n: u64| {
            let n = (n as usize).min(rest.len());
            let (head, tail) = rest.split_at(n);
            rest = tail;
            head
        };
        let [tau, albedo, shares, response, shape] = record.lengths().map(&mut take);
        let grid = |side: u32| DirectionGrid::new(side).unwrap_or(DirectionGrid::ONE);
        let bands = (record.bands as usize).clamp(1, crate::limits::MAX_BANDS);
        let single = (record.scatterers > 0).then(|| {
            SingleScatter::trusted(
                grid(record.single_side),
                bands,
                record.scatterers as usize,
                shape,
                visible,
            )
        });
        Self {
            lo: Vec3::from(record.lo),
            hi: Vec3::from(record.hi),
            tau_grid: grid(record.tau_side),
            tau,
            albedo,
            phase: PhaseTable::trusted(
                grid(record.incoming_side),
                grid(record.outgoing_side),
                bands,
                shares,
                response,
            ),
            single,
        }
    }

    /// The same tables with the polygons' first scattering kept apart: the phase table then
    /// holds the light scattered more than once.
    pub fn with_single(self, single: SingleScatter<'a>) -> Result<Self, TableError> {
        let stride = super::single::shape_stride(self.phase.bands());
        if single.shape().len() != single.polygons() * stride {
            return Err(TableError::Bands);
        }
        Ok(Self {
            single: Some(single),
            ..self
        })
    }

    /// The polygons' first scattering, when the tables keep it apart.
    pub fn single(&self) -> Option<SingleScatter<'a>> {
        self.single
    }

    /// The box (m).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        (self.lo, self.hi)
    }

    /// The grid of `tau`.
    pub fn tau_grid(&self) -> DirectionGrid {
        self.tau_grid
    }

    /// `tau` at the cell centres.
    pub fn tau_values(&self) -> &'a [f32] {
        self.tau
    }

    /// The albedo at the cells of the `tau` grid, `[(cell * 2 + side) * bands + band]`.
    pub fn albedo_values(&self) -> &'a [f32] {
        self.albedo
    }

    /// The phase table.
    pub fn phase(&self) -> PhaseTable<'a> {
        self.phase
    }

    /// The box's projected area along `d` (m^2).
    pub fn area(&self, d: Vec3) -> f32 {
        projected_area(self.lo, self.hi, d)
    }

    /// Uncollided transmittance along `d`, interpolated (0..=1).
    pub fn tau(&self, d: Vec3) -> f32 {
        interpolate_tau(&self.tau_grid, self.tau, self.lo, self.hi, d)
    }

    /// The cross-section along `d`: the area of the contents' shadow, `(1 - tau) A` (m^2).
    pub fn shadow(&self, d: Vec3) -> f32 {
        (1.0 - self.tau(d)) * self.area(d)
    }

    /// Power scattered out of the box in band `band` for a sun of 1 W/m^2 towards `source`
    /// (m^2), of the light that fell on side `side` of the polygons (0 fronts, 1 backs).
    pub fn scattered_by(&self, source: Vec3, side: usize, band: usize) -> f32 {
        let bands = self.phase.bands();
        interpolate_scattered(
            &self.tau_grid,
            self.tau,
            self.albedo,
            2 * bands,
            side * bands + band,
            self.lo,
            self.hi,
            source,
        )
    }

    /// Power scattered out of the box in band `band` for a sun of 1 W/m^2 towards `source`
    /// (m^2): the scattered cross-section `albedo (1 - tau) A`, interpolated as a whole for
    /// the reason `tau` is (see [`interpolate_tau`]).
    pub fn scattered(&self, source: Vec3, band: usize) -> f32 {
        self.scattered_by(source, 0, band) + self.scattered_by(source, 1, band)
    }

    /// Of the power intercepted from a sun towards `source`, the fraction scattered out in
    /// band `band` (0..=1; 0 where nothing is intercepted).
    pub fn albedo(&self, source: Vec3, band: usize) -> f32 {
        let s = self.shadow(source);
        if s > 0.0 {
            (self.scattered(source, band) / s).clamp(0.0, 1.0)
        } else {
            0.0
        }
    }

    /// Intensity leaving the box towards `observer` in band `band` for a sun of 1 W/m^2
    /// towards `source` (m^2/sr): the polygons' first scattering where the tables keep it
    /// (see [`super::single`]) plus the bidirectional response's part.
    pub fn intensity(&self, source: Vec3, observer: Vec3, band: usize) -> f32 {
        let single = self
            .single
            .map_or(0.0, |s| s.intensity(source, observer, band));
        single + self.response_intensity(source, observer, band)
    }

    /// The part of [`Self::intensity`] the phase table holds: per side lit (see
    /// [`side_lit`]), the response interpolated over the incoming cells where that side is
    /// lit times the power scattered from that side, times the cross-section seen (m^2/sr).
    pub fn response_intensity(&self, source: Vec3, observer: Vec3, band: usize) -> f32 {
        let total = self.scattered(source, band);
        let mut sum = 0.0;
        for side in 0..2 {
            let s = self.scattered_by(source, side, band);
            if !side_lit(s, total) {
                continue;
            }
            sum += self.phase.response(source, observer, side, band) * s;
        }
        sum * self.shadow(observer)
    }

    /// The same by the uniform form: the scattered power leaves as if from a surface of
    /// uniform radiance whose area seen from `observer` is the cross-section there.
    pub fn uniform_intensity(&self, source: Vec3, observer: Vec3, band: usize) -> f32 {
        let integral = self.shadow_integral();
        if integral <= 0.0 {
            return 0.0;
        }
        self.scattered(source, band) * self.shadow(observer) / integral
    }

    /// The cross-section integrated over the sphere (m^2 sr): the uniform form's spread.
    pub fn shadow_integral(&self) -> f32 {
        let g = self.tau_grid;
        (0..g.cells())
            .map(|c| {
                let t = self.tau.get(c as usize).copied().unwrap_or(1.0);
                (1.0 - t) * projected_area(self.lo, self.hi, g.direction(c))
            })
            .sum::<f32>()
            * g.solid_angle()
    }
}
