//! Progress while the GIL is released: the runner's progress reports go to the Python
//! callback (at most ten times a second, and whenever a phase starts), and every report
//! checks for Ctrl-C. A callback that raises or returns `False`, or a pending signal, stops
//! the solve: the report unwinds with [`Cancelled`] (caught at the module's boundary, see
//! `lib.rs`) and the Python exception is raised in the caller instead.

use hirad::output::Progress;
use pyo3::prelude::*;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Shortest time between two calls of the callback within one phase.
const EVERY: Duration = Duration::from_millis(100);

/// The payload a cancelled solve unwinds with.
pub struct Cancelled;

/// What stopped the solve, raised in the caller.
#[derive(Default)]
pub struct Stop {
    /// The exception (KeyboardInterrupt, the callback's own, or `hirad.Cancelled`).
    pub error: Option<PyErr>,
}

struct Last {
    phase: String,
    at: Option<Instant>,
}

/// The runner's reporter for a solve called from Python: `callback(phase, done, total)`
/// (`total` None for an open count), or only the signal check without one.
pub fn progress(
    callback: Option<Py<PyAny>>,
    cancelled: Py<PyAny>,
    stop: Arc<Mutex<Stop>>,
) -> Progress {
    let last = Mutex::new(Last {
        phase: String::new(),
        at: None,
    });
    Progress::observed(Box::new(move |phase, done, total| {
        let now = Instant::now();
        {
            let mut l = last.lock().unwrap_or_else(|e| e.into_inner());
            let new_phase = l.phase != phase;
            let finished = total.is_some_and(|t| done >= t);
            if !new_phase && !finished && l.at.is_some_and(|t| now - t < EVERY) {
                return;
            }
            l.at = Some(now);
            if new_phase {
                l.phase = phase.to_string();
            }
        }
        let error = Python::attach(|py| -> Option<PyErr> {
            if let Err(e) = py.check_signals() {
                return Some(e);
            }
            let cb = callback.as_ref()?;
            match cb.call1(py, (phase, done, total)) {
                Err(e) => Some(e),
                Ok(v) if v.bind(py).is(&*pyo3::types::PyBool::new(py, false)) => {
                    Some(PyErr::from_value(
                        cancelled
                            .call1(py, ("cancelled by the progress callback",))
                            .map(|e| e.into_bound(py))
                            .unwrap_or_else(|e| e.into_value(py).into_any().into_bound(py)),
                    ))
                }
                Ok(_) => None,
            }
        });
        if let Some(e) = error {
            stop.lock().unwrap_or_else(|e| e.into_inner()).error = Some(e);
            std::panic::resume_unwind(Box::new(Cancelled));
        }
    }))
}
