//! Linear layers to OpenEXR: one file per view with named f32 channels (`transmission.R`,
//! `depth.Z`, ...), written to a temporary file and renamed into place.
use anyhow::{Context, Result};
use exr::prelude::{
    AnyChannel, AnyChannels, FlatSamples, Image as ExrImage, SmallVec, WritableImage,
};
use std::path::Path;
use trgs_core::Image;

/// Write `layers` (name, image) as one EXR; RGB images become `name.R/G/B`, one-channel images
/// `name.Y` (or `name.Z` for a layer called "depth").
pub fn write_exr(path: &Path, layers: &[(&str, &Image<f32>)]) -> Result<()> {
    let Some((_, first)) = layers.first() else { return Ok(()) };
    let (w, h) = (first.width as usize, first.height as usize);
    let mut channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for (name, img) in layers {
        let names: &[&str] = match (img.channels, *name) {
            (3, _) => &["R", "G", "B"],
            (_, "depth") => &["Z"],
            _ => &["Y"],
        };
        for (c, suffix) in names.iter().enumerate() {
            let data: Vec<f32> =
                (0..w * h).map(|p| img.data[p * img.channels as usize + c]).collect();
            let channel = format!("{name}.{suffix}");
            channels.push(AnyChannel::new(channel.as_str(), FlatSamples::F32(data)));
        }
    }
    let image = ExrImage::from_channels((w, h), AnyChannels::sort(channels));
    let mut bytes = std::io::Cursor::new(Vec::new());
    image
        .write()
        .to_buffered(&mut bytes)
        .with_context(|| format!("encoding {}", path.display()))?;
    trgs_core::io::write_atomic(path, bytes.get_ref())?;
    Ok(())
}
