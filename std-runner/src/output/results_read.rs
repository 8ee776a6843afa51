//! Reads a results table (see [`super::results`]) from untrusted bytes: every fault is
//! refused with its line:column, nothing panics. Used for `--reference` tables, which may
//! come from other tools. Columns are found by name (see [`super::columns`]), so tables of
//! every layout hirad has written read alike: band labels by name or index, units in the
//! names or not (`area`, `rad_0`), with or without `face`, `material` and `group`, and
//! empty back-side fields for one-sided polygons (read as 0).

use super::columns::{Column, Field, parse_column, split_fields};
use super::results::{ResultsTable, header};
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

fn fields(line_no: u64, line: &[u8]) -> Result<Vec<Field<'_>>, TableError> {
    split_fields(line).or_else(|at| {
        fail(
            line_no,
            at,
            "a quoted field must end with a quote before the next comma",
        )
    })
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

/// Reads a table file; errors name the file and the line:column of the fault, and are
/// input errors (exit status 3).
pub fn read_results_file(path: &Path) -> anyhow::Result<ResultsTable> {
    let bytes = std::fs::read(path)
        .map_err(|e| crate::exit::input(anyhow::anyhow!("{}: cannot read: {e}", path.display())))?;
    read_results(&bytes).map_err(|e| crate::exit::input(anyhow::anyhow!("{}:{e}", path.display())))
}

/// Parses a whole table. Accepts `\n` or `\r\n` line ends, an optional final newline and a
/// leading UTF-8 byte-order mark; refuses empty lines, unknown or missing columns, wrong
/// field counts, numbers that are not finite f32, negative areas, and ids that are not
/// strictly increasing.
pub fn read_results(bytes: &[u8]) -> Result<ResultsTable, TableError> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let bytes = bytes.strip_suffix(b"\n").unwrap_or(bytes);
    if bytes.is_empty() {
        return fail(
            1,
            0,
            format!(
                "empty file: expected a header such as `{}`",
                header(1, false)
            ),
        );
    }
    let mut lines = bytes.split(|&c| c == b'\n').enumerate();
    let (mut table, layout) = match lines.next() {
        Some((_, h)) => read_header(strip_cr(h))?,
        None => return fail(1, 0, "empty file"),
    };
    let expected = layout.roles.len();
    for (index, raw) in lines {
        let line_no = index as u64 + 1;
        let line = strip_cr(raw);
        if line.is_empty() {
            return fail(line_no, 0, "empty line: expected a row");
        }
        let f = fields(line_no, line)?;
        if f.len() != expected {
            let column = f.get(expected).map_or(line.len(), |x| x.at);
            return fail(
                line_no,
                column,
                format!("expected {expected} fields, found {}", f.len()),
            );
        }
        let mut values = [[[0.0f32; MAX_BANDS]; 2]; 2];
        let (mut id, mut area) = (0u64, 0.0f32);
        for (field, role) in f.iter().zip(&layout.roles) {
            match *role {
                Role::Id => id = parse_id(line_no, field)?,
                Role::Area => {
                    area = parse_value(line_no, field)?;
                    if area < 0.0 {
                        return fail(line_no, field.at, format!("negative area {area}"));
                    }
                }
                Role::Flux {
                    quantity,
                    side,
                    band,
                } => {
                    if side == 1 && field.text.is_empty() {
                        // The back of a one-sided polygon: none.
                        continue;
                    }
                    values[quantity][side][band] = parse_value(line_no, field)?;
                }
                // Checked like an id, not kept: a reference is matched by id.
                Role::Face => {
                    parse_id(line_no, field)?;
                }
                Role::Text => {}
            }
        }
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
        table.ids.push(id);
        table.areas.push(area);
        let bands = table.bands;
        let sides = if table.two_sided { 2 } else { 1 };
        let [rad, irr] = &values;
        for (side, (r, i)) in rad.iter().zip(irr).enumerate().take(sides) {
            table.radiosity[side].extend_from_slice(&r[..bands]);
            table.irradiance[side].extend_from_slice(&i[..bands]);
        }
    }
    Ok(table)
}

fn strip_cr(line: &[u8]) -> &[u8] {
    line.strip_suffix(b"\r").unwrap_or(line)
}

/// What a column of a table read holds.
#[derive(Clone, Copy, Debug)]
enum Role {
    Id,
    Area,
    Flux {
        quantity: usize,
        side: usize,
        band: usize,
    },
    Face,
    /// `material`, `group`: read past.
    Text,
}

/// The roles of a table's columns, in order.
struct Layout {
    roles: Vec<Role>,
}

