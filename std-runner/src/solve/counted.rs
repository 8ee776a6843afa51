//! A sink that counts the polygons a solve hands out and tells the progress: hi finishes
//! them level by level over the whole run, so the count of final polygons is the run's own
//! progress (a 10-tree forest takes hours).

use crate::output::Progress;
use hirad_core::sink::{PatchResult, PolygonResult, Sink};

/// Polygons between two reports to the progress.
const REPORT_EVERY: u64 = 4096;

/// `inner`, with every polygon counted of `total` for `progress`.
pub(super) struct Counted<'a, K> {
    pub inner: &'a mut K,
    pub progress: &'a Progress,
    pub done: u64,
    pub total: u64,
}

impl<K: Sink<Error = anyhow::Error>> Sink for Counted<'_, K> {
    type Error = anyhow::Error;

    fn patch(&mut self, patch: &PatchResult<'_>) -> anyhow::Result<()> {
        self.inner.patch(patch)
    }

    fn polygon(&mut self, polygon: &PolygonResult<'_>) -> anyhow::Result<()> {
        self.inner.polygon(polygon)?;
        self.done += 1;
        if self.done.is_multiple_of(REPORT_EVERY) || self.done == self.total {
            self.progress.polygons_final(self.done, self.total);
        }
        Ok(())
    }
}
