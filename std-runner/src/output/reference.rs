//! Error against a reference solution, the paper's measure (Soler & Sillion 2000, Figure 4):
//! the L2 difference of per-polygon radiosity, area-weighted, in percent of the reference's
//! largest radiosity:
//!
//! `100 * sqrt( sum_i sum_c A_i (B_ic - R_ic)^2 / (n_c * sum_i A_i) ) / max_ic R_ic`
//!
//! over the columns `c`: every band of the front radiosity, and of the back radiosity when
//! both tables have back columns (then one-sided polygons count with their back at 0 on both
//! sides). The areas `A_i` are the reference's. Sums run in f64 in id order, so the result
//! is deterministic.
//!
//! Beside the global measure, the comparison names the [`WORST_COUNT`] polygons with the
//! largest relative error: a polygon's relative error is the largest `|B_ic - R_ic| / R_ic`
//! over the compared columns whose reference value is at least [`RELATIVE_FLOOR`] times the
//! reference's largest radiosity (darker columns, where the ratio says nothing, are left out).
//! Ties go to the lower id, then to the first column (front before back, bands in order).

use super::results::ResultsTable;
use crate::numbers::short;
use hirad_core::sink::{PolygonResult, Sink};
use serde::{Deserialize, Serialize};
use std::fmt::{self, Write as _};

/// Largest relative difference between a polygon's area in the results and in the reference
/// before the two are declared different scenes.
pub const AREA_TOLERANCE: f64 = 1e-3;

/// Relative errors are taken only where the reference is at least this fraction of its
/// largest radiosity (0.1%): black or unlit polygons would otherwise dominate with 0/0.
pub const RELATIVE_FLOOR: f64 = 1e-3;

/// Number of polygons [`Comparison::worst`] lists.
pub const WORST_COUNT: usize = 5;

/// A polygon with one of the largest relative errors, at its worst column.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WorstPolygon {
    /// Global id.
    pub id: u64,
    /// Band index of the worst column.
    pub band: usize,
    /// True when the worst column is the back side's.
    pub back: bool,
    /// The reference's radiosity there (W/m^2), as in its table.
    pub reference: f32,
    /// The result's radiosity there (W/m^2).
    pub result: f32,
    /// `100 * (result - reference) / reference`.
    pub relative_error_percent: f64,
}

/// How far a solution is from the reference.
#[derive(Clone, Debug, PartialEq)]
pub struct Comparison {
    /// The paper's error (percent of the reference's largest radiosity).
    pub error_percent: f64,
    /// The same measure for each band alone (front and back together), with the same
    /// normaliser; `error_percent^2` is the mean of their squares.
    pub per_band_percent: Vec<f64>,
    /// Largest absolute radiosity difference over every polygon and compared column (W/m^2).
    pub max_abs_difference: f64,
    /// The reference's largest radiosity over the compared columns (W/m^2).
    pub reference_max: f64,
    /// Polygons compared.
    pub polygons: u64,
    /// True when back-side radiosity was compared too.
    pub back_compared: bool,
    /// The [`WORST_COUNT`] polygons with the largest relative error (fewer when fewer have a
    /// column above the floor), largest first, ties by id.
    pub worst: Vec<WorstPolygon>,
    /// Reference values below this (W/m^2), [`RELATIVE_FLOOR`] times
    /// [`Comparison::reference_max`], have no relative error.
    pub relative_floor: f64,
}

impl Comparison {
    /// The worst polygons for people: a heading naming the floor, then one line per polygon,
    /// e.g. `  id 17 back band 1 (nir): reference 0.02618 W/m^2, got 0.02795, +6.76 %`.
    /// `band_names` are the scene's (may be empty).
    pub fn worst_lines(&self, band_names: &[String]) -> String {
        let mut out = format!(
            "worst polygons (relative error of radiosity, where the reference is at least {}% of \
             its largest, {} W/m^2):\n",
            short(100.0 * RELATIVE_FLOOR),
            short(self.relative_floor)
        );
        if self.worst.is_empty() {
            out.push_str("  none\n");
        }
        for w in &self.worst {
            let side = if w.back { "back" } else { "front" };
            let name = match band_names.get(w.band) {
                Some(n) => format!(" ({n})"),
                None => String::new(),
            };
            let _ = writeln!(
                out,
                "  id {} {side} band {}{name}: reference {} W/m^2, got {}, {:+.2} %",
                w.id,
                w.band,
                short(f64::from(w.reference)),
                short(f64::from(w.result)),
                w.relative_error_percent
            );
        }
        out
    }
}

/// Why two tables cannot be compared.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CompareError(pub String);

impl fmt::Display for CompareError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for CompareError {}

fn refuse<T>(message: String) -> Result<T, CompareError> {
    Err(CompareError(message))
}

