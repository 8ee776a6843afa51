//! The colour-map picture of one band: every pixel's radiosity (W/m^2, the image's radiance
//! times pi) through [`super::colormap::viridis`], from 0 at the bottom of the map to a
//! round value just above the 99th percentile of the lit pixels at the top (brighter pixels
//! clip), with a labelled colour bar drawn on a black panel at the right. Pixels of zero
//! radiance (nothing there, or the unlit back of a one-sided polygon) stay black.

use super::colormap::viridis_u8;
use super::font::{HEIGHT, draw_text, text_width};
use super::frame::Frame;
use super::png_file::EXPOSURE_PERCENTILE;

/// One band shown through the colour map.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MapDisplay {
    /// The band shown.
    pub band: usize,
    /// Its name on the bar, e.g. `PAR`.
    pub name: String,
}

/// Where the bar is: its columns `x0..x1`, the top of the map at row `top` (value
/// [`Scale::top`]) and 0 at row `bottom`; the panel behind it starts at column `panel`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BarLayout {
    /// First column of the black panel.
    pub panel: u32,
    /// First column of the bar.
    pub x0: u32,
    /// Column after the bar.
    pub x1: u32,
    /// Row of the top of the map.
    pub top: u32,
    /// Row of 0.
    pub bottom: u32,
    /// Image pixels per font pixel.
    pub scale: u32,
}

/// The values the map spans (W/m^2) and its ticks.
#[derive(Clone, Debug, PartialEq)]
pub struct Scale {
    /// The value at the top of the map (0 is at the bottom).
    pub top: f64,
    /// Tick values from 0 up, each at most `top`.
    pub ticks: Vec<f64>,
    /// Decimals of the tick labels (`None`: exponent notation).
    pub decimals: Option<usize>,
}

impl Scale {
    /// A scale whose top is a round value (1, 1.2, 1.5, 2, 2.5, 3, 4, 5, 6 or 8 times a
    /// power of ten) at or above `high` (W/m^2, > 0), with 3 to 6 ticks.
    pub fn new(high: f64) -> Self {
        let high = if high.is_finite() && high > 0.0 {
            high
        } else {
            1.0
        };
        let p = 10f64.powf(high.log10().floor());
        let top = [1.0, 1.2, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0]
            .iter()
            .map(|m| m * p)
            .find(|&t| t >= high * (1.0 - 1e-9))
            .unwrap_or(10.0 * p);
        let q = 10f64.powf((top / 6.0).log10().floor());
        let step = [1.0, 2.0, 2.5, 5.0, 10.0]
            .iter()
            .map(|m| m * q)
            .find(|&s| top / s <= 6.0 + 1e-9)
            .unwrap_or(10.0 * q);
        let ticks: Vec<f64> = (0..)
            .map(|k| k as f64 * step)
            .take_while(|&v| v <= top * (1.0 + 1e-9))
            .collect();
        // The fewest decimals that write every tick exactly.
        let decimals = if !(1e-3..1e5).contains(&top) {
            None
        } else {
            (0..=6).find(|&d| {
                ticks.iter().all(|v| {
                    let back: f64 = format!("{v:.d$}").parse().unwrap_or(f64::NAN);
                    (back - v).abs() <= 1e-9 * top
                })
            })
        };
        Scale {
            top,
            ticks,
            decimals,
        }
    }

    /// A tick's label.
    pub fn label(&self, v: f64) -> String {
        match self.decimals {
            Some(d) => format!("{v:.d$}"),
            None if v == 0.0 => "0".into(),
            None => format!("{v:.1e}"),
        }
    }
}

/// The bar's place in an image of `width` x `height` pixels with `labels` (tick labels and
/// title lines), or `None` when the image is too small to hold it (the picture is then
/// drawn without a bar).
pub fn layout(width: u32, height: u32, labels: &[String], title: &[String]) -> Option<BarLayout> {
    let scale = (height / 400).max(1);
    let margin = 4 * scale;
    let bar_w = 10 * scale;
    let line = (HEIGHT + 2) * scale;
    let widest = |l: &[String]| l.iter().map(|t| text_width(t, scale)).max().unwrap_or(0);
    let inner = widest(title).max(bar_w + 3 * scale + widest(labels));
    let panel_w = inner + 2 * margin;
    let top = margin + title.len() as u32 * line + line / 2 + margin;
    let bottom = height.checked_sub(margin + line / 2 + 1)?;
    if panel_w * 3 > width || bottom < top + 4 * line {
        return None;
    }
    let panel = width - panel_w;
    Some(BarLayout {
        panel,
        x0: panel + margin,
        x1: panel + margin + bar_w,
        top,
        bottom,
        scale,
    })
}

