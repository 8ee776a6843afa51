//! Reads a results table (see [`super::results`]) from untrusted bytes: every fault is
//! refused with its line:column, nothing panics. Used for `--reference` tables, which may
//! come from other tools.

use super::results::{ResultsTable, field_count, header};
use hirad_core::limits::MAX_BANDS;
use std::fmt;
use std::path::Path;

/// A fault in a results table, located by 1-based line and byte column.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TableError {
    /// Line (1-based; the header is line 1).
    pub line: u64,
    /// Byte column in the line (1-based).
    pub column: u64,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for TableError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}: {}", self.line, self.column, self.message)
    }
}

impl std::error::Error for TableError {}

fn fail<T>(line: u64, column: usize, message: impl Into<String>) -> Result<T, TableError> {
    Err(TableError {
        line,
        column: column as u64 + 1,
        message: message.into(),
    })
}

/// A field of a line: its text and its byte offset in the line.
struct Field<'a> {
    text: &'a [u8],
    at: usize,
}

fn fields(line: &[u8]) -> Vec<Field<'_>> {
    let mut out = Vec::new();
    let mut at = 0;
    for text in line.split(|&c| c == b',') {
        out.push(Field { text, at });
        at += text.len() + 1;
    }
    out
}

/// At most 40 characters of a field, for messages.
fn shown(text: &[u8]) -> String {
    let s = String::from_utf8_lossy(text);
    let mut out: String = s.chars().take(40).collect();
    if s.chars().count() > 40 {
        out.push_str("...");
    }
    out
}

/// Reads a table file; errors name the file and the line:column of the fault.
pub fn read_results_file(path: &Path) -> anyhow::Result<ResultsTable> {
    let bytes =
        std::fs::read(path).map_err(|e| anyhow::anyhow!("{}: cannot read: {e}", path.display()))?;
    read_results(&bytes).map_err(|e| anyhow::anyhow!("{}:{e}", path.display()))
}

/// Parses a whole table. Accepts `\n` or `\r\n` line ends, an optional final newline and a
/// leading UTF-8 byte-order mark; refuses empty lines, wrong headers or field counts, numbers
/// that are not finite f32, negative areas, and ids that are not strictly increasing.
pub fn read_results(bytes: &[u8]) -> Result<ResultsTable, TableError> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let bytes = bytes.strip_suffix(b"\n").unwrap_or(bytes);
    if bytes.is_empty() {
        return fail(
            1,
            0,
            format!("empty file: expected the header `{}`", header(1, false)),
        );
    }
    let mut lines = bytes.split(|&c| c == b'\n').enumerate();
    let (mut table, with_faces) = match lines.next() {
        Some((_, h)) => read_header(strip_cr(h))?,
        None => return fail(1, 0, "empty file"),
    };
    let values = field_count(table.bands, table.two_sided);
    let expected = values + with_faces as usize;
    for (index, raw) in lines {
        let line_no = index as u64 + 1;
        let line = strip_cr(raw);
        if line.is_empty() {
            return fail(line_no, 0, "empty line: expected a row");
        }
        let f = fields(line);
        if f.len() != expected {
            let column = f.get(expected).map_or(line.len(), |x| x.at);
            return fail(
                line_no,
                column,
                format!("expected {expected} fields, found {}", f.len()),
            );
        }
        let id = parse_id(line_no, &f[0])?;
        if let Some(&last) = table.ids.last() {
            if id == last {
                return fail(line_no, 0, format!("duplicate id {id}"));
            }
            if id < last {
                return fail(
                    line_no,
                    0,
                    format!("id {id} after id {last}: ids must be in increasing order"),
                );
            }
        }
        let area = parse_value(line_no, &f[1])?;
        if area < 0.0 {
            return fail(line_no, f[1].at, format!("negative area {area}"));
        }
        table.ids.push(id);
        table.areas.push(area);
        let bands = table.bands;
        let [rad_front, rad_back] = &mut table.radiosity;
        let [irr_front, irr_back] = &mut table.irradiance;
        let groups = [rad_front, irr_front, rad_back, irr_back];
        for (g, column) in groups.into_iter().zip(f[2..values].chunks(bands)) {
            for field in column {
                g.push(parse_value(line_no, field)?);
            }
        }
        if with_faces {
            // Checked like an id, not kept: a reference is matched by id.
            parse_id(line_no, &f[values])?;
        }
    }
    Ok(table)
}

fn strip_cr(line: &[u8]) -> &[u8] {
    line.strip_suffix(b"\r").unwrap_or(line)
}

/// Reads the header: `id,area`, then `2 n` (one-sided) or `4 n` (two-sided) named columns,
/// and an optional last column `face`; returns the empty table and whether `face` is there.
fn read_header(line: &[u8]) -> Result<(ResultsTable, bool), TableError> {
    let all = fields(line);
    let with_faces = all.len() > 2 && all.last().is_some_and(|x| x.text == b"face");
    let f = &all[..all.len() - with_faces as usize];
    let two_sided = f.iter().any(|x| x.text == b"rad_back_0");
    let per_band = if two_sided { 4 } else { 2 };
    let bands = f.len().saturating_sub(2) / per_band;
    if !(1..=MAX_BANDS).contains(&bands) || f.len() != field_count(bands, two_sided) {
        let column = f.get(2 + per_band * MAX_BANDS).map_or(line.len(), |x| x.at);
        return fail(
            1,
            column,
            format!(
                "header has {} columns: expected `id,area`, then rad_K and irr_K for each \
                 of 1 to {MAX_BANDS} bands K (and rad_back_K, irr_back_K for two-sided scenes), \
                 and an optional last column `face`",
                f.len()
            ),
        );
    }
    let want = header(bands, two_sided);
    for (field, name) in f.iter().zip(want.split(',')) {
        if field.text != name.as_bytes() {
            return fail(
                1,
                field.at,
                format!(
                    "header: expected column `{name}`, found `{}`",
                    shown(field.text)
                ),
            );
        }
    }
    Ok((ResultsTable::new(bands, two_sided), with_faces))
}

fn parse_id(line: u64, f: &Field<'_>) -> Result<u64, TableError> {
    let ok = !f.text.is_empty() && f.text.iter().all(u8::is_ascii_digit);
    let value = ok
        .then(|| std::str::from_utf8(f.text).ok()?.parse::<u64>().ok())
        .flatten();
    match value {
        Some(v) => Ok(v),
        None => fail(
            line,
            f.at,
            format!(
                "`{}` is not a polygon id (an integer from 0 to {})",
                shown(f.text),
                u64::MAX
            ),
        ),
    }
}

/// A finite f32 in decimal notation (digits, sign, point, exponent; no `inf` or `NaN`).
fn parse_value(line: u64, f: &Field<'_>) -> Result<f32, TableError> {
    let decimal = !f.text.is_empty()
        && f.text
            .iter()
            .all(|c| c.is_ascii_digit() || b"+-.eE".contains(c));
    let parsed = decimal
        .then(|| std::str::from_utf8(f.text).ok()?.parse::<f32>().ok())
        .flatten();
    match parsed {
        Some(v) if v.is_finite() => Ok(v),
        Some(_) => fail(
            line,
            f.at,
            format!("`{}` is out of the range of f32", shown(f.text)),
        ),
        None => fail(
            line,
            f.at,
            format!("`{}` is not a finite decimal number", shown(f.text)),
        ),
    }
}
