//! The per-polygon results table: one CSV row per input polygon in global-id order, streamed
//! by a [`Sink`] as the solver finishes polygons, and the same table held in memory.
//!
//! Columns (see [`super::columns`]): `id,area_m2`, the radiosity and irradiance of the front
//! side per band (`rad_par_W_m2`, ..., `irr_par_W_m2`, ...), then `rad_back_...` and
//! `irr_back_...` only when some polygon of the scene is two-sided (a one-sided polygon leaves
//! them empty: it has no back), then `face` only when the scene came from an OBJ file (the
//! number of the `f` statement the polygon came from, 1-based, as modelling programs number
//! faces; the pieces of a split face share it, a skipped face has no row), then `material`
//! and `group` (the cluster path) when the writer is given them ([`RowLabels`]). Units are in
//! the names: m^2 for the area, W/m^2 for radiosity and irradiance.
//! Numbers are written with Rust's shortest round-trip form, so reading gives the same bits.

use super::columns::{band_labels, numeric_header, push_field};
use super::row_labels::RowLabels;
use crate::files::{persist, temp_beside};
use anyhow::anyhow;
use hirad_core::limits::MAX_BANDS;
use hirad_core::sink::{PolygonResult, Sink};
use std::fmt::Write as _;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

/// The header line (without its newline) of a table with `bands` bands labelled by index.
pub fn header(bands: usize, two_sided: bool) -> String {
    numeric_header(&band_labels(bands, &[]), two_sided).join(",")
}

/// Number of numeric fields of a row (id, area, radiosity and irradiance).
pub fn field_count(bands: usize, two_sided: bool) -> usize {
    2 + bands * if two_sided { 4 } else { 2 }
}

/// What a table's columns are: its band labels and sides, and the optional columns.
#[derive(Clone, Debug, PartialEq)]
pub struct TableLayout {
    /// One label per band (see [`band_labels`]).
    pub labels: Vec<String>,
    /// Back-side columns (some polygon is two-sided).
    pub two_sided: bool,
    /// The `face` column, by id (the scene's OBJ face numbers).
    pub faces: Option<Vec<u64>>,
    /// The `material` and `group` columns.
    pub rows: Option<RowLabels>,
}

impl TableLayout {
    /// Bands labelled by index, no optional columns.
    pub fn plain(bands: usize, two_sided: bool) -> Self {
        TableLayout {
            labels: band_labels(bands, &[]),
            two_sided,
            faces: None,
            rows: None,
        }
    }

    /// The header line (without its newline).
    pub fn header(&self) -> String {
        let mut h = numeric_header(&self.labels, self.two_sided);
        if self.faces.is_some() {
            h.push("face".into());
        }
        if self.rows.is_some() {
            h.push("material".into());
            h.push("group".into());
        }
        h.join(",")
    }
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
    layout: TableLayout,
    last: Option<u64>,
    line: String,
}

impl<W: Write> ResultsWriter<W> {
    /// Writes the header for `bands` bands (1..=[`MAX_BANDS`]) labelled by index, with
    /// back-side columns when `two_sided`.
    pub fn new(out: W, bands: usize, two_sided: bool) -> io::Result<Self> {
        Self::with_layout(out, TableLayout::plain(bands, two_sided))
    }

    /// Writes the header of `layout` (1..=[`MAX_BANDS`] bands).
    pub fn with_layout(mut out: W, layout: TableLayout) -> io::Result<Self> {
        let bands = layout.labels.len();
        if !(1..=MAX_BANDS).contains(&bands) {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("a results table has 1 to {MAX_BANDS} bands, not {bands}"),
            ));
        }
        out.write_all(layout.header().as_bytes())?;
        out.write_all(b"\n")?;
        Ok(ResultsWriter {
            out,
            layout,
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
        let bands = self.layout.labels.len();
        let two_sided = self.layout.two_sided;
        check_polygon(p, bands, two_sided, self.last)
            .map_err(|e| io::Error::new(io::ErrorKind::InvalidData, e))?;
        self.last = Some(p.id);
        let invalid = |what: &str| {
            io::Error::new(
                io::ErrorKind::InvalidData,
                format!("polygon {} has no {what}", p.id),
            )
        };
        let line = &mut self.line;
        line.clear();
        let _ = write!(line, "{},{}", p.id, p.area);
        let sides = if two_sided { 2 } else { 1 };
        for side in 0..sides {
            for values in [p.radiosity[side], p.irradiance[side]] {
                if values.is_empty() {
                    // Front values are checked present: this is the back of a one-sided
                    // polygon, which has none.
                    for _ in 0..bands {
                        line.push(',');
                    }
                } else {
                    for v in values {
                        let _ = write!(line, ",{v}");
                    }
                }
            }
        }
        if let Some(faces) = &self.layout.faces {
            let f = faces
                .get(p.id as usize)
                .ok_or_else(|| invalid("face number"))?;
            let _ = write!(line, ",{f}");
        }
        if let Some(rows) = &mut self.layout.rows {
            let (m, g) = rows
                .label(p.id)
                .ok_or_else(|| invalid("material or group"))?;
            line.push(',');
            push_field(line, m);
            line.push(',');
            push_field(line, g);
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
    /// Creates the temporary file beside `path` and writes the header (bands labelled by
    /// index, no optional columns).
    pub fn create(path: &Path, bands: usize, two_sided: bool) -> anyhow::Result<Self> {
        Self::create_with_layout(path, TableLayout::plain(bands, two_sided))
    }

    /// [`ResultsFile::create`] with the columns of `layout`.
    pub fn create_with_layout(path: &Path, layout: TableLayout) -> anyhow::Result<Self> {
        let tmp = temp_beside(path)?;
        let writer = ResultsWriter::with_layout(BufWriter::new(tmp), layout)
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
