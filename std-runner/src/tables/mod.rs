//! Directional tables of originals (issue 17, paper sections 3.1 and 4): for each original
//! that instances share, `tau(dir)`, the box's projected area `A(dir)` and the phase table,
//! measured on the original alone, expanded, in its own frame.
//!
//! Units: directions are unit vectors in the original's frame (incoming ones towards the
//! source, outgoing ones towards the observer); areas m^2; intensities m^2/sr (W/sr per W/m^2
//! of sun); fractions of the power the box intercepts (sun irradiance x `A(dir)`).

mod bake;
mod cache;
mod check;
mod complete;
mod export;
mod intercept;
mod original;
mod plot;
mod response;
mod sample;
mod single_bake;
mod tau_bake;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_image;

pub use bake::{TableSettings, bake_alone, bake_original, uniform_direction};
pub use cache::{Cache, Key};
pub use check::{CheckReport, check};
pub use complete::{
    Completed, complete, complete_with, instanced_originals, missing, missing_of, obtain,
};
pub use export::{write_bidirectional, write_directions};
pub use original::{Alone, Lit};
pub use plot::{map_pixel, picture, plot_sun, write_plots};
pub use sample::{Sample, sample_at, sample_sides};

use glam::Vec3;
use hirad_core::tables::directional::DirectionalTables;
use hirad_core::tables::grid::DirectionGrid;
use hirad_core::tables::phase::PhaseTable;
use hirad_core::tables::single::SingleScatter;

/// The tables of one original and what was measured making them.
#[derive(Clone, Debug)]
pub struct OriginalTables {
    /// The original's name.
    pub name: String,
    /// Its index in the scene's originals.
    pub index: usize,
    /// Polygons of the original expanded.
    pub polygons: usize,
    /// Bands.
    pub bands: usize,
    /// Its bounding box in its own frame (m).
    pub lo: Vec3,
    /// Upper corner.
    pub hi: Vec3,
    /// Grid of `tau`.
    pub tau_grid: DirectionGrid,
    /// `tau` per cell of `tau_grid` (dimensionless, 0..=1).
    pub tau: Vec<f32>,
    /// Per cell of `tau_grid` and band: of the power intercepted, the share scattered out
    /// (dimensionless, 0..=1).
    pub albedo: Vec<f32>,
    /// Largest error of the interpolated cross-section `(1 - tau) A` or scattered
    /// cross-section at the bake's check directions, relative to itself (or to 5% of `A`
    /// where the contents cast less).
    pub tau_error: f32,
    /// Grid of incoming directions of the phase table.
    pub incoming: DirectionGrid,
    /// Grid of outgoing directions of the bidirectional phase table.
    pub outgoing: DirectionGrid,
    /// Per incoming cell, side lit and band: the share of the scattered power that fell on
    /// that side first (see [`PhaseTable`]).
    pub shares: Vec<f32>,
    /// Per incoming cell, outgoing cell, side lit and band: the response (1/(m^2 sr), see
    /// [`PhaseTable`]).
    pub response: Vec<f32>,
    /// The polygons' first scattering kept apart, when the original is small enough (the
    /// response then holds the light scattered more than once).
    pub single: Option<Scatterers>,
    /// Per incoming cell and band: the absorbed fraction.
    pub absorbed: Vec<f32>,
    /// Per incoming cell and band: what enters minus what is absorbed, scattered out (the
    /// table's intensity summed over the sphere) and transmitted uncollided, over what enters.
    pub residual: Vec<f32>,
    /// Largest relative error of the interpolated scattered fraction at the check
    /// directions (relative to the measured fraction, or to 0.01 when smaller).
    pub scattered_error: f32,
    /// Largest error of the interpolated intensity at the check directions, relative to the
    /// measured intensity or, when it is darker, to the mean over all directions.
    pub intensity_error: f32,
    /// Incoming grids tried: side, scattered error, intensity error.
    pub tried: Vec<(u32, f32, f32)>,
    /// Outgoing grids tried: side, intensity error at the check suns' own light.
    pub out_tried: Vec<(u32, f32)>,
    /// True when every error met its target (false: a grid reached its largest side first).
    pub met: bool,
    /// Suns the original was solved under (grids and checks; several share one hr solve,
    /// see [`Alone::solve_many`]).
    pub solves: u32,
    /// Rays cast for `tau` and the outgoing light.
    pub rays: u64,
    /// Seconds spent.
    pub seconds: f64,
}

/// The polygons of an original whose first scattering its tables keep apart (see
/// [`hirad_core::tables::single`]).
#[derive(Clone, Debug)]
pub struct Scatterers {
    /// Grid of the visible fractions.
    pub grid: DirectionGrid,
    /// Polygons.
    pub polygons: usize,
    /// Per polygon: normal, area (m^2), then per band front and back reflectance and
    /// transmittance.
    pub shape: Vec<f32>,
    /// `[cell * polygons + p]`: visible fractions in 1/255 steps.
    pub visible: Vec<u8>,
    /// Grids tried: side, largest error of the interpolated first scattering at the check
    /// directions (relative as the intensity's).
    pub tried: Vec<(u32, f32)>,
}

