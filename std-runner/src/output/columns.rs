//! The columns of a results table: what each is called, with its unit in its name, so that a
//! table read without the docs says what it holds.
//!
//! `id,area_m2`, then per side (front; back only when some polygon is two-sided)
//! `rad[_back]_<band>_W_m2` for every band and `irr[_back]_<band>_W_m2` for every band, then
//! `face` (OBJ scenes), `material` and `group` (when the writer knows them). `<band>` is the
//! scene's band name (`par`, `nir`, `red`, ...) when it names its bands with plain names,
//! else the band's index from 0 — the numbering of `--display-bands` and of every message.

/// Unit suffix of the radiosity and irradiance columns.
pub const FLUX_UNIT: &str = "W_m2";

/// Name of the area column.
pub const AREA: &str = "area_m2";

/// The label of each band in column names: the scene's names when there is one per band,
/// each non-empty, distinct and made of ASCII letters, digits, `_`, `-` and `.` (safe in a
/// CSV header and in a column name of any data-frame library); otherwise `0`, `1`, ...
pub fn band_labels(bands: usize, names: &[String]) -> Vec<String> {
    let plain = |n: &String| {
        !n.is_empty()
            && n.bytes()
                .all(|c| c.is_ascii_alphanumeric() || b"_-.".contains(&c))
    };
    let usable = names.len() == bands
        && names.iter().all(plain)
        && names
            .iter()
            .enumerate()
            .all(|(i, n)| !names[..i].contains(n));
    if usable {
        names.to_vec()
    } else {
        (0..bands).map(|b| b.to_string()).collect()
    }
}

/// How messages name band `b`: `band 1 (nir)`, or `band 1` when the scene names none.
pub fn band_name(b: usize, names: &[String]) -> String {
    match names.get(b).filter(|n| !n.is_empty()) {
        Some(n) => format!("band {b} ({n})"),
        None => format!("band {b}"),
    }
}

/// The numeric columns of a table: `id,area_m2` and the radiosity and irradiance of each
/// side, for bands labelled `labels`.
pub fn numeric_header(labels: &[String], two_sided: bool) -> Vec<String> {
    let mut h = vec!["id".to_string(), AREA.to_string()];
    let sides: &[&str] = if two_sided { &["", "_back"] } else { &[""] };
    for side in sides {
        for quantity in ["rad", "irr"] {
            for l in labels {
                h.push(format!("{quantity}{side}_{l}_{FLUX_UNIT}"));
            }
        }
    }
    h
}

/// A column of a results table as a reader recognises it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Column {
    /// `id`.
    Id,
    /// `area_m2` (or `area`, as tables before named their units).
    Area,
    /// Radiosity (`rad`) or irradiance (`irr`) of a side (0 front, 1 back) of the band
    /// labelled `label`.
    Flux {
        /// 0 radiosity, 1 irradiance.
        quantity: usize,
        /// 0 front, 1 back.
        side: usize,
        /// The band's label.
        label: String,
    },
    /// `face`.
    Face,
    /// `material`.
    Material,
    /// `group`.
    Group,
}

/// Recognises a column name; `None` when it is none of a results table's.
pub fn parse_column(name: &str) -> Option<Column> {
    match name {
        "id" => return Some(Column::Id),
        "area" | AREA => return Some(Column::Area),
        "face" => return Some(Column::Face),
        "material" => return Some(Column::Material),
        "group" => return Some(Column::Group),
        _ => {}
    }
    let (quantity, rest) = if let Some(r) = name.strip_prefix("rad_") {
        (0, r)
    } else if let Some(r) = name.strip_prefix("irr_") {
        (1, r)
    } else {
        return None;
    };
    let (side, rest) = match rest.strip_prefix("back_") {
        Some(r) => (1, r),
        None => (0, rest),
    };
    let label = rest
        .strip_suffix(FLUX_UNIT)
        .and_then(|l| l.strip_suffix('_'))
        .unwrap_or(rest);
    if label.is_empty() {
        return None;
    }
    Some(Column::Flux {
        quantity,
        side,
        label: label.to_string(),
    })
}

/// Writes `text` as one CSV field: quoted (with `""` for a quote) when it holds a comma, a
/// quote, a line break or leading or trailing spaces; line breaks become spaces (a row is
/// one line).
pub fn push_field(out: &mut String, text: &str) {
    let needs =
        text.contains([',', '"', '\n', '\r']) || text.starts_with(' ') || text.ends_with(' ');
    if !needs {
        out.push_str(text);
        return;
    }
    out.push('"');
    for c in text.chars() {
        match c {
            '"' => out.push_str("\"\""),
            '\n' | '\r' => out.push(' '),
            c => out.push(c),
        }
    }
    out.push('"');
}

/// A field of a CSV line: its text (unquoted, `""` read as `"`) and the byte offset where it
/// starts.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Field<'a> {
    /// The field's bytes as written (without the quotes of a quoted field).
    pub text: std::borrow::Cow<'a, [u8]>,
    /// Byte offset of the field in its line.
    pub at: usize,
}

/// Splits a line into fields (RFC 4180 quoting within the line); `Err(offset)` at an
/// unterminated quote or a quote followed by something other than a comma.
pub fn split_fields(line: &[u8]) -> Result<Vec<Field<'_>>, usize> {
    let mut out = Vec::new();
    let mut at = 0usize;
    loop {
        if line.get(at) == Some(&b'"') {
            let start = at;
            let mut text = Vec::new();
            let mut i = at + 1;
            loop {
                match line.get(i) {
                    None => return Err(start),
                    Some(b'"') if line.get(i + 1) == Some(&b'"') => {
                        text.push(b'"');
                        i += 2;
                    }
                    Some(b'"') => {
                        i += 1;
                        break;
                    }
                    Some(&c) => {
                        text.push(c);
                        i += 1;
                    }
                }
            }
            out.push(Field {
                text: std::borrow::Cow::Owned(text),
                at: start,
            });
            match line.get(i) {
                None => return Ok(out),
                Some(b',') => at = i + 1,
                Some(_) => return Err(i),
            }
        } else {
            let end = line[at..]
                .iter()
                .position(|&c| c == b',')
                .map_or(line.len(), |p| at + p);
            out.push(Field {
                text: std::borrow::Cow::Borrowed(&line[at..end]),
                at,
            });
            if end == line.len() {
                return Ok(out);
            }
            at = end + 1;
        }
    }
}
