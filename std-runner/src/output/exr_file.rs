//! Linear float images as OpenEXR: one layer, one f32 channel per band, lossless run-length
//! compression. Pixel (0, 0) is the top left, as in the EXR data window.

use super::frame::Frame;
use anyhow::{Context, anyhow, bail};
use exr::prelude::{
    AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, ReadChannels,
    ReadLayers, SmallVec, WritableImage, read,
};
use std::io::{Seek, Write};
use std::path::Path;

/// Writes `frame` as a single-layer EXR with f32 channels named as the frame's channels.
pub fn write_exr(frame: &Frame, out: impl Write + Seek) -> anyhow::Result<()> {
    let n = frame.channels.len();
    if n == 0 || frame.width == 0 || frame.height == 0 {
        bail!("an EXR image needs at least one channel and one pixel");
    }
    let channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = frame
        .channels
        .iter()
        .enumerate()
        .map(|(c, name)| {
            let samples = frame.data.iter().skip(c).step_by(n).copied().collect();
            AnyChannel::new(name.as_str(), FlatSamples::F32(samples))
        })
        .collect();
    let layer = Layer::new(
        (frame.width as usize, frame.height as usize),
        LayerAttributes::default(),
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(channels),
    );
    Image::from_layer(layer)
        .write()
        // Chunks in a fixed order: the same image gives the same bytes on any machine.
        .non_parallel()
        .to_buffered(out)
        .map_err(|e| anyhow!("cannot write the EXR image: {e}"))
}

/// Reads the first layer of an EXR file (every channel, as f32), for checks and comparisons.
/// Channels come in the file's order (alphabetical).
pub fn read_exr(path: &Path) -> anyhow::Result<Frame> {
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .with_context(|| format!("{}: cannot read the EXR image", path.display()))?;
    let layer = image.layer_data;
    let (width, height) = (layer.size.width(), layer.size.height());
    let list = &layer.channel_data.list;
    let n = list.len();
    let mut data = vec![0.0f32; width * height * n];
    for (c, channel) in list.iter().enumerate() {
        for (i, v) in channel.sample_data.values_as_f32().enumerate() {
            if let Some(slot) = data.get_mut(i * n + c) {
                *slot = v;
            }
        }
    }
    Ok(Frame {
        width: u32::try_from(width).context("EXR image too wide")?,
        height: u32::try_from(height).context("EXR image too tall")?,
        channels: list.iter().map(|c| c.name.to_string()).collect(),
        data,
    })
}