impl OriginalTables {
    /// The tables as the core reads them, or why they are not sound.
    pub fn try_view(&self) -> Result<DirectionalTables<'_>, hirad_core::tables::phase::TableError> {
        let phase = PhaseTable::new(
            self.incoming,
            self.outgoing,
            self.bands,
            &self.shares,
            &self.response,
        )?;
        let t = DirectionalTables::new(
            self.lo,
            self.hi,
            self.tau_grid,
            &self.tau,
            &self.albedo,
            phase,
        )?;
        match &self.single {
            None => Ok(t),
            Some(s) => t.with_single(SingleScatter::new(
                s.grid, self.bands, s.polygons, &s.shape, &s.visible,
            )?),
        }
    }

    /// Tables as an image or a cache entry stores them: `values` in the record's order
    /// (see [`TableRecord::lengths`]) and the scatterers' visible fractions; `None` unless
    /// they make sound tables. What only a bake knows (grids tried, time, absorbed
    /// fractions and residuals) is left empty.
    pub fn from_record(
        name: &str,
        index: usize,
        polygons: usize,
        record: &hirad_core::image::TableRecord,
        values: &[f32],
        visible: &[u8],
    ) -> Option<Self> {
        let [tau, albedo, shares, response, shape] = record.lengths().map(|n| n as usize);
        if values.len() != tau + albedo + shares + response + shape
            || visible.len() as u64 != record.visible_bytes()
        {
            return None;
        }
        let grid = |s: u32| DirectionGrid::new(s).ok();
        let mut at = 0usize;
        let mut take = |n: usize| {
            let v = values[at..at + n].to_vec();
            at += n;
            v
        };
        let single = if record.scatterers > 0 {
            Some(Scatterers {
                grid: grid(record.single_side)?,
                polygons: record.scatterers as usize,
                shape: Vec::new(),
                visible: visible.to_vec(),
                tried: Vec::new(),
            })
        } else {
            None
        };
        let mut t = OriginalTables {
            name: name.to_string(),
            index,
            polygons,
            bands: record.bands as usize,
            lo: Vec3::from(record.lo),
            hi: Vec3::from(record.hi),
            tau_grid: grid(record.tau_side)?,
            tau: take(tau),
            albedo: take(albedo),
            tau_error: record.tau_error,
            incoming: grid(record.incoming_side)?,
            outgoing: grid(record.outgoing_side)?,
            shares: take(shares),
            response: take(response),
            single,
            absorbed: Vec::new(),
            residual: Vec::new(),
            scattered_error: record.scattered_error,
            intensity_error: record.intensity_error,
            tried: Vec::new(),
            out_tried: Vec::new(),
            met: record.flags & hirad_core::image::TABLE_MET != 0,
            solves: 0,
            rays: 0,
            seconds: 0.0,
        };
        if let Some(s) = &mut t.single {
            s.shape = take(shape);
        }
        // The values must make sound tables (ranges, lengths, box), as the image's would.
        t.try_view().ok()?;
        Some(t)
    }

    /// The tables as the core reads them (a bake or a cache entry is always sound).
    pub fn view(&self) -> DirectionalTables<'_> {
        self.try_view().expect("baked tables are consistent")
    }

    /// The tables as the scene model and the image store them.
    pub fn to_scene(&self) -> crate::scene::Tables {
        use hirad_core::image::{TABLE_MET, TableRecord};
        let shape: &[f32] = self.single.as_ref().map_or(&[], |s| &s.shape);
        let mut values = Vec::with_capacity(
            self.tau.len()
                + self.albedo.len()
                + self.shares.len()
                + self.response.len()
                + shape.len(),
        );
        values.extend_from_slice(&self.tau);
        values.extend_from_slice(&self.albedo);
        values.extend_from_slice(&self.shares);
        values.extend_from_slice(&self.response);
        values.extend_from_slice(shape);
        crate::scene::Tables {
            original: self.index,
            record: TableRecord {
                original: self.index as u32,
                bands: self.bands as u32,
                tau_side: self.tau_grid.side(),
                incoming_side: self.incoming.side(),
                outgoing_side: self.outgoing.side(),
                flags: if self.met { TABLE_MET } else { 0 },
                lo: self.lo.to_array(),
                hi: self.hi.to_array(),
                first: 0,
                tau_error: self.tau_error,
                scattered_error: self.scattered_error,
                intensity_error: self.intensity_error,
                scatterers: self.single.as_ref().map_or(0, |s| s.polygons as u32),
                single_side: self.single.as_ref().map_or(0, |s| s.grid.side()),
                reserved: 0,
                first_visible: 0,
            },
            values,
            visible: self
                .single
                .as_ref()
                .map_or(Vec::new(), |s| s.visible.clone()),
        }
    }

    /// Bytes of the tables (f32 values, one byte per visible fraction).
    pub fn bytes(&self) -> u64 {
        let (shape, visible) = self
            .single
            .as_ref()
            .map_or((0, 0), |s| (s.shape.len(), s.visible.len()));
        4 * (self.tau.len() + self.albedo.len() + self.shares.len() + self.response.len() + shape)
            as u64
            + visible as u64
    }

    /// Largest |residual| over the incoming cells, per band.
    pub fn worst_residual(&self) -> Vec<f32> {
        (0..self.bands)
            .map(|b| {
                self.residual
                    .iter()
                    .skip(b)
                    .step_by(self.bands)
                    .fold(0.0f32, |m, r| m.max(r.abs()))
            })
            .collect()
    }
}
