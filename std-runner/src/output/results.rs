//! The per-polygon results table: one CSV row per input polygon in global-id order, streamed
//! by a [`Sink`] as the solver finishes polygons, and the same table held in memory.
//!
//! Columns: `id,area,rad_0..rad_{n-1},irr_0..irr_{n-1}` for the front side, then
//! `rad_back_0..`, `irr_back_0..` only when the scene has two-sided materials (one-sided
//! polygons get 0 there), then `face` only when the scene came from an OBJ file: the number
//! of the `f` statement the polygon came from (1-based, as modelling programs number faces;
//! the pieces of a split face share it, a skipped face has no row). Units: m^2 for the area,
//! W/m^2 for radiosity and irradiance.
//! Numbers are written with Rust's shortest round-trip form, so reading gives the same bits.

use crate::files::{persist, temp_beside};
use anyhow::anyhow;
use hirad_core::limits::MAX_BANDS;
use hirad_core::sink::{PolygonResult, Sink};
use std::fmt::Write as _;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

/// The header line (without its newline) of a table with `bands` bands.
pub fn header(bands: usize, two_sided: bool) -> String {
    let mut h = String::from("id,area");
    let sides: &[&str] = if two_sided { &["", "_back"] } else { &[""] };
    for side in sides {
        for quantity in ["rad", "irr"] {
            for b in 0..bands {
                let _ = write!(h, ",{quantity}{side}_{b}");
            }
        }
    }
    h
}

/// Number of fields of a row.
pub fn field_count(bands: usize, two_sided: bool) -> usize {
    2 + bands * if two_sided { 4 } else { 2 }
}

/// A whole results table in memory (rows in increasing id order).
#[derive(Clone, Debug, PartialEq)]
pub struct ResultsTable {
    /// Spectral bands, 1..=[`MAX_BANDS`].
    pub bands: usize,
    /// True when the table has back-side columns.
    pub two_sided: bool,
    /// Global polygon ids, strictly increasing.
    pub ids: Vec<u64>,
    /// Polygon areas (m^2).
    pub areas: Vec<f32>,
    /// Radiosity (W/m^2), `[front, back]`, row-major (`bands` values per row); back is
    /// empty when the table is one-sided.
    pub radiosity: [Vec<f32>; 2],
    /// Irradiance (W/m^2), laid out like `radiosity`.
    pub irradiance: [Vec<f32>; 2],
}

impl ResultsTable {
    /// An empty table.
    pub fn new(bands: usize, two_sided: bool) -> Self {
        ResultsTable {
            bands,
            two_sided,
            ids: Vec::new(),
            areas: Vec::new(),
            radiosity: [Vec::new(), Vec::new()],
            irradiance: [Vec::new(), Vec::new()],
        }
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    /// True when the table has no rows.
    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }

    /// Radiosity of row `row` on `side` (0 front, 1 back; empty for a one-sided table).
    pub fn radiosity(&self, row: usize, side: usize) -> &[f32] {
        row_slice(&self.radiosity[side], row, self.bands)
    }

    /// Irradiance of row `row` on `side` (0 front, 1 back; empty for a one-sided table).
    pub fn irradiance(&self, row: usize, side: usize) -> &[f32] {
        row_slice(&self.irradiance[side], row, self.bands)
    }

    /// Appends a polygon after checking it like [`ResultsWriter`] does.
    pub fn push(&mut self, p: &PolygonResult<'_>) -> Result<(), String> {
        check_polygon(p, self.bands, self.two_sided, self.ids.last().copied())?;
        self.ids.push(p.id);
        self.areas.push(p.area);
        for side in 0..self.sides() {
            for (dst, src) in [
                (&mut self.radiosity[side], p.radiosity[side]),
                (&mut self.irradiance[side], p.irradiance[side]),
            ] {
                if src.is_empty() {
                    dst.extend(std::iter::repeat_n(0.0, self.bands));
                } else {
                    dst.extend_from_slice(src);
                }
            }
        }
        Ok(())
    }

    /// Writes the table as CSV (header and rows).
    pub fn write_csv(&self, out: impl Write) -> io::Result<()> {
        let mut w = ResultsWriter::new(out, self.bands, self.two_sided)?;
        for row in 0..self.len() {
            w.polygon(&PolygonResult {
                id: self.ids[row],
                area: self.areas[row],
                two_sided: self.two_sided,
                radiosity: [self.radiosity(row, 0), self.radiosity(row, 1)],
                irradiance: [self.irradiance(row, 0), self.irradiance(row, 1)],
            })?;
        }
        w.finish().map(|_| ())
    }

    fn sides(&self) -> usize {
        if self.two_sided { 2 } else { 1 }
    }
}

fn row_slice(v: &[f32], row: usize, bands: usize) -> &[f32] {
    v.get(row * bands..(row + 1) * bands).unwrap_or(&[])
}

impl Sink for ResultsTable {
    type Error = anyhow::Error;

    fn polygon(&mut self, p: &PolygonResult<'_>) -> Result<(), Self::Error> {
        self.push(p).map_err(|e| anyhow!("results table: {e}"))
    }
}

