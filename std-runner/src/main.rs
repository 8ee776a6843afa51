//! The `hirad` command line.

use std::process::ExitCode;

fn main() -> ExitCode {
    match hirad::cli::run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
