//! A finished image in memory: linear radiance (W/m^2/sr) per pixel and channel.

/// Pixels row by row from the top left, each pixel's channels together.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Pixels across.
    pub width: u32,
    /// Pixels down.
    pub height: u32,
    /// Channel names, one per value of a pixel.
    pub channels: Vec<String>,
    /// `width * height * channels.len()` values.
    pub data: Vec<f32>,
}

impl Frame {
    /// The channels of pixel (`x`, `y`), (0, 0) at the top left; empty outside the image.
    pub fn pixel(&self, x: u32, y: u32) -> &[f32] {
        if x >= self.width || y >= self.height {
            return &[];
        }
        let n = self.channels.len();
        let at = (y as usize * self.width as usize + x as usize) * n;
        &self.data[at..at + n]
    }

    /// Index of the channel called `name`.
    pub fn channel(&self, name: &str) -> Option<usize> {
        self.channels.iter().position(|c| c == name)
    }
}

/// Channel names for an image of `bands` bands: `Y` for one band, `R`, `G`, `B` for three,
/// otherwise the scene's band names (when there is one per band, each non-empty and
/// distinct) or `band_0`, `band_1`, ...
pub fn channel_names(bands: usize, band_names: &[String]) -> Vec<String> {
    match bands {
        1 => vec!["Y".into()],
        3 => vec!["R".into(), "G".into(), "B".into()],
        _ => {
            let usable = band_names.len() == bands
                && band_names.iter().all(|n| !n.is_empty())
                && band_names
                    .iter()
                    .enumerate()
                    .all(|(i, n)| !band_names[..i].contains(n));
            if usable {
                band_names.to_vec()
            } else {
                (0..bands).map(|b| format!("band_{b}")).collect()
            }
        }
    }
}
