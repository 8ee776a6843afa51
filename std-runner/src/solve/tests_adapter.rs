//! The core's progress reports as the runner shows them.

use super::ProgressAdapter;
use crate::output::Progress;
use hirad_core::hr::Progress as _;
use std::io::Write;
use std::sync::{Arc, Mutex};

#[derive(Clone, Default)]
struct Shared(Arc<Mutex<Vec<u8>>>);

impl Write for Shared {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.lock().unwrap().extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
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
    let mut a = ProgressAdapter {
        bar: &bar,
        phase: String::new(),
        pass: 0,
        times: Vec::new(),
        current: None,
    };
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
