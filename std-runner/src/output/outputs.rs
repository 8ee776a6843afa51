//! Every output of a solve behind one [`Sink`]: the results table, the image and the
//! comparison with a reference, each optional, finished together.

use super::image::ImageSink;
use super::reference::{Comparison, ReferenceSink};
use super::results::ResultsFile;
use anyhow::anyhow;
use hirad_core::sink::{PatchResult, PolygonResult, Sink};

/// The sinks a solve feeds. Dropped unfinished (a failed solve), no file is left behind.
#[derive(Default)]
pub struct Outputs {
    /// `--results`: the CSV table.
    pub results: Option<ResultsFile>,
    /// `--image`: the EXR or PNG image.
    pub image: Option<ImageSink>,
    /// `--reference`: the running comparison.
    pub reference: Option<ReferenceSink>,
}

impl Outputs {
    /// Renames the finished files into place, then returns the comparison, if any (a
    /// reference that does not match is reported after the files are written).
    pub fn finish(self) -> anyhow::Result<Option<Comparison>> {
        if let Some(r) = self.results {
            r.finish()?;
        }
        if let Some(i) = self.image {
            i.finish()?;
        }
        match self.reference {
            Some(r) => Ok(Some(r.finish().map_err(|e| anyhow!("reference: {e}"))?)),
            None => Ok(None),
        }
    }
}

impl Sink for Outputs {
    type Error = anyhow::Error;

    fn patch(&mut self, patch: &PatchResult<'_>) -> anyhow::Result<()> {
        if let Some(i) = &mut self.image {
            i.patch(patch)?;
        }
        Ok(())
    }

    fn polygon(&mut self, polygon: &PolygonResult<'_>) -> anyhow::Result<()> {
        if let Some(r) = &mut self.results {
            r.polygon(polygon)?;
        }
        if let Some(r) = &mut self.reference {
            r.polygon(polygon).map_err(|e| anyhow!("reference: {e}"))?;
        }
        Ok(())
    }
}
