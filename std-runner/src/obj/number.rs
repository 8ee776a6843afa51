//! Numbers of OBJ/MTL statements: finite `f32` values and 1-based (or negative, relative)
//! element indices. Errors are messages; callers attach the location.

/// Parses a finite `f32`. NaN, infinities and values beyond the `f32` range are refused.
pub(crate) fn parse_f32(text: &str) -> Result<f32, String> {
    match text.parse::<f32>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => {
            let lower = text.to_ascii_lowercase();
            if lower.contains("inf") || lower.contains("nan") {
                Err(format!("'{text}' is not a finite number"))
            } else {
                Err(format!("'{text}' is too large for a 32-bit float"))
            }
        }
        Err(_) => Err(format!("expected a number, found '{text}'")),
    }
}

/// Resolves an OBJ index of element kind `what` ("vertex", "texture coordinate", "normal")
/// against the `count` elements defined so far: `1..=count` from the start, `-1..=-count`
/// from the end. Returns the 0-based index.
pub(crate) fn resolve_index(text: &str, what: &str, count: usize) -> Result<usize, String> {
    if text.is_empty() {
        return Err(format!("missing {what} index"));
    }
    let Ok(i) = text.parse::<i64>() else {
        let digits = text.strip_prefix(['-', '+']).unwrap_or(text);
        return if !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()) {
            // An integer beyond i64: out of range whatever was defined.
            Err(format!(
                "{what} index {text} is out of range ({count} defined so far)"
            ))
        } else {
            Err(format!("expected a {what} index, found '{text}'"))
        };
    };
    let count_i = i64::try_from(count).unwrap_or(i64::MAX);
    if i == 0 {
        Err(format!(
            "{what} index 0 is invalid (OBJ indices start at 1, negative ones count back from the last)"
        ))
    } else if i > 0 && i <= count_i {
        Ok((i - 1) as usize)
    } else if i < 0 && i >= -count_i {
        Ok((count_i + i) as usize)
    } else {
        Err(format!(
            "{what} index {i} is out of range ({count} defined so far)"
        ))
    }
}
