//! Whether a solve's numbers are right: its power balance per band, and the reason a run
//! fails (not converged, diverged, a balance beyond `--max-imbalance`) or the warning it
//! passes with, decided before the stats that record the verdict are written.

use crate::output::{self, SolveReport};
use hirad_core::hr::Balance;

/// The power balance's lines, one per band (both solvers account alike).
pub(super) fn powers(p: &Balance, bands: usize, names: &[String]) -> Vec<output::BandPower> {
    (0..bands)
        .map(|b| output::BandPower {
            band: names.get(b).cloned().unwrap_or_else(|| b.to_string()),
            emitted: p.emitted[b],
            direct: p.direct[b],
            absorbed: p.absorbed[b],
            absorbed_backs: p.absorbed_backs[b],
            escaped: p.escaped[b],
            imbalance: p.imbalance(b),
            imbalance_percent: 100.0 * p.relative_imbalance(b),
        })
        .collect()
}

/// Why the run's numbers are not right (the run then exits 1 after writing its outputs), or
/// `None`.
pub(super) fn failure(
    report: &SolveReport,
    max_iterations: u32,
    max_imbalance: f64,
) -> Option<String> {
    if report.diverged {
        return Some(format!(
            "the solution diverged (a radiosity grew without bound after {} iterations): the outputs were written but mean nothing; this is a solver defect, please report the scene",
            report.iterations
        ));
    }
    if !report.converged {
        return Some(format!(
            "the solution did not converge within {} iterations{}: the outputs were written but are not final (raise --tolerance, or check that the scene absorbs light)",
            max_iterations,
            report
                .remaining_change
                .map(|r| format!(
                    " (estimated change still to come {r:.1e} of the largest radiosity)"
                ))
                .unwrap_or_default()
        ));
    }
    let w = worst_band(report)?;
    (w.imbalance_percent.abs() > max_imbalance).then(|| {
        format!(
            "{}; above --max-imbalance {}%, the outputs were written but are not right",
            balance_line(report, w),
            max_imbalance
        )
    })
}

/// The warning of a power balance off by more than 1% but within `--max-imbalance`.
pub(super) fn balance_warning(report: &SolveReport, max_imbalance: f64) -> Option<String> {
    let w = worst_band(report)?;
    let off = w.imbalance_percent.abs();
    (off > max_imbalance.min(1.0) && off <= max_imbalance).then(|| balance_line(report, w))
}

/// The band whose power balance is worst.
fn worst_band(report: &SolveReport) -> Option<&output::BandPower> {
    report.power.iter().max_by(|x, y| {
        x.imbalance_percent
            .abs()
            .total_cmp(&y.imbalance_percent.abs())
    })
}

fn balance_line(report: &SolveReport, w: &output::BandPower) -> String {
    let index = report
        .power
        .iter()
        .position(|p| std::ptr::eq(p, w))
        .unwrap_or(0);
    let names: Vec<String> = report.power.iter().map(|p| p.band.clone()).collect();
    let names = if names.iter().enumerate().all(|(i, n)| *n == i.to_string()) {
        Vec::new()
    } else {
        names
    };
    let what = if w.imbalance_percent > 0.0 {
        "lost"
    } else {
        "made"
    };
    let cure = if report.method == "exact" {
        "the form factors disagree with the rays: more --elements brings it down"
    } else {
        "cluster links approximate; a smaller --epsilon or more --rays brings it down"
    };
    format!(
        "the power balance is off by {:+.2}% in {}: the transport {what} that much light ({cure})",
        w.imbalance_percent,
        output::columns::band_name(index, &names)
    )
}
