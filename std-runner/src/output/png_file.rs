//! An 8-bit sRGB PNG preview of a linear image.
//!
//! Operator: linear exposure, then clipping, then the sRGB transfer curve. The exposure is
//! automatic: the 99th percentile of the luminance (Rec. 709 weights) of the lit pixels maps
//! to 0.9, so the brightest 1 % may clip. Bands become display colours first (see
//! [`DisplayBands`]): by default 1 band is grey; 2 bands (PAR, NIR) are false colour, red =
//! band 1 and green = blue = band 0 (so light of equal bands is grey, band 0 alone cyan,
//! band 1 alone red, as in colour-infrared pictures); 3 bands are R, G, B; more than 3 show
//! the first three as R, G, B. `--display-bands` chooses otherwise.

use super::frame::Frame;
use anyhow::anyhow;
use std::io::Write;

/// Luminance percentile that sets the exposure.
pub const EXPOSURE_PERCENTILE: f64 = 0.99;

/// Display value the percentile luminance maps to.
pub const EXPOSURE_TARGET: f32 = 0.9;

/// Which band each display channel (red, green, blue) shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DisplayBands(pub [usize; 3]);

impl DisplayBands {
    /// The default for a scene of `bands` bands (see the module).
    pub fn default_for(bands: usize) -> Self {
        match bands {
            0 | 1 => DisplayBands([0, 0, 0]),
            2 => DisplayBands([1, 0, 0]),
            _ => DisplayBands([0, 1, 2]),
        }
    }

    /// `--display-bands`: one band (grey) or three (red, green, blue), each a band name of
    /// the scene (any case) or a band index from 0, separated by commas.
    pub fn parse(spec: &str, bands: usize, names: &[String]) -> Result<Self, String> {
        let known = || {
            let list: Vec<String> = (0..bands)
                .map(|b| match names.get(b).filter(|n| !n.is_empty()) {
                    Some(n) => format!("{b} ({n})"),
                    None => b.to_string(),
                })
                .collect();
            list.join(", ")
        };
        let band = |word: &str| -> Result<usize, String> {
            let w = word.trim();
            if let Some(b) = names
                .iter()
                .position(|n| !n.is_empty() && n.eq_ignore_ascii_case(w))
            {
                return Ok(b);
            }
            match w.parse::<usize>() {
                Ok(b) if b < bands => Ok(b),
                _ => Err(format!(
                    "--display-bands: `{w}` is not a band of this scene (its bands: {})",
                    known()
                )),
            }
        };
        let words: Vec<&str> = spec.split(',').collect();
        match words.as_slice() {
            [one] => {
                let b = band(one)?;
                Ok(DisplayBands([b, b, b]))
            }
            [r, g, b] => Ok(DisplayBands([band(r)?, band(g)?, band(b)?])),
            _ => Err(format!(
                "--display-bands: expected one band (grey) or three (red,green,blue), found `{spec}`"
            )),
        }
    }

    /// `red = nir, green = par, blue = par`, or `grey = par`.
    pub fn describe(&self, names: &[String]) -> String {
        let name = |b: usize| match names.get(b).filter(|n| !n.is_empty()) {
            Some(n) => n.clone(),
            None => format!("band {b}"),
        };
        let [r, g, b] = self.0;
        if r == g && g == b {
            format!("grey = {}", name(r))
        } else {
            format!("red = {}, green = {}, blue = {}", name(r), name(g), name(b))
        }
    }

    /// Linear display colour of one pixel.
    fn rgb(&self, px: &[f32]) -> [f32; 3] {
        self.0.map(|b| px.get(b).copied().unwrap_or(0.0))
    }
}

fn luminance([r, g, b]: [f32; 3]) -> f32 {
    0.2126 * r + 0.7152 * g + 0.0722 * b
}

/// The exposure scale: [`EXPOSURE_TARGET`] over the [`EXPOSURE_PERCENTILE`] luminance of the
/// pixels with positive luminance; 1 when no pixel is lit. With the default display bands.
pub fn exposure(frame: &Frame) -> f32 {
    exposure_with(frame, DisplayBands::default_for(frame.channels.len()))
}

/// [`exposure`] with the given display bands.
pub fn exposure_with(frame: &Frame, display: DisplayBands) -> f32 {
    let n = frame.channels.len().max(1);
    let mut lit: Vec<f32> = frame
        .data
        .chunks(n)
        .map(|px| luminance(display.rgb(px)))
        .filter(|&l| l > 0.0 && l.is_finite())
        .collect();
    if lit.is_empty() {
        return 1.0;
    }
    let k = ((lit.len() - 1) as f64 * EXPOSURE_PERCENTILE).floor() as usize;
    let (_, &mut at, _) = lit.select_nth_unstable_by(k, f32::total_cmp);
    let scale = EXPOSURE_TARGET / at;
    if scale.is_finite() { scale } else { f32::MAX }
}

/// The sRGB transfer curve of a linear value in [0, 1].
pub fn srgb_encode(v: f32) -> f32 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// 8-bit sRGB pixels (R, G, B, row by row from the top left) of the tone-mapped frame,
/// with the default display bands.
pub fn tone_map(frame: &Frame) -> Vec<u8> {
    tone_map_with(frame, DisplayBands::default_for(frame.channels.len()))
}

/// [`tone_map`] with the given display bands.
pub fn tone_map_with(frame: &Frame, display: DisplayBands) -> Vec<u8> {
    let n = frame.channels.len().max(1);
    let scale = exposure_with(frame, display);
    let mut out = Vec::with_capacity(frame.data.len() / n * 3);
    for px in frame.data.chunks(n) {
        for v in display.rgb(px) {
            let linear = (v * scale).clamp(0.0, 1.0);
            // NaN clamps to NaN and casts to 0.
            out.push((srgb_encode(linear) * 255.0 + 0.5) as u8);
        }
    }
    out
}

/// Writes the tone-mapped frame as an 8-bit RGB PNG marked as sRGB.
pub fn write_png(frame: &Frame, display: DisplayBands, out: impl Write) -> anyhow::Result<()> {
    write_rgb_png(
        frame.width,
        frame.height,
        &tone_map_with(frame, display),
        out,
    )
}

/// Writes 8-bit sRGB pixels (R, G, B, row by row from the top left) of a `width` x
/// `height` image as a PNG marked as sRGB.
pub fn write_rgb_png(width: u32, height: u32, rgb: &[u8], out: impl Write) -> anyhow::Result<()> {
    let mut encoder = png::Encoder::new(out, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
    let mut writer = encoder
        .write_header()
        .map_err(|e| anyhow!("cannot write the PNG image: {e}"))?;
    writer
        .write_image_data(rgb)
        .map_err(|e| anyhow!("cannot write the PNG image: {e}"))?;
    writer
        .finish()
        .map_err(|e| anyhow!("cannot write the PNG image: {e}"))
}
