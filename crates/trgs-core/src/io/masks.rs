//! Glass masks: `glass_masks/<image file name>.png`, one 8-bit label a pixel: 0 = no reflective
//! surface, k > 0 = reflective plane k (the label `planes.json` refers to).
use std::path::{Path, PathBuf};

use super::FormatError;
use super::png::{decode_label_png, write_png_gray};
use crate::image::Image;

/// The mask of `image_name` in `masks_dir`, if there is one: `<full image file name>.png` (e.g.
/// `0001.jpg.png`, the documented form) or `<image stem>.png` (e.g. `0001.png`, what most
/// annotation tools write).
pub fn mask_path(masks_dir: &Path, image_name: &str) -> Option<PathBuf> {
    let full = masks_dir.join(format!("{image_name}.png"));
    let stem = masks_dir.join(Path::new(image_name).with_extension("png"));
    [full, stem].into_iter().find(|p| p.is_file())
}

/// Read a label mask that must be `width x height`: gray (any bit depth), palette (the indices
/// are the labels) or RGB/RGBA with equal channels (painting tools that save labels as (k, k, k)
/// or with an alpha channel); see [`decode_label_png`].
pub fn read_glass_mask(path: &Path, width: u32, height: u32) -> Result<Image<u8>, FormatError> {
    let mask = decode_label_png(path)?;
    if (mask.width, mask.height) != (width, height) {
        let problem = format!(
            "the mask is {}x{} but its image is {width}x{height}: masks must have the image's size",
            mask.width, mask.height
        );
        return Err(FormatError::new(path, problem));
    }
    Ok(mask)
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

    /// A 3x2 PNG with the given colour type, bit depth, palette and packed rows.
    fn write_raw_png(
        path: &Path,
        color: png::ColorType,
        depth: png::BitDepth,
        palette: Option<Vec<u8>>,
        rows: &[u8],
    ) {
        let file = std::fs::File::create(path).expect("create");
        let mut enc = png::Encoder::new(std::io::BufWriter::new(file), 3, 2);
        enc.set_color(color);
        enc.set_depth(depth);
        if let Some(p) = palette {
            enc.set_palette(p);
        }
        enc.write_header().expect("header").write_image_data(rows).expect("data");
    }

    #[test]
    fn rgb_mask_with_equal_channels_is_read_and_colours_are_refused() {
        let dir = scratch_dir("mask-rgb");
        let path = dir.join("m.png");
        let rgb = Image::from_u8(3, 2, 3, &[0, 0, 0, 1, 1, 1, 2, 2, 2, 0, 0, 0, 0, 0, 0, 7, 7, 7]);
        crate::io::write_png_rgb(&path, &rgb).expect("write");
        assert_eq!(read_glass_mask(&path, 3, 2).expect("read"), mask());
        // A colour-coded mask (plane 2 painted green) is not silently read as label 0.
        let coloured =
            Image::from_u8(3, 2, 3, &[0, 0, 0, 1, 1, 1, 0, 128, 0, 0, 0, 0, 0, 0, 0, 7, 7, 7]);
        crate::io::write_png_rgb(&path, &coloured).expect("write");
        let err = read_glass_mask(&path, 3, 2).expect_err("colours");
        assert_mentions(&err, &["m.png", "(2, 0)", "[0, 128, 0]", "palette"]);
    }

    #[test]
    fn palette_indices_and_low_bit_values_are_the_labels() {
        let dir = scratch_dir("mask-palette");
        let path = dir.join("m.png");
        // VOC-style palette: index 1 is dark red, 2 dark green, 7 grey; the indices are labels.
        let mut palette = vec![0u8; 8 * 3];
        palette[3..6].copy_from_slice(&[128, 0, 0]);
        palette[6..9].copy_from_slice(&[0, 128, 0]);
        palette[21..24].copy_from_slice(&[128, 128, 128]);
        let rows = [0, 1, 2, 0, 0, 7];
        write_raw_png(&path, png::ColorType::Indexed, png::BitDepth::Eight, Some(palette), &rows);
        assert_eq!(read_glass_mask(&path, 3, 2).expect("palette"), mask());
        // 4-bit gray: two pixels a byte, values not scaled up (1 stays 1, not 17).
        let rows = [0x01, 0x20, 0x00, 0x70];
        write_raw_png(&path, png::ColorType::Grayscale, png::BitDepth::Four, None, &rows);
        assert_eq!(read_glass_mask(&path, 3, 2).expect("4-bit"), mask());
        // 1-bit gray: a binary mask is label 1, not 255.
        let rows = [0b0100_0000, 0b1010_0000];
        write_raw_png(&path, png::ColorType::Grayscale, png::BitDepth::One, None, &rows);
        let binary = read_glass_mask(&path, 3, 2).expect("1-bit");
        assert_eq!(binary.data, vec![0, 1, 0, 1, 0, 1]);
        // 16-bit gray: small values are labels, large ones an error.
        let rows = [0, 0, 0, 1, 0, 2, 0, 0, 0, 0, 0, 7];
        write_raw_png(&path, png::ColorType::Grayscale, png::BitDepth::Sixteen, None, &rows);
        assert_eq!(read_glass_mask(&path, 3, 2).expect("16-bit"), mask());
        let rows = [0, 0, 0, 1, 1, 0, 0, 0, 0, 0, 0, 7];
        write_raw_png(&path, png::ColorType::Grayscale, png::BitDepth::Sixteen, None, &rows);
        let err = read_glass_mask(&path, 3, 2).expect_err("label 256");
        assert_mentions(&err, &["m.png", "(2, 0)", "256"]);
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
