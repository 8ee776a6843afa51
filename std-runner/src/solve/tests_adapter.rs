//! The core's progress reports as the runner shows them.

use super::ProgressAdapter;
use crate::output::Progress;
use crate::output::tests_progress::Shared;
use hirad_core::hr::Progress as _;

/// An adapter on `bar`, before any report.
fn adapter(bar: &Progress) -> ProgressAdapter<'_> {
    ProgressAdapter {
        bar,
        phase: String::new(),
        pass: 0,
        loads: 0,
        times: Vec::new(),
        current: None,
    }
}

/// The last line drawn (bars are redrawn after a carriage return).
fn last(out: &Shared) -> String {
    let text = String::from_utf8(out.0.lock().unwrap().clone()).unwrap();
    text.rsplit('\r')
        .next()
        .unwrap_or("")
        .replace("\x1b[2K", "")
}

#[test]
fn sibling_levels_reporting_one_phase_show_their_own_totals() {
    let out = Shared::default();
    let bar = Progress::with_every(Box::new(out.clone()));
    let mut a = adapter(&bar);
    let phase = "final gather: polygons and output (polygons)";
    // Two levels on two threads: one of 12 polygons, one of 287, through one reporter.
    a.report(phase, 0, 12);
    assert!(last(&out).contains(" 0/12 "), "{}", last(&out));
    a.report(phase, 268, 287);
    assert!(last(&out).contains(" 268/287 "), "{}", last(&out));
    a.report(phase, 12, 12);
    assert!(last(&out).contains(" 12/12 100%"), "{}", last(&out));
    // A phase with no total keeps counting without one.
    a.report("refining (links)", 5, 0);
    a.report("refining (links)", 9, 0);
    assert!(
        last(&out).contains("refining (links): 9,"),
        "{}",
        last(&out)
    );
}

#[test]
fn passes_are_numbered_in_the_first_level_only() {
    let out = Shared::default();
    let bar = Progress::with_every(Box::new(out.clone()));
    let mut a = adapter(&bar);
    // hr, or hi's top level: its passes numbered.
    a.report("loaded (polygons)", 10, 10);
    for pass in 1..=2 {
        a.report("refining (links)", 1, 0);
        let line = last(&out);
        assert!(
            line.starts_with(&format!("pass {pass}: refining")),
            "{line}"
        );
        a.report("evaluating links", 0, 4);
        let line = last(&out);
        assert!(
            line.starts_with(&format!("pass {pass}: evaluating")),
            "{line}"
        );
    }
    // An opened level (hi): its passes are its own, not the run's third.
    a.report("loaded (polygons)", 5, 5);
    a.report("refining (links)", 1, 0);
    assert!(last(&out).starts_with("refining (links)"), "{}", last(&out));
    a.report("lighting patches", 0, 5);
    assert!(last(&out).starts_with("lighting patches"), "{}", last(&out));
}