/// Running sums of the measure, fed one polygon at a time in id order.
#[derive(Clone, Debug)]
struct Accumulator {
    sides: usize,
    area: f64,
    squares: Vec<f64>,
    max_abs: f64,
    max_ref: f64,
    polygons: u64,
    /// Reference values below this have no relative error (W/m^2).
    floor: f64,
    /// The worst polygons so far, in report order.
    worst: Vec<WorstPolygon>,
}

/// The reference's largest radiosity over the compared columns (front, and back when
/// `back`); the relative-error floor is [`RELATIVE_FLOOR`] times it.
fn reference_max(reference: &ResultsTable, back: bool) -> f64 {
    let sides = if back { 2 } else { 1 };
    reference.radiosity[..sides]
        .iter()
        .flatten()
        .map(|&v| f64::from(v))
        .fold(f64::NEG_INFINITY, f64::max)
}

/// Report order: larger relative error first, then lower id.
fn worse(a: &WorstPolygon, b: &WorstPolygon) -> std::cmp::Ordering {
    b.relative_error_percent
        .abs()
        .total_cmp(&a.relative_error_percent.abs())
        .then(a.id.cmp(&b.id))
}

impl Accumulator {
    /// Sums for `bands` bands, with back sides when `back`; `reference_max` is the
    /// reference's largest radiosity over the compared columns (for the relative floor).
    fn new(bands: usize, back: bool, reference_max: f64) -> Self {
        Accumulator {
            sides: if back { 2 } else { 1 },
            area: 0.0,
            squares: vec![0.0; bands],
            max_abs: 0.0,
            max_ref: f64::NEG_INFINITY,
            polygons: 0,
            floor: RELATIVE_FLOOR * reference_max,
            worst: Vec::with_capacity(WORST_COUNT + 1),
        }
    }

    /// Adds polygon `id`: reference area, result and reference radiosity per side (an empty
    /// slice stands for zeros).
    fn add(&mut self, id: u64, area: f32, result: [&[f32]; 2], reference: [&[f32]; 2]) {
        let area = f64::from(area);
        self.area += area;
        self.polygons += 1;
        let mut worst: Option<WorstPolygon> = None;
        for side in 0..self.sides {
            for (b, sum) in self.squares.iter_mut().enumerate() {
                let got = f64::from(result[side].get(b).copied().unwrap_or(0.0));
                let want = f64::from(reference[side].get(b).copied().unwrap_or(0.0));
                let d = got - want;
                *sum += area * d * d;
                self.max_abs = self.max_abs.max(d.abs());
                self.max_ref = self.max_ref.max(want);
                if want > 0.0 && want >= self.floor {
                    let percent = 100.0 * d / want;
                    if worst
                        .as_ref()
                        .is_none_or(|w| percent.abs() > w.relative_error_percent.abs())
                    {
                        worst = Some(WorstPolygon {
                            id,
                            band: b,
                            back: side == 1,
                            // Both came from f32: exact.
                            reference: want as f32,
                            result: got as f32,
                            relative_error_percent: percent,
                        });
                    }
                }
            }
        }
        if let Some(w) = worst.filter(|w| w.relative_error_percent.is_finite()) {
            let at = self.worst.partition_point(|k| worse(k, &w).is_lt());
            if at < WORST_COUNT {
                self.worst.insert(at, w);
                self.worst.truncate(WORST_COUNT);
            }
        }
    }

    fn finish(self) -> Result<Comparison, CompareError> {
        if self.polygons == 0 {
            return refuse("the reference has no polygons".into());
        }
        if self.area.is_nan() || self.area <= 0.0 {
            return refuse("the reference's polygons have no area".into());
        }
        if self.max_ref.is_nan() || self.max_ref <= 0.0 {
            return refuse(format!(
                "the reference's largest radiosity is {} W/m^2: an error in percent of it \
                 is undefined",
                self.max_ref
            ));
        }
        let bands = self.squares.len() as f64;
        let sides = self.sides as f64;
        let percent =
            |sum: f64, columns: f64| 100.0 * (sum / (columns * self.area)).sqrt() / self.max_ref;
        let total: f64 = self.squares.iter().sum();
        Ok(Comparison {
            error_percent: percent(total, bands * sides),
            per_band_percent: self.squares.iter().map(|&s| percent(s, sides)).collect(),
            max_abs_difference: self.max_abs,
            reference_max: self.max_ref,
            polygons: self.polygons,
            back_compared: self.sides == 2,
            worst: self.worst,
            relative_floor: self.floor,
        })
    }
}

fn check_bands(bands: usize, reference: &ResultsTable) -> Result<(), CompareError> {
    if bands != reference.bands {
        return refuse(format!(
            "the results have {bands} band{} but the reference has {}",
            plural(bands),
            reference.bands
        ));
    }
    Ok(())
}

fn plural(n: usize) -> &'static str {
    if n == 1 { "" } else { "s" }
}

