//! A one-line progress bar on stderr for long solves: silent for the first second, redrawn at
//! most ten times a second, only when stderr is a terminal, never with `--quiet`. Safe to
//! update from several threads.

use std::io::{IsTerminal, Write};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Nothing is shown before a run has lasted this long.
pub const QUIET_START: Duration = Duration::from_secs(1);

/// Shortest time between two redraws.
pub const REDRAW_EVERY: Duration = Duration::from_millis(100);

/// Width of the bar in characters.
const BAR: usize = 30;

/// Longest phase name shown (characters).
const PHASE_CHARS: usize = 40;

struct State {
    phase: String,
    total: Option<u64>,
    done: u64,
    last_draw: Option<Instant>,
    shown: bool,
    out: Box<dyn Write + Send>,
}

/// The progress of a run: a phase with a known total (`done/total` and a bar) or an open
/// count (iterations).
pub struct Progress {
    enabled: bool,
    start: Instant,
    state: Mutex<State>,
}

impl Progress {
    /// A reporter on stderr; shows nothing when `quiet` or when stderr is not a terminal.
    pub fn new(quiet: bool) -> Self {
        let enabled = !quiet && std::io::stderr().is_terminal();
        Self::with_output(enabled, Box::new(std::io::stderr()))
    }

    /// A reporter on any writer (for tests).
    pub(crate) fn with_output(enabled: bool, out: Box<dyn Write + Send>) -> Self {
        Progress {
            enabled,
            start: Instant::now(),
            state: Mutex::new(State {
                phase: String::new(),
                total: None,
                done: 0,
                last_draw: None,
                shown: false,
                out,
            }),
        }
    }

    /// True when something may be shown.
    pub fn enabled(&self) -> bool {
        self.enabled
    }

    /// Starts a phase: `total` steps when known, else an open count. Resets the count.
    pub fn phase(&self, name: &str, total: Option<u64>) {
        self.update(Instant::now(), |s| {
            s.phase = name.chars().take(PHASE_CHARS).collect();
            s.total = total;
            s.done = 0;
        });
    }

    /// Sets the steps done in the current phase.
    pub fn set(&self, done: u64) {
        self.update(Instant::now(), |s| s.done = done);
    }

    /// Adds steps done in the current phase.
    pub fn advance(&self, steps: u64) {
        self.update(Instant::now(), |s| s.done = s.done.saturating_add(steps));
    }

    /// Clears the line, if one was drawn.
    pub fn finish(&self) {
        if !self.enabled {
            return;
        }
        let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        if s.shown {
            let _ = s.out.write_all(b"\r\x1b[2K");
            let _ = s.out.flush();
            s.shown = false;
        }
    }

    /// [`Progress::set`] at a given time (for tests).
    #[cfg(test)]
    pub(crate) fn set_at(&self, done: u64, now: Instant) {
        self.update(now, |s| s.done = done);
    }

    /// Applies `change` and redraws if it is time to.
    fn update(&self, now: Instant, change: impl FnOnce(&mut State)) {
        if !self.enabled {
            return;
        }
        let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        change(&mut s);
        let elapsed = now.saturating_duration_since(self.start);
        let due = elapsed >= QUIET_START
            && s.last_draw
                .is_none_or(|t| now.saturating_duration_since(t) >= REDRAW_EVERY);
        if due {
            let text = line(&s.phase, s.done, s.total, elapsed);
            let _ = write!(s.out, "\r\x1b[2K{text}");
            let _ = s.out.flush();
            s.last_draw = Some(now);
            s.shown = true;
        }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.finish();
    }
}

/// The text of the line: `phase [#####-----] done/total pct% secs s`, or `phase: done,
/// secs s` for an open count.
pub fn line(phase: &str, done: u64, total: Option<u64>, elapsed: Duration) -> String {
    let secs = elapsed.as_secs_f64();
    match total {
        Some(total) => {
            let fraction = if total == 0 {
                1.0
            } else {
                (done as f64 / total as f64).clamp(0.0, 1.0)
            };
            let filled = (fraction * BAR as f64).floor() as usize;
            format!(
                "{phase} [{}{}] {done}/{total} {:3.0}% {secs:.1} s",
                "#".repeat(filled),
                "-".repeat(BAR - filled),
                fraction * 100.0
            )
        }
        None => format!("{phase}: {done}, {secs:.1} s"),
    }
}
