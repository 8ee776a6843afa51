//! Progress of long runs on stderr, never with `--quiet`, silent for the first second. Safe
//! to update from several threads.
//!
//! * On a terminal, a one-line bar redrawn at most ten times a second (and whenever a phase
//!   starts or completes, so that no phase shows a stale count). A phase with a known total
//!   shows its bar, its count and, once it has run a few seconds, the time it still needs at
//!   its pace so far.
//! * Without a terminal (a log, CI), plain lines, no escape codes: one when a phase starts
//!   (at most one every [`LOG_MIN`]) and one every [`LOG_EVERY`] within a long phase, each
//!   with the run's time, e.g. `progress 12.4 s: lighting patches 5120/20480 (25%), about
//!   37 s left`.
//!
//! `HIRAD_PROGRESS` overrides the choice: `bar` draws the bar, `lines` (or `always`) writes
//! the lines, `off` shows nothing, `every` draws every update as a bar from the start (what
//! the tests read).

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
const PHASE_CHARS: usize = 48;

/// A phase that has run this long shows how long it still needs.
const ETA_AFTER: Duration = Duration::from_secs(3);

/// Without a terminal: the shortest time between two lines.
pub const LOG_MIN: Duration = Duration::from_secs(2);

/// Without a terminal: a line at least this often within a long phase.
pub const LOG_EVERY: Duration = Duration::from_secs(10);

struct State {
    phase: String,
    total: Option<u64>,
    done: u64,
    /// When the current phase started.
    since: Instant,
    last_draw: Option<Instant>,
    shown: bool,
    /// The phase of the last line written (lines mode).
    logged: String,
    /// Polygons final of all and their total, for a run that streams them as it goes (hi,
    /// level by level): shown after the phase, with the time the rest needs at the run's
    /// pace so far.
    polygons: Option<(u64, u64)>,
    out: Box<dyn Write + Send>,
}

/// What an embedding caller is told of every update (see [`Progress::observed`]): the phase
/// as shown, steps done and the phase's total when known.
pub type Observer = Box<dyn Fn(&str, u64, Option<u64>) + Send + Sync>;

/// The progress of a run: a phase with a known total (`done/total` and a bar) or an open
/// count (iterations).
pub struct Progress {
    enabled: bool,
    /// Told of every update, drawn or not (an embedding's callback).
    observer: Option<Observer>,
    /// Every update drawn, from the start (`HIRAD_PROGRESS=every`).
    every: bool,
    /// Plain lines instead of a bar (no terminal).
    lines: bool,
    start: Instant,
    state: Mutex<State>,
}

impl Progress {
    /// A reporter on stderr; shows nothing when `quiet` or when stderr is not a terminal
    /// (unless `HIRAD_PROGRESS` says otherwise: see the module).
    pub fn new(quiet: bool) -> Self {
        let mode = std::env::var("HIRAD_PROGRESS").unwrap_or_default();
        let terminal = std::io::stderr().is_terminal();
        let (enabled, lines) = match mode.as_str() {
            "off" | "never" | "0" => (false, false),
            "bar" | "every" => (true, false),
            "lines" | "always" => (true, true),
            _ => (true, !terminal),
        };
        let mut p = Self::with_output(enabled && !quiet, Box::new(std::io::stderr()));
        p.every = mode == "every";
        p.lines = lines;
        p
    }

    /// A reporter writing plain lines to any writer (for tests).
    #[cfg(test)]
    pub(crate) fn with_lines(out: Box<dyn Write + Send>) -> Self {
        let mut p = Self::with_output(true, out);
        p.lines = true;
        p
    }

    /// A reporter drawing every update as a bar on any writer (for tests).
    #[cfg(test)]
    pub(crate) fn with_every(out: Box<dyn Write + Send>) -> Self {
        let mut p = Self::with_output(true, out);
        p.every = true;
        p
    }

    /// A reporter on any writer (for tests).
    pub(crate) fn with_output(enabled: bool, out: Box<dyn Write + Send>) -> Self {
        let start = Instant::now();
        Progress {
            enabled,
            observer: None,
            every: false,
            lines: false,
            start,
            state: Mutex::new(State {
                phase: String::new(),
                total: None,
                done: 0,
                since: start,
                last_draw: None,
                shown: false,
                logged: String::new(),
                polygons: None,
                out,
            }),
        }
    }

    /// A reporter that draws nothing and tells `observer` of every update instead (a
    /// library caller's callback: the Python package's progress and its Ctrl-C check). The
    /// observer runs on whichever thread reports, without the reporter's lock held; it may
    /// unwind to stop the run (the caller catches it).
    pub fn observed(observer: Observer) -> Self {
        let mut p = Self::with_output(false, Box::new(std::io::sink()));
        p.observer = Some(observer);
        p
    }

    /// True when something may be shown.
    pub fn enabled(&self) -> bool {
        self.enabled
    }

    /// Starts a phase: `total` steps when known, else an open count. Resets the count.
    pub fn phase(&self, name: &str, total: Option<u64>) {
        self.phase_at(name, total, 0);
    }

    /// Starts a phase with `done` steps already done (one update: a phase that starts
    /// complete shows so at once).
    pub fn phase_at(&self, name: &str, total: Option<u64>, done: u64) {
        let now = Instant::now();
        self.update(now, |s| {
            s.phase = name.chars().take(PHASE_CHARS).collect();
            s.total = total;
            s.done = done;
            s.since = now;
            true
        });
    }

    /// Sets the steps done in the current phase.
    pub fn set(&self, done: u64) {
        self.update(Instant::now(), |s| {
            s.done = done;
            s.total.is_some_and(|t| done >= t)
        });
    }

