//! Unit tests of the `.hir` parser and printer.

mod accepts;
mod errors;
mod print;

use super::{TextError, parse, print};
use crate::scene::Scene;

/// A minimal valid document with 3 bands: prefix + `body` inside `scene { }`.
pub(super) fn doc(body: &str) -> String {
    format!(
        "hirad 1\nbands 3\nmaterial white rho 0.7 0.7 0.7\nmaterial lamp rho 0 0 0 emit 10 10 10\nscene {{\n{body}\n}}\n"
    )
}

/// Parses, panicking with the error if it fails.
pub(super) fn ok(src: &str) -> Scene {
    match parse(src.as_bytes()) {
        Ok(s) => s,
        Err(e) => panic!("unexpected error {e}\n--- input ---\n{src}"),
    }
}

/// Parses, expecting an error.
pub(super) fn err(src: impl AsRef<[u8]>) -> TextError {
    match parse(src.as_ref()) {
        Ok(_) => panic!(
            "expected an error for\n{}",
            String::from_utf8_lossy(src.as_ref())
        ),
        Err(e) => e,
    }
}

/// Asserts an error at `line:column` whose message contains `needle`.
#[track_caller]
pub(super) fn fails_at(src: impl AsRef<[u8]>, line: u32, column: u32, needle: &str) {
    let e = err(src);
    assert_eq!(
        (e.line, e.column),
        (line, column),
        "wrong position for error: {e}"
    );
    assert!(
        e.message.contains(needle),
        "message {:?} lacks {needle:?}",
        e.message
    );
}

/// parse(print(s)) == s and print is a fixed point.
#[track_caller]
pub(super) fn round_trips(s: &Scene) {
    let text = print(s);
    let back = match parse(text.as_bytes()) {
        Ok(b) => b,
        Err(e) => panic!("printed scene does not parse: {e}\n{text}"),
    };
    assert_eq!(&back, s, "\n{text}");
    assert_eq!(print(&back), text);
}
