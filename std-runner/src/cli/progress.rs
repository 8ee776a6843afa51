//! Progress on stderr for long runs: only on a terminal, at most once a second.

use std::io::{IsTerminal, Write};
use std::time::{Duration, Instant};

/// A writer that counts bytes and shows progress while a long output is written.
pub struct Progress<W> {
    inner: W,
    label: &'static str,
    bytes: u64,
    start: Instant,
    last: Instant,
    shown: bool,
    enabled: bool,
}

impl<W: Write> Progress<W> {
    /// Wraps `inner`; shows `label` and the bytes written when stderr is a terminal.
    pub fn new(inner: W, label: &'static str, quiet: bool) -> Self {
        let now = Instant::now();
        Progress {
            inner,
            label,
            bytes: 0,
            start: now,
            last: now,
            shown: false,
            enabled: !quiet && std::io::stderr().is_terminal(),
        }
    }

    /// Clears the progress line.
    pub fn finish(&mut self) {
        if self.shown {
            eprint!("\r\x1b[2K");
            self.shown = false;
        }
    }
}

impl<W: Write> Write for Progress<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.bytes += n as u64;
        if self.enabled && self.last.elapsed() >= Duration::from_secs(1) {
            self.last = Instant::now();
            let secs = self.start.elapsed().as_secs_f64();
            eprint!(
                "\r\x1b[2K{}: {:.1} MB written, {:.0} s",
                self.label,
                self.bytes as f64 / 1e6,
                secs
            );
            self.shown = true;
        }
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}
