//! The `--image` output: a [`Sink`] that rasterises leaf patches as they stream by and, when
//! the solve is done, writes a linear f32 EXR (`.exr`) or an 8-bit sRGB preview (`.png`)
//! through a temporary file renamed into place.
//!
//! Shading (both formats): smooth by default, radiosity interpolated across the corners
//! patches share (see [`super::smooth`]; the patches are kept, about 80 bytes each plus 8
//! per band, a few hundred bytes more each for a moment while their shared corners are
//! found, and the samples are coloured again when the image is written, or, with
//! [`ImageSink::with_batch`], every so many patches: corners are then shared within a batch
//! only, and memory stays bounded), or flat, every patch in its own value as it streams by. A PNG shows bands as colours or one band
//! through a colour map with a bar (see [`super::display`]).

use super::camera::Size;
use super::colorbar::map_pixels;
use super::display::Display;
use super::exr_file::write_exr;
use super::frame::{Frame, channel_names};
use super::png_file::{write_png, write_rgb_png};
use super::raster::Rasterizer;
use super::shade::shade_all;
use super::smooth::PatchStore;
use crate::files::{persist, temp_beside};
use crate::scene::Camera;
use anyhow::{anyhow, bail};
use hirad_core::sink::{PatchResult, PolygonResult, Sink};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// The image file formats, chosen by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// `.exr`: linear radiance, f32 per band.
    Exr,
    /// `.png`: 8-bit sRGB tone-mapped preview.
    Png,
}

impl ImageFormat {
    /// The format named by a path's extension (case-insensitive).
    pub fn of(path: &Path) -> anyhow::Result<ImageFormat> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("exr") => Ok(ImageFormat::Exr),
            Some("png") => Ok(ImageFormat::Png),
            _ => bail!(
                "{}: unknown image format; expected an .exr or .png file",
                path.display()
            ),
        }
    }
}

/// How patches are coloured.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Shading {
    /// Radiosity interpolated across the corners patches share on one surface (the
    /// `output::smooth` module); keeps every patch in memory until the image is written.
    #[default]
    Smooth,
    /// Every patch (element) in its own flat radiosity: shows the mesh.
    Flat,
}

/// An image being rendered into memory, written to its file by [`ImageSink::finish`].
#[derive(Clone, Debug)]
pub struct ImageSink {
    path: PathBuf,
    format: ImageFormat,
    raster: Rasterizer,
    channels: Vec<String>,
    display: Display,
    /// The patches, kept for smooth shading (`None`: flat).
    store: Option<PatchStore>,
    /// Whether the framebuffer shows the smoothed values of every stored patch.
    shaded: bool,
    /// Most patches kept for smooth shading before they are shaded and dropped.
    batch: usize,
    /// The drawing index of the store's first patch (see [`Rasterizer::drawn`]).
    first: u32,
}

impl ImageSink {
    /// An image for `path` (`.exr` or `.png`, checked now so that a long solve does not end
    /// in a refusal) of `size` pixels from a checked `camera`, with `supersample x
    /// supersample` samples per pixel, for a scene of `bands` bands named `band_names`.
    pub fn new(
        path: &Path,
        camera: &Camera,
        size: Size,
        supersample: u32,
        bands: usize,
        band_names: &[String],
    ) -> anyhow::Result<Self> {
        let format = ImageFormat::of(path)?;
        let mut raster = Rasterizer::new(camera, size, supersample, bands)
            .map_err(|e| anyhow!("{}: {e}", path.display()))?;
        raster.track_owners();
        Ok(ImageSink {
            path: path.to_path_buf(),
            format,
            raster,
            channels: channel_names(bands, band_names),
            display: Display::default_for(bands, band_names),
            store: Some(PatchStore::new(bands)),
            shaded: true,
            batch: usize::MAX,
            first: 0,
        })
    }

    /// Smooth shading in batches of at most `patches` patches (at least 1): each batch is
    /// shaded, corners shared within it, and dropped once full, so that the image's memory
    /// does not grow with the scene (for solves whose memory is bounded). Patches that meet
    /// across a batch's end are shaded apart there. Default: one batch (all patches kept).
    pub fn with_batch(mut self, patches: usize) -> Self {
        self.batch = patches.max(1);
        self
    }

