//! The progress line: its text, its timing, and silence when disabled.

use super::progress::{Progress, line};
use std::io::Write;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// A writer the tests read back (shared with the progress adapter's tests).
#[derive(Clone, Default)]
pub(crate) struct Shared(pub(crate) Arc<Mutex<Vec<u8>>>);

impl Write for Shared {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.lock().unwrap().extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl Shared {
    fn text(&self) -> String {
        String::from_utf8(self.0.lock().unwrap().clone()).unwrap()
    }
}

#[test]
fn line_text() {
    let l = line("gather", 5, Some(10), Duration::from_millis(2500));
    assert_eq!(
        l,
        format!(
            "gather [{}{}] 5/10  50% 2.5 s",
            "#".repeat(15),
            "-".repeat(15)
        )
    );
    assert_eq!(
        line("refine", 12, None, Duration::from_secs(3)),
        "refine: 12, 3.0 s"
    );
    assert_eq!(
        line("meshing", 0, None, Duration::from_millis(500)),
        "meshing, 0.5 s"
    );
    assert_eq!(
        line("solving (iterations)", 0, None, Duration::ZERO),
        "solving (iterations): 0, 0.0 s"
    );
    assert!(line("x", 3, Some(0), Duration::ZERO).contains("100%"));
    assert!(line("x", 30, Some(10), Duration::ZERO).contains("100%"));
}

#[test]
fn silent_first_second_then_at_most_ten_redraws_a_second() {
    let out = Shared::default();
    // Taken before the reporter starts, so that `t0 + d` is at most `d` into its run.
    let t0 = Instant::now();
    let p = Progress::with_output(true, Box::new(out.clone()));
    p.phase("solve", Some(100));
    p.set_at(1, t0 + Duration::from_millis(500));
    assert_eq!(out.text(), "");
    p.set_at(2, t0 + Duration::from_millis(1200));
    assert!(out.text().contains("2/100"), "{}", out.text());
    p.set_at(3, t0 + Duration::from_millis(1250));
    assert!(!out.text().contains("3/100"));
    p.set_at(4, t0 + Duration::from_millis(1400));
    assert!(out.text().contains("4/100"));
    p.finish();
    assert!(out.text().ends_with("\r\x1b[2K"));
    let before = out.text().len();
    p.finish();
    drop(p);
    assert_eq!(out.text().len(), before, "the line is cleared once");
}

#[test]
fn disabled_shows_nothing() {
    let out = Shared::default();
    let p = Progress::with_output(false, Box::new(out.clone()));
    p.phase("solve", None);
    p.set_at(5, Instant::now() + Duration::from_secs(5));
    p.advance(3);
    p.finish();
    assert!(!p.enabled());
    assert_eq!(out.text(), "");
    assert!(!Progress::new(true).enabled(), "quiet disables it");
}

#[test]
fn the_time_left_shows_once_a_phase_has_run_a_while() {
    use super::progress::remaining;
    let s = Duration::from_secs;
    assert_eq!(remaining(10, Some(100), s(1)), None, "too early to tell");
    assert_eq!(remaining(0, Some(100), s(10)), None, "nothing done yet");
    assert_eq!(remaining(100, Some(100), s(10)), None, "done");
    assert_eq!(remaining(5, None, s(10)), None, "an open count");
    assert_eq!(remaining(25, Some(100), s(10)), Some(s(30)));
}

#[test]
fn a_new_phase_and_a_finished_one_are_drawn_at_once() {
    let out = Shared::default();
    let p = Progress::with_output(true, Box::new(out.clone()));
    // Past the quiet first second (the run's own clock).
    std::thread::sleep(Duration::from_millis(1050));
    p.phase_at("loaded (polygons)", Some(40), 40);
    assert!(out.text().contains("40/40 100%"), "{}", out.text());
    // A new phase is drawn even right after a draw, with its count.
    p.phase_at("refining (links)", None, 17);
    assert!(
        out.text().contains("refining (links): 17"),
        "{}",
        out.text()
    );
    // So is its completion.
    p.phase("gather", Some(10));
    p.set(10);
    assert!(out.text().contains("10/10 100%"), "{}", out.text());
}

#[test]
fn without_a_terminal_plain_lines_a_phase_each_and_few() {
    use super::progress::{LOG_EVERY, LOG_MIN, log_line};
    let out = Shared::default();
    let t0 = Instant::now();
    let p = Progress::with_lines(Box::new(out.clone()));
    p.phase("loading", None);
    p.set_at(0, t0 + Duration::from_millis(500));
    assert_eq!(out.text(), "", "silent for the first second");
    p.set_at(0, t0 + Duration::from_millis(1100));
    assert_eq!(out.text().lines().count(), 1, "{}", out.text());
    p.phase("lighting patches", Some(100));
    // A new phase within LOG_MIN of the last line waits; counts within a phase wait for
    // LOG_EVERY.
    p.set_at(10, t0 + Duration::from_millis(1100) + LOG_MIN / 2);
    assert_eq!(out.text().lines().count(), 1, "{}", out.text());
    p.set_at(20, t0 + Duration::from_millis(1100) + LOG_MIN);
    assert_eq!(out.text().lines().count(), 2, "{}", out.text());
    for k in 0..50u32 {
        p.set_at(
            21 + u64::from(k),
            t0 + Duration::from_millis(1100) + LOG_MIN + LOG_EVERY * k / 50,
        );
    }
    assert_eq!(out.text().lines().count(), 2, "{}", out.text());
    p.set_at(90, t0 + Duration::from_millis(1100) + LOG_MIN + LOG_EVERY);
    let text = out.text();
    assert_eq!(text.lines().count(), 3, "{text}");
    assert!(
        !text.contains('\x1b') && !text.contains('\r'),
        "no escape codes: {text:?}"
    );
    assert!(
        text.lines()
            .nth(1)
            .unwrap()
            .contains("lighting patches 20/100 (20%)"),
        "{text}"
    );
    assert!(text.lines().all(|l| l.starts_with("progress ")), "{text}");
    p.finish();
    assert_eq!(out.text(), text, "nothing to clear");
    assert_eq!(
        log_line("solving (iterations)", 7, None, Duration::from_secs(3)),
        "progress 3.0 s: solving (iterations): 7"
    );
    assert_eq!(
        log_line("meshing", 0, None, Duration::from_secs(3)),
        "progress 3.0 s: meshing"
    );
}

#[test]
fn a_run_that_streams_its_polygons_shows_them_after_the_phase() {
    use super::progress::overall;
    assert_eq!(overall(None, Duration::from_secs(9)), "");
    assert_eq!(
        overall(Some((0, 10)), Duration::from_secs(9)),
        "; polygons final 0/10 (0%)"
    );
    // Too early for the pace to tell; then at the run's pace so far.
    assert_eq!(
        overall(Some((5, 10)), Duration::from_secs(2)),
        "; polygons final 5/10 (50%)"
    );
    assert_eq!(
        overall(Some((2500, 10000)), Duration::from_secs(300)),
        "; polygons final 2500/10000 (25%), about 15 min 00 s left in all"
    );
    let out = Shared::default();
    let t0 = Instant::now();
    let p = Progress::with_lines(Box::new(out.clone()));
    p.phase("final gather: polygons and output (polygons)", Some(12));
    p.polygons_final(4096, 16384);
    p.set_at(3, t0 + Duration::from_secs(5));
    let text = out.text();
    assert!(text.contains("(polygons) 3/12 (25%), about "), "{text}");
    assert!(
        text.contains(" s left; polygons final 4096/16384 (25%), about "),
        "{text}"
    );
    assert!(text.trim_end().ends_with("left in all"), "{text}");
}
