//! Glass masks: `glass_masks/<image file name>.png`, one 8-bit label a pixel: 0 = no reflective
//! surface, k > 0 = reflective plane k (the label `planes.json` refers to).
use std::path::{Path, PathBuf};

use image::DynamicImage;

use super::FormatError;
use super::png::{decode_png, write_png_gray};
use crate::image::Image;

/// The mask of `image_name` in `masks_dir`, if there is one: `<full image file name>.png` (e.g.
/// `0001.jpg.png`, the documented form) or `<image stem>.png` (e.g. `0001.png`, what most
/// annotation tools write).
pub fn mask_path(masks_dir: &Path, image_name: &str) -> Option<PathBuf> {
    let full = masks_dir.join(format!("{image_name}.png"));
    let stem = masks_dir.join(Path::new(image_name).with_extension("png"));
    [full, stem].into_iter().find(|p| p.is_file())
}

/// Read a label mask that must be `width x height`. Gray, gray+alpha, RGB and RGBA PNGs are
/// accepted and the first channel is taken: the values are labels, not colours, so painting tools
/// that save labels as (k, k, k) or with an alpha channel give the same mask, and no colour
/// conversion (which would blend labels) is applied.
pub fn read_glass_mask(path: &Path, width: u32, height: u32) -> Result<Image<u8>, FormatError> {
    let img = decode_png(path)?;
    if (img.width(), img.height()) != (width, height) {
        let problem = format!(
            "the mask is {}x{} but its image is {width}x{height}: masks must have the image's size",
            img.width(),
            img.height()
        );
        return Err(FormatError::new(path, problem));
    }
    let (raw, channels) = match &img {
        DynamicImage::ImageLuma8(b) => (b.as_raw(), 1),
        DynamicImage::ImageLumaA8(b) => (b.as_raw(), 2),
        DynamicImage::ImageRgb8(b) => (b.as_raw(), 3),
        DynamicImage::ImageRgba8(b) => (b.as_raw(), 4),
        other => {
            let problem = format!(
                "the mask is {:?}; expected 8-bit labels (gray, or RGB/RGBA)",
                other.color()
            );
            return Err(FormatError::new(path, problem));
        }
    };
    let data = raw.chunks_exact(channels).map(|px| px[0]).collect();
    Ok(Image { width, height, channels: 1, data })
}

/// Write a one-channel label mask as an 8-bit gray PNG.
pub fn write_glass_mask(path: &Path, mask: &Image<u8>) -> Result<(), FormatError> {
    write_png_gray(path, mask)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::test_util::{assert_mentions, scratch_dir};

    fn mask() -> Image<u8> {
        Image { width: 3, height: 2, channels: 1, data: vec![0, 1, 2, 0, 0, 7] }
    }

    #[test]
    fn round_trip_and_lookup() {
        let dir = scratch_dir("mask-rt");
        write_glass_mask(&dir.join("0001.jpg.png"), &mask()).expect("write");
        write_glass_mask(&dir.join("0002.png"), &mask()).expect("write");
        let p = mask_path(&dir, "0001.jpg").expect("full name");
        assert_eq!(read_glass_mask(&p, 3, 2).expect("read"), mask());
        assert_eq!(mask_path(&dir, "0002.jpg"), Some(dir.join("0002.png")));
        assert_eq!(mask_path(&dir, "0002.png"), Some(dir.join("0002.png")));
        assert_eq!(mask_path(&dir, "0003.png"), None);
    }

    #[test]
    fn rgb_mask_takes_first_channel() {
        let dir = scratch_dir("mask-rgb");
        let path = dir.join("m.png");
        let rgb = Image::from_u8(3, 2, 3, &[0, 9, 9, 1, 0, 0, 2, 2, 2, 0, 0, 0, 0, 5, 5, 7, 7, 7]);
        crate::io::write_png_rgb(&path, &rgb).expect("write");
        assert_eq!(read_glass_mask(&path, 3, 2).expect("read"), mask());
    }

    #[test]
    fn wrong_size_names_both_sizes() {
        let dir = scratch_dir("mask-size");
        let path = dir.join("m.png");
        write_glass_mask(&path, &mask()).expect("write");
        let err = read_glass_mask(&path, 4, 2).expect_err("size");
        assert_mentions(&err, &["m.png", "3x2", "4x2"]);
    }
}