/// Checks that a polygon fits a table: band counts, sides, finite values, increasing ids.
fn check_polygon(
    p: &PolygonResult<'_>,
    bands: usize,
    two_sided: bool,
    last: Option<u64>,
) -> Result<(), String> {
    let id = p.id;
    if let Some(last) = last
        && id <= last
    {
        return Err(format!(
            "polygon {id} arrived after polygon {last}: ids must increase"
        ));
    }
    if !(p.area.is_finite() && p.area >= 0.0) {
        return Err(format!("polygon {id}: area {} is not usable", p.area));
    }
    for (what, sides) in [("radiosity", p.radiosity), ("irradiance", p.irradiance)] {
        if sides[0].len() != bands {
            return Err(format!(
                "polygon {id}: {} front {what} values for {bands} bands",
                sides[0].len()
            ));
        }
        if !sides[1].is_empty() && (sides[1].len() != bands || !two_sided) {
            return Err(format!(
                "polygon {id}: {} back {what} values in a table with {} back bands",
                sides[1].len(),
                if two_sided { bands } else { 0 }
            ));
        }
        for (side, values) in sides.iter().enumerate() {
            if let Some(b) = values.iter().position(|v| !v.is_finite()) {
                let name = ["front", "back"][side];
                return Err(format!(
                    "polygon {id}: {name} {what} of band {b} is {}",
                    values[b]
                ));
            }
        }
    }
    Ok(())
}

/// Streams the table as CSV to any writer. Refuses polygons that would make an unreadable
/// table (wrong band counts, non-finite values, ids out of order) rather than write them.
#[derive(Debug)]
pub struct ResultsWriter<W: Write> {
    out: W,
    bands: usize,
    two_sided: bool,
    /// The `face` column, by id.
    faces: Option<Vec<u64>>,
    last: Option<u64>,
    line: String,
}

impl<W: Write> ResultsWriter<W> {
    /// Writes the header for `bands` bands (1..=[`MAX_BANDS`]), with back-side columns when
    /// `two_sided` (the scene has two-sided materials).
    pub fn new(out: W, bands: usize, two_sided: bool) -> io::Result<Self> {
        Self::with_faces(out, bands, two_sided, None)
    }

    /// [`ResultsWriter::new`] with the `face` column: `faces[id]` for the row of polygon
    /// `id` (the scene's OBJ face numbers).
    pub fn with_faces(
        mut out: W,
        bands: usize,
        two_sided: bool,
        faces: Option<Vec<u64>>,
    ) -> io::Result<Self> {
        if !(1..=MAX_BANDS).contains(&bands) {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("a results table has 1 to {MAX_BANDS} bands, not {bands}"),
            ));
        }
        out.write_all(header(bands, two_sided).as_bytes())?;
        if faces.is_some() {
            out.write_all(b",face")?;
        }
        out.write_all(b"\n")?;
        Ok(ResultsWriter {
            out,
            bands,
            two_sided,
            faces,
            last: None,
            line: String::new(),
        })
    }

    /// Flushes and hands back the writer.
    pub fn finish(mut self) -> io::Result<W> {
        self.out.flush()?;
        Ok(self.out)
    }
}

impl<W: Write> Sink for ResultsWriter<W> {
    type Error = io::Error;

    fn polygon(&mut self, p: &PolygonResult<'_>) -> Result<(), io::Error> {
        check_polygon(p, self.bands, self.two_sided, self.last)
            .map_err(|e| io::Error::new(io::ErrorKind::InvalidData, e))?;
        self.last = Some(p.id);
        let line = &mut self.line;
        line.clear();
        let _ = write!(line, "{},{}", p.id, p.area);
        let sides = if self.two_sided { 2 } else { 1 };
        for side in 0..sides {
            for values in [p.radiosity[side], p.irradiance[side]] {
                if values.is_empty() {
                    for _ in 0..self.bands {
                        line.push_str(",0");
                    }
                } else {
                    for v in values {
                        let _ = write!(line, ",{v}");
                    }
                }
            }
        }
        if let Some(faces) = &self.faces {
            match faces.get(p.id as usize) {
                Some(f) => {
                    let _ = write!(line, ",{f}");
                }
                None => {
                    return Err(io::Error::new(
                        io::ErrorKind::InvalidData,
                        format!("polygon {} has no face number", p.id),
                    ));
                }
            }
        }
        line.push('\n');
        self.out.write_all(line.as_bytes())
    }
}

/// A results table written to a file through a temporary name, renamed into place by
/// [`ResultsFile::finish`]; dropped unfinished, it leaves nothing behind.
pub struct ResultsFile {
    path: PathBuf,
    writer: ResultsWriter<BufWriter<tempfile::NamedTempFile>>,
}

impl ResultsFile {
    /// Creates the temporary file beside `path` and writes the header.
    pub fn create(path: &Path, bands: usize, two_sided: bool) -> anyhow::Result<Self> {
        Self::create_with_faces(path, bands, two_sided, None)
    }

    /// [`ResultsFile::create`] with the `face` column (see [`ResultsWriter::with_faces`]).
    pub fn create_with_faces(
        path: &Path,
        bands: usize,
        two_sided: bool,
        faces: Option<Vec<u64>>,
    ) -> anyhow::Result<Self> {
        let tmp = temp_beside(path)?;
        let writer = ResultsWriter::with_faces(BufWriter::new(tmp), bands, two_sided, faces)
            .map_err(|e| anyhow!("{}: cannot write: {e}", path.display()))?;
        Ok(ResultsFile {
            path: path.to_path_buf(),
            writer,
        })
    }

    /// Flushes the table and renames it to its final name.
    pub fn finish(self) -> anyhow::Result<()> {
        let path = self.path;
        let buffered = self
            .writer
            .finish()
            .map_err(|e| anyhow!("{}: cannot write: {e}", path.display()))?;
        let tmp = buffered
            .into_inner()
            .map_err(|e| anyhow!("{}: cannot write: {}", path.display(), e.error()))?;
        persist(tmp, &path)
    }
}

impl Sink for ResultsFile {
    type Error = anyhow::Error;

    fn polygon(&mut self, p: &PolygonResult<'_>) -> anyhow::Result<()> {
        self.writer
            .polygon(p)
            .map_err(|e| anyhow!("{}: {e}", self.path.display()))
    }
}