/// The 8-bit sRGB pixels (R, G, B, row by row from the top left) of `frame`'s band
/// `map.band` through the colour map, with the colour bar; and the scale used.
pub fn map_pixels(frame: &Frame, map: &MapDisplay) -> (Vec<u8>, Scale) {
    let n = frame.channels.len().max(1);
    let pi = std::f64::consts::PI;
    let radiosity: Vec<f64> = frame
        .data
        .chunks(n)
        .map(|px| f64::from(px.get(map.band).copied().unwrap_or(0.0)) * pi)
        .collect();
    let mut lit: Vec<f64> = radiosity
        .iter()
        .copied()
        .filter(|v| *v > 0.0 && v.is_finite())
        .collect();
    let high = if lit.is_empty() {
        1.0
    } else {
        let k = ((lit.len() - 1) as f64 * EXPOSURE_PERCENTILE).floor() as usize;
        *lit.select_nth_unstable_by(k, f64::total_cmp).1
    };
    let scale = Scale::new(high);
    let mut rgb = Vec::with_capacity(radiosity.len() * 3);
    for &v in &radiosity {
        if v > 0.0 && v.is_finite() {
            rgb.extend(viridis_u8((v / scale.top) as f32));
        } else {
            rgb.extend([0, 0, 0]);
        }
    }
    draw_bar(&mut rgb, frame.width, frame.height, map, &scale);
    (rgb, scale)
}

/// The title lines above the bar: band name, quantity, unit.
pub fn title(map: &MapDisplay) -> Vec<String> {
    vec![map.name.clone(), "radiosity".into(), "W/m^2".into()]
}

/// Draws the panel, bar, ticks and labels (see [`layout`]).
fn draw_bar(rgb: &mut [u8], width: u32, height: u32, map: &MapDisplay, scale: &Scale) {
    draw_titled_bar(rgb, width, height, &title(map), scale);
}

/// The labels of `scale`'s ticks.
pub fn tick_labels(scale: &Scale) -> Vec<String> {
    scale.ticks.iter().map(|&v| scale.label(v)).collect()
}

/// Draws a black panel at the right of an 8-bit RGB image with the colour bar of `scale`,
/// its ticks and labels, under the lines of `title` (see [`layout`]); nothing when the
/// image is too small.
pub fn draw_titled_bar(rgb: &mut [u8], width: u32, height: u32, title: &[String], scale: &Scale) {
    let labels = tick_labels(scale);
    let Some(l) = layout(width, height, &labels, title) else {
        return;
    };
    let w = width as usize;
    for y in 0..height as usize {
        rgb[(y * w + l.panel as usize) * 3..(y * w + w) * 3].fill(0);
    }
    let span = f64::from(l.bottom - l.top);
    for y in l.top..=l.bottom {
        let c = viridis_u8((f64::from(l.bottom - y) / span) as f32);
        for x in l.x0..l.x1 {
            let at = (y as usize * w + x as usize) * 3;
            rgb[at..at + 3].copy_from_slice(&c);
        }
    }
    let white = [255, 255, 255];
    let s = l.scale;
    let line = (HEIGHT + 2) * s;
    for (k, t) in title.iter().enumerate() {
        let y = 4 * s + k as u32 * line;
        draw_text(rgb, width, height, l.x0.into(), y.into(), s, t, white);
    }
    for (v, text) in scale.ticks.iter().zip(&labels) {
        // A tick: a black notch cut into the bar's right third, so it does not read as a
        // minus sign before the label.
        let y = l.bottom - ((v / scale.top) * span).round() as u32;
        for x in l.x1 - (l.x1 - l.x0) / 3..l.x1 {
            for dy in 0..s {
                let at = ((y + dy).min(height - 1) as usize * w + x as usize) * 3;
                rgb[at..at + 3].fill(0);
            }
        }
        let ty = i64::from(y) - i64::from(HEIGHT * s / 2);
        draw_text(
            rgb,
            width,
            height,
            (l.x1 + 3 * s).into(),
            ty,
            s,
            text,
            white,
        );
    }
}