    /// Chooses how patches are coloured (default smooth); call before any patch arrives.
    pub fn with_shading(mut self, shading: Shading) -> Self {
        self.store = match shading {
            Shading::Smooth => {
                self.raster.track_owners();
                Some(PatchStore::new(self.raster.bands()))
            }
            Shading::Flat => {
                self.raster.stop_tracking();
                None
            }
        };
        self
    }

    /// Colours the samples of every stored patch from its smoothed corner values.
    fn shade(&mut self) {
        let Some(store) = &self.store else {
            return;
        };
        if self.shaded {
            return;
        }
        shade_all(&mut self.raster, store, self.first);
        self.shaded = true;
    }

    /// Shows `display` in the PNG (an EXR keeps every band). Default:
    /// [`Display::default_for`].
    pub fn with_display(mut self, display: impl Into<Display>) -> Self {
        self.display = display.into();
        self
    }

    /// True when the image is a PNG (whose colours are chosen bands).
    pub fn is_png(&self) -> bool {
        self.format == ImageFormat::Png
    }

    /// The image as rendered so far (linear radiance, W/m^2/sr), smoothed when shading is
    /// smooth.
    pub fn frame(&mut self) -> Frame {
        self.shade();
        self.raster.frame(self.channels.clone())
    }

    /// What the image shows (see [`super::raster::Coverage`]).
    pub fn coverage(&self) -> super::raster::Coverage {
        self.raster.coverage()
    }

    /// Why the picture is nearly black, when less than 2% of it shows a lit surface.
    pub fn nearly_black(&self) -> Option<String> {
        let c = self.coverage();
        if c.lit >= 0.02 {
            return None;
        }
        let pct = |f: f64| format!("{:.1}%", 100.0 * f);
        let mut why = format!(
            "{} is nearly black: {} of it shows a lit surface",
            self.path.display(),
            pct(c.lit)
        );
        if c.backs > 0.0 {
            why += &format!(
                ", {} the backs of one-sided polygons (they absorb and show nothing: is the camera outside a closed room?)",
                pct(c.backs)
            );
        }
        if c.empty > 0.0 {
            why += &format!(", {} nothing at all", pct(c.empty));
        }
        why += "; choose the view with --camera";
        Some(why)
    }

    /// Writes the file: a temporary name beside it, renamed into place when complete.
    pub fn finish(mut self) -> anyhow::Result<()> {
        let frame = self.frame();
        let path = &self.path;
        let tmp = temp_beside(path)?;
        let mut w = BufWriter::new(tmp);
        match self.format {
            ImageFormat::Exr => write_exr(&frame, &mut w),
            ImageFormat::Png => match &self.display {
                Display::Bands(d) => write_png(&frame, *d, &mut w),
                Display::Map(m) => {
                    let (rgb, _) = map_pixels(&frame, m);
                    write_rgb_png(frame.width, frame.height, &rgb, &mut w)
                }
            },
        }
        .map_err(|e| anyhow!("{}: {e:#}", path.display()))?;
        w.flush()
            .map_err(|e| anyhow!("{}: cannot write: {e}", path.display()))?;
        let tmp = w
            .into_inner()
            .map_err(|e| anyhow!("{}: cannot write: {}", path.display(), e.error()))?;
        persist(tmp, path)
    }
}

impl Sink for ImageSink {
    type Error = anyhow::Error;

    fn patch(&mut self, patch: &PatchResult<'_>) -> anyhow::Result<()> {
        self.raster
            .patch(patch)
            .map_err(|e| anyhow!("{}: {e}", self.path.display()))?;
        if let Some(store) = &mut self.store {
            store.push(patch);
            self.shaded = false;
            if store.len() >= self.batch {
                self.shade();
                self.store = Some(PatchStore::new(self.raster.bands()));
                self.first = self.raster.drawn();
            }
        }
        Ok(())
    }

    fn polygon(&mut self, _: &PolygonResult<'_>) -> anyhow::Result<()> {
        Ok(())
    }
}
