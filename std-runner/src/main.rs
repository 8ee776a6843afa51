//! The `hirad` command line.

use std::process::ExitCode;

fn main() -> ExitCode {
    if let Err(e) = hirad::interrupt::install() {
        eprintln!(
            "warning: cannot handle SIGINT and SIGTERM ({e}): an interrupted run may leave temporary files"
        );
    }
    match hirad::cli::run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            // The statuses are documented in `hirad::exit` and README.md.
            ExitCode::from(hirad::exit::class_of(&e) as u8)
        }
    }
}
