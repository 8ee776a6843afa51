//! Everything a solve writes and reads besides the solver: the per-polygon results table
//! (CSV) and its reader, the error against a reference table, images rasterised as patches
//! stream by (EXR, PNG), the stats report, and progress on stderr.
//!
//! Units: m^2 for areas, W/m^2 for radiosity and irradiance, W/m^2/sr (radiosity / pi) for
//! image radiance.

pub mod camera;
pub mod colorbar;
pub mod colormap;
pub mod columns;
pub mod display;
pub mod exr_file;
pub mod font;
pub mod frame;
pub mod image;
pub mod image_compare;
pub mod interp;
pub mod outputs;
pub mod png_file;
pub mod progress;
pub mod raster;
pub mod reference;
pub mod results;
pub mod results_read;
pub mod row_labels;
pub mod shade;
pub mod smooth;
pub mod stats;
pub mod view;
pub mod weld;

pub use camera::{
    OptionError, Projection, Size, camera_arg, check_camera, default_camera, default_camera_up,
    parse_camera, parse_size, scene_bounds,
};
pub use display::{Display, DisplayMode};
pub use exr_file::{read_exr, write_exr};
pub use frame::{Frame, channel_names};
pub use image::{ImageFormat, ImageSink, Shading};
pub use outputs::Outputs;
pub use png_file::{DisplayBands, tone_map, tone_map_with, write_png, write_rgb_png};
pub use progress::Progress;
pub use raster::Rasterizer;
pub use reference::{CompareError, Comparison, ReferenceSink, WorstPolygon, compare};
pub use results::{ResultsFile, ResultsTable, ResultsWriter, TableLayout};
pub use results_read::{TableError, read_results, read_results_file};
pub use row_labels::RowLabels;
pub use stats::{
    BandPower, ImageSettings, LeafBin, Levels, OutputFile, PhaseTime, RaysByPhase, RunSettings,
    SolveReport, TablesMade, TopLevelBytes, Verdict,
};

#[cfg(test)]
mod tests_camera;
#[cfg(test)]
mod tests_colormap;
#[cfg(test)]
mod tests_image;
#[cfg(test)]
pub(crate) mod tests_progress;
#[cfg(test)]
mod tests_reference;
#[cfg(test)]
mod tests_results;
#[cfg(test)]
mod tests_smooth;
#[cfg(test)]
mod tests_stats;
