//! Helpers shared by the integration tests in `tests/`.

use std::path::PathBuf;

pub mod sample;

/// Path of a file in `fixtures/`.
pub fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(name)
}