    /// Sets the steps done in the current phase and its total (sibling levels solved on
    /// two threads report the same phase with their own totals: the line shows a pair that
    /// belongs together).
    pub fn set_of(&self, done: u64, total: Option<u64>) {
        self.update(Instant::now(), |s| {
            s.done = done;
            s.total = total;
            total.is_some_and(|t| done >= t)
        });
    }

    /// Adds steps done in the current phase.
    pub fn advance(&self, steps: u64) {
        self.update(Instant::now(), |s| {
            s.done = s.done.saturating_add(steps);
            false
        });
    }

    /// Sets the polygons final of the run's `total` (see [`State`]); nothing is drawn for it
    /// alone.
    pub fn polygons_final(&self, done: u64, total: u64) {
        self.update(Instant::now(), |s| {
            s.polygons = Some((done, total));
            false
        });
    }

    /// Clears the line, if one was drawn.
    pub fn finish(&self) {
        if !self.enabled || self.lines {
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
        self.update(now, |s| {
            s.done = done;
            false
        });
    }

    /// Applies `change` (which says whether the update must be drawn: a phase starting or
    /// completing) and redraws if it is time to.
    fn update(&self, now: Instant, change: impl FnOnce(&mut State) -> bool) {
        if let Some(observer) = &self.observer {
            let (phase, done, total) = {
                let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
                change(&mut s);
                (s.phase.clone(), s.done, s.total)
            };
            observer(&phase, done, total);
            return;
        }
        if !self.enabled {
            return;
        }
        let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        let must = change(&mut s);
        let elapsed = now.saturating_duration_since(self.start);
        if self.lines {
            let since = s.last_draw.map(|t| now.saturating_duration_since(t));
            let new_phase = s.phase != s.logged;
            let due = elapsed >= QUIET_START
                && since.is_none_or(|d| d >= LOG_EVERY || (new_phase && d >= LOG_MIN));
            if due {
                let mut text = log_line(&s.phase, s.done, s.total, elapsed);
                if let Some(left) =
                    remaining(s.done, s.total, now.saturating_duration_since(s.since))
                {
                    text.push_str(&format!(", about {} left", duration(left)));
                }
                text.push_str(&overall(s.polygons, elapsed));
                let _ = writeln!(s.out, "{text}");
                let _ = s.out.flush();
                s.last_draw = Some(now);
                s.logged = s.phase.clone();
            }
            return;
        }
        let due = self.every
            || (elapsed >= QUIET_START
                && (must
                    || s.last_draw
                        .is_none_or(|t| now.saturating_duration_since(t) >= REDRAW_EVERY)));
        if due {
            let mut text = line(&s.phase, s.done, s.total, elapsed);
            if let Some(left) = remaining(s.done, s.total, now.saturating_duration_since(s.since)) {
                text.push_str(&format!(", about {} left", duration(left)));
            }
            text.push_str(&overall(s.polygons, elapsed));
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

/// The time a phase with a total still needs at its pace so far, once it has run
/// [`ETA_AFTER`] and is neither done nor just started.
pub fn remaining(done: u64, total: Option<u64>, in_phase: Duration) -> Option<Duration> {
    let total = total?;
    if in_phase < ETA_AFTER || done == 0 || done >= total {
        return None;
    }
    Some(in_phase.mul_f64((total - done) as f64 / done as f64))
}

/// What follows the phase for a run that streams its polygons (see `State::polygons`):
/// `; polygons final 1200/10000 (12%), about 14 min 40 s left in all`, or nothing.
pub fn overall(polygons: Option<(u64, u64)>, elapsed: Duration) -> String {
    let Some((done, total)) = polygons else {
        return String::new();
    };
    let pct = if total == 0 {
        100.0
    } else {
        (done as f64 / total as f64).clamp(0.0, 1.0) * 100.0
    };
    let mut text = format!("; polygons final {done}/{total} ({pct:.0}%)");
    if let Some(left) = remaining(done, Some(total), elapsed) {
        text.push_str(&format!(", about {} left in all", duration(left)));
    }
    text
}

/// `42 s`, `3 min 20 s`, `1 h 05 min`.
fn duration(d: Duration) -> String {
    let s = d.as_secs();
    if s < 60 {
        format!("{s} s")
    } else if s < 3600 {
        format!("{} min {:02} s", s / 60, s % 60)
    } else {
        format!("{} h {:02} min", s / 3600, (s % 3600) / 60)
    }
}

/// A line of a log: `progress 12.4 s: phase 5120/20480 (25%)`, or `progress 3.0 s:
/// phase: 12` for an open count (`progress 3.0 s: phase` when it counts nothing).
pub fn log_line(phase: &str, done: u64, total: Option<u64>, elapsed: Duration) -> String {
    let secs = elapsed.as_secs_f64();
    match total {
        Some(total) => {
            let pct = if total == 0 {
                100.0
            } else {
                (done as f64 / total as f64).clamp(0.0, 1.0) * 100.0
            };
            format!("progress {secs:.1} s: {phase} {done}/{total} ({pct:.0}%)")
        }
        None if done == 0 && !phase.ends_with(')') => format!("progress {secs:.1} s: {phase}"),
        None => format!("progress {secs:.1} s: {phase}: {done}"),
    }
}

/// The text of the line: `phase [#####-----] done/total pct% secs s`, or `phase: done,
/// secs s` for an open count (`phase, secs s` when it counts nothing).
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
        // A phase that counts nothing (no unit named, nothing counted): its name and time.
        None if done == 0 && !phase.ends_with(')') => format!("{phase}, {secs:.1} s"),
        None => format!("{phase}: {done}, {secs:.1} s"),
    }
}
