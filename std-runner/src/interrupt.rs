//! What SIGINT and SIGTERM leave behind: nothing but the outputs that were complete.
//!
//! Outputs are written to a temporary file beside their final name and renamed into place
//! when complete (`files::persist`). A signal kills the process without running destructors,
//! so the temporary files are registered here: on SIGINT or SIGTERM a thread removes every
//! one still there, says which outputs were not written, and exits with 130 or 143 (128 +
//! the signal), as a shell would report the signal. Renaming into place holds the same lock,
//! so an output is either complete under its name or gone.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Temporary files and the outputs asked for.
struct Registry {
    /// Temporary files that may still exist.
    temps: Vec<PathBuf>,
    /// Outputs asked for and not yet in place, in the order they were asked for.
    pending: Vec<PathBuf>,
}

static REGISTRY: Mutex<Registry> = Mutex::new(Registry {
    temps: Vec::new(),
    pending: Vec::new(),
});

fn registry() -> std::sync::MutexGuard<'static, Registry> {
    REGISTRY.lock().unwrap_or_else(|e| e.into_inner())
}

/// Starts the thread that handles SIGINT and SIGTERM for the rest of the process.
pub fn install() -> std::io::Result<()> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM])?;
    std::thread::Builder::new()
        .name("hirad-signals".into())
        .spawn(move || {
            if let Some(signal) = signals.forever().next() {
                let name = if signal == SIGINT {
                    "SIGINT"
                } else {
                    "SIGTERM"
                };
                // Held until exit: no output is renamed into place half way.
                let r = registry();
                for t in &r.temps {
                    let _ = std::fs::remove_file(t);
                }
                let not_written: Vec<String> =
                    r.pending.iter().map(|p| p.display().to_string()).collect();
                if not_written.is_empty() {
                    eprintln!("\ninterrupted by {name}");
                } else {
                    eprintln!(
                        "\ninterrupted by {name}: not written: {}",
                        not_written.join(", ")
                    );
                }
                std::process::exit(128 + signal);
            }
        })?;
    Ok(())
}

/// Notes outputs that the run will write, so that an interruption can name those it did not.
pub fn expect(outputs: &[&Path]) {
    let mut r = registry();
    for p in outputs {
        if !r.pending.iter().any(|q| q == p) {
            r.pending.push(p.to_path_buf());
        }
    }
}

/// Creates a temporary file with `create` and notes it for removal on interruption, under
/// the registry's lock (a file created just before an interruption is removed with the
/// others, not left behind unnoted).
pub fn temporary(
    create: impl FnOnce() -> std::io::Result<tempfile::NamedTempFile>,
) -> std::io::Result<tempfile::NamedTempFile> {
    let mut r = registry();
    let tmp = create()?;
    r.temps.push(tmp.path().to_path_buf());
    Ok(tmp)
}

/// Runs `f` with no interruption handled meanwhile (for a temporary file made and removed
/// at once).
pub fn uninterrupted<T>(f: impl FnOnce() -> T) -> T {
    let _r = registry();
    f()
}

/// Runs `rename` (which puts `temp` in place as `output`) so that no interruption can come
/// between it and the registry's update.
pub fn in_place<T>(temp: &Path, output: &Path, rename: impl FnOnce() -> T) -> T {
    let mut r = registry();
    let result = rename();
    r.temps.retain(|t| t != temp);
    r.pending.retain(|p| p != output);
    result
}