/// Reads the header: `id`, `area` (or `area_m2`), for each of 1 to [`MAX_BANDS`] bands its
/// `rad_B` and `irr_B` (with or without `_W_m2`), the same with `_back_` for two-sided
/// tables, and optionally `face`, `material` and `group`, each once. The bands' order is
/// that of the front radiosity columns; every set must name the same bands.
fn read_header(line: &[u8]) -> Result<(ResultsTable, Layout), TableError> {
    let all = fields(1, line)?;
    let usage = format!(
        "expected `id`, `area_m2`, then `rad_B_W_m2` and `irr_B_W_m2` for each band B \
         (and `rad_back_B_W_m2`, `irr_back_B_W_m2` for two-sided scenes), and optionally \
         `face`, `material`, `group`, e.g. `{}`",
        header(1, false)
    );
    let mut labels: Vec<String> = Vec::new();
    let mut columns = Vec::with_capacity(all.len());
    let mut seen: Vec<Column> = Vec::new();
    for f in &all {
        let name = std::str::from_utf8(&f.text).unwrap_or("");
        let Some(c) = parse_column(name) else {
            return fail(
                1,
                f.at,
                format!("header: unknown column `{}`: {usage}", shown(&f.text)),
            );
        };
        if seen.contains(&c) {
            return fail(
                1,
                f.at,
                format!("header: column `{}` appears twice", shown(&f.text)),
            );
        }
        if let Column::Flux {
            quantity: 0,
            side: 0,
            label,
        } = &c
        {
            labels.push(label.clone());
        }
        seen.push(c.clone());
        columns.push((c, f.at));
    }
    let bands = labels.len();
    if !(1..=MAX_BANDS).contains(&bands) {
        return fail(
            1,
            line.len(),
            format!(
                "header has radiosity columns for {bands} bands, expected 1 to {MAX_BANDS}: {usage}"
            ),
        );
    }
    let two_sided = seen
        .iter()
        .any(|c| matches!(c, Column::Flux { side: 1, .. }));
    for required in [Column::Id, Column::Area] {
        if !seen.contains(&required) {
            let name = if required == Column::Id {
                "id"
            } else {
                "area_m2"
            };
            return fail(1, 0, format!("header: no `{name}` column: {usage}"));
        }
    }
    let mut roles = Vec::with_capacity(columns.len());
    for (c, at) in &columns {
        roles.push(match c {
            Column::Id => Role::Id,
            Column::Area => Role::Area,
            Column::Face => Role::Face,
            Column::Material | Column::Group => Role::Text,
            Column::Flux {
                quantity,
                side,
                label,
            } => match labels.iter().position(|l| l == label) {
                Some(band) => Role::Flux {
                    quantity: *quantity,
                    side: *side,
                    band,
                },
                None => {
                    return fail(
                        1,
                        *at,
                        format!(
                            "header: band `{label}` has no front radiosity column (the bands are {})",
                            labels.join(", ")
                        ),
                    );
                }
            },
        });
    }
    // Every band of every set present.
    let sides = if two_sided { 2 } else { 1 };
    for side in 0..sides {
        for quantity in 0..2 {
            for (band, label) in labels.iter().enumerate() {
                let found = roles.iter().any(|r| {
                    matches!(*r, Role::Flux { quantity: q, side: s, band: b } if q == quantity && s == side && b == band)
                });
                if !found {
                    let q = ["rad", "irr"][quantity];
                    let sd = ["", "_back"][side];
                    return fail(
                        1,
                        line.len(),
                        format!("header: no column `{q}{sd}_{label}_W_m2`: {usage}"),
                    );
                }
            }
        }
    }
    Ok((ResultsTable::new(bands, two_sided), Layout { roles }))
}

fn parse_id(line: u64, f: &Field<'_>) -> Result<u64, TableError> {
    let ok = !f.text.is_empty() && f.text.iter().all(u8::is_ascii_digit);
    let value = ok
        .then(|| std::str::from_utf8(&f.text).ok()?.parse::<u64>().ok())
        .flatten();
    match value {
        Some(v) => Ok(v),
        None => fail(
            line,
            f.at,
            format!(
                "`{}` is not a polygon id (an integer from 0 to {})",
                shown(&f.text),
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
        .then(|| std::str::from_utf8(&f.text).ok()?.parse::<f32>().ok())
        .flatten();
    match parsed {
        Some(v) if v.is_finite() => Ok(v),
        Some(_) => fail(
            line,
            f.at,
            format!("`{}` is out of the range of f32", shown(&f.text)),
        ),
        None => fail(
            line,
            f.at,
            format!("`{}` is not a finite decimal number", shown(&f.text)),
        ),
    }
}
