//! Keywords and the spelling of names: bare when they are identifiers that are not keywords,
//! quoted (with escapes) otherwise. Shared by the lexer, the parser and the printer.

use std::fmt::Write;

/// Every keyword of the format. A bare word that is a keyword is never a name.
pub const KEYWORDS: [&str; 33] = [
    "hirad",
    "bands",
    "material",
    "rho",
    "emit",
    "back_rho",
    "tau",
    "back_emit",
    "camera",
    "pos",
    "target",
    "up",
    "fovy",
    "sun",
    "sky",
    "from",
    "irradiance",
    "original",
    "scene",
    "v",
    "tri",
    "quad",
    "cluster",
    "instance",
    "exact",
    "approx",
    "name",
    "axis",
    "age",
    "translate",
    "rotate",
    "quat",
    "scale",
];

/// True if `w` is a keyword.
pub(crate) fn is_keyword(w: &str) -> bool {
    KEYWORDS.contains(&w)
}

/// True if `s` matches `[A-Za-z_][A-Za-z0-9_.-]*`.
pub(crate) fn is_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '.' | '-'))
}

/// `s` in double quotes with `"`, `\` and control characters escaped.
pub(crate) fn quote(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            '\r' => out.push_str("\\r"),
            c if c.is_control() => {
                let _ = write!(out, "\\u{{{:x}}}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// How a name is written: bare if that reads back as the same name, else quoted.
pub(crate) fn spell(s: &str) -> String {
    if is_identifier(s) && !is_keyword(s) {
        s.to_string()
    } else {
        quote(s)
    }
}