/// Refuses a row whose id or area does not match the reference's row.
fn check_row(row: usize, id: u64, area: f32, reference: &ResultsTable) -> Result<(), CompareError> {
    let want = reference.ids[row];
    if id != want {
        return refuse(format!(
            "row {}: polygon {id} in the results but polygon {want} in the reference",
            row + 1
        ));
    }
    let (a, r) = (f64::from(area), f64::from(reference.areas[row]));
    if (a - r).abs() > AREA_TOLERANCE * a.max(r) {
        return refuse(format!(
            "polygon {id}: area {area} m^2 in the results but {} m^2 in the reference: not \
             the same scene",
            reference.areas[row]
        ));
    }
    Ok(())
}

/// Compares two tables of the same scene. Refuses different band counts, polygon counts,
/// ids, or areas (beyond [`AREA_TOLERANCE`]), and a reference whose radiosity is nowhere
/// positive.
pub fn compare(
    result: &ResultsTable,
    reference: &ResultsTable,
) -> Result<Comparison, CompareError> {
    check_bands(result.bands, reference)?;
    if result.len() != reference.len() {
        return refuse(format!(
            "the results have {} polygons but the reference has {}",
            result.len(),
            reference.len()
        ));
    }
    let back = result.two_sided && reference.two_sided;
    let mut acc = Accumulator::new(reference.bands, back, reference_max(reference, back));
    for row in 0..reference.len() {
        check_row(row, result.ids[row], result.areas[row], reference)?;
        acc.add(
            reference.ids[row],
            reference.areas[row],
            [result.radiosity(row, 0), result.radiosity(row, 1)],
            [reference.radiosity(row, 0), reference.radiosity(row, 1)],
        );
    }
    acc.finish()
}

/// Compares polygons against a reference as the solver hands them over, so that the
/// solution never has to be held: a [`Sink`] whose [`ReferenceSink::finish`] gives the
/// same [`Comparison`] as [`compare`] on the whole table.
///
/// A mismatch never stops the solve (its other outputs are still worth having): the sink
/// keeps the first one and [`ReferenceSink::finish`] reports it.
#[derive(Clone, Debug)]
pub struct ReferenceSink {
    reference: ResultsTable,
    seen: u64,
    acc: Accumulator,
    failed: Option<CompareError>,
}

impl ReferenceSink {
    /// A comparison against `reference` for results with `bands` bands, with back-side
    /// values when `two_sided` (the scene has two-sided materials).
    pub fn new(
        reference: ResultsTable,
        bands: usize,
        two_sided: bool,
    ) -> Result<Self, CompareError> {
        check_bands(bands, &reference)?;
        let back = two_sided && reference.two_sided;
        let acc = Accumulator::new(bands, back, reference_max(&reference, back));
        Ok(ReferenceSink {
            reference,
            seen: 0,
            acc,
            failed: None,
        })
    }

    /// Polygons in the reference (check it against the scene's before a long solve).
    pub fn reference_polygons(&self) -> u64 {
        self.reference.len() as u64
    }

    /// The comparison, or the first mismatch; refuses a solution with a different number
    /// of polygons than the reference.
    pub fn finish(self) -> Result<Comparison, CompareError> {
        if self.seen != self.reference.len() as u64 {
            return refuse(format!(
                "the results have {} polygons but the reference has {}",
                self.seen,
                self.reference.len()
            ));
        }
        if let Some(e) = self.failed {
            return Err(e);
        }
        self.acc.finish()
    }

    /// Checks one polygon against the next reference row and adds it to the sums.
    fn take(&mut self, p: &PolygonResult<'_>) -> Result<(), CompareError> {
        let row = self.seen as usize;
        if row >= self.reference.len() {
            // Counted by `finish`.
            return Ok(());
        }
        check_row(row, p.id, p.area, &self.reference)?;
        for side in 0..self.acc.sides {
            let n = p.radiosity[side].len();
            let missing_back = side == 1 && n == 0;
            if n != self.reference.bands && !missing_back {
                return refuse(format!(
                    "polygon {}: {n} radiosity values for {} bands",
                    p.id, self.reference.bands
                ));
            }
            if p.radiosity[side].iter().any(|v| !v.is_finite()) {
                return refuse(format!("polygon {}: radiosity is not finite", p.id));
            }
        }
        let r = &self.reference;
        self.acc.add(
            p.id,
            r.areas[row],
            p.radiosity,
            [r.radiosity(row, 0), r.radiosity(row, 1)],
        );
        Ok(())
    }
}

impl Sink for ReferenceSink {
    type Error = core::convert::Infallible;

    fn polygon(&mut self, p: &PolygonResult<'_>) -> Result<(), Self::Error> {
        if self.failed.is_none()
            && let Err(e) = self.take(p)
        {
            self.failed = Some(e);
        }
        self.seen += 1;
        Ok(())
    }
}
