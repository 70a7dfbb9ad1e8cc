//! Glass masks: `glass_masks/<image file name>.png`, one 8-bit label a pixel: 0 = no reflective
//! surface, k > 0 = reflective plane k (the label `planes.json` refers to).
//!
//! A label is a value that fills a region: 0, or a value with at least 16 pixels whose four
//! neighbours all hold it (`mask_labels::MIN_INTERIOR_PIXELS`; a neighbour outside the image
//! counts as holding it). Any other value below the largest label is a soft edge: antialiasing,
//! a blurred brush, a mask re-saved from a JPEG. Its pixels go to the nearest label (the lower on
//! a tie), so a 0/255 mask with grey edges reads as 0 and 255, thresholded at 128, and the reader
//! says how many pixels it moved ([`GlassMask::soft_pixels`]). A value above every label keeps
//! its pixels (a small pane of its own), and so does every value of a mask in which nothing but 0
//! fills a region: there nothing tells a label from an edge. A mask of more than [`MAX_PLANES`]
//! labels is refused.
use std::path::{Path, PathBuf};

use super::FormatError;
use super::mask_labels::snap_soft_edges;
use super::png::{decode_label_png, write_png_gray};
use crate::image::Image;

/// The most planes a scene's glass masks may label, in one mask (checked by
/// [`read_glass_mask`]) and over a dataset (checked where trgs-train's `TrainingData` is
/// assembled). A scene has a few panes; a mask of dozens of values is a soft-edged or noisy
/// gray image, which would become a plane per value and fail much later, out of memory.
pub const MAX_PLANES: usize = 8;

/// A glass mask as read: its labels, and how many pixels of soft edges were moved to the nearest
/// label (0 for a mask painted with one value a pane).
#[derive(Clone, Debug, PartialEq)]
pub struct GlassMask {
    pub labels: Image<u8>,
    pub soft_pixels: usize,
}

/// Refuse more than [`MAX_PLANES`] distinct plane labels (`labels`, ascending, 0 left out):
/// the problem, for the caller to say where it is.
pub fn check_plane_count(labels: &[u32]) -> Result<(), String> {
    if labels.len() <= MAX_PLANES {
        return Ok(());
    }
    let mut list: Vec<String> = labels.iter().take(20).map(u32::to_string).collect();
    if labels.len() > list.len() {
        list.push("...".into());
    }
    Err(format!(
        "{} labels ({}), more than the {MAX_PLANES} planes trgs fits: a mask holds 0 for no glass \
         and k for plane k, one value painted over each pane (a photo, or a gray image with \
         shading or noise inside its panes, is not a label mask)",
        labels.len(),
        list.join(", ")
    ))
}

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
/// or with an alpha channel); see [`decode_label_png`]. Soft edges go to the nearest label and
/// more than [`MAX_PLANES`] labels are refused (the module docs say what a label is).
pub fn read_glass_mask(path: &Path, width: u32, height: u32) -> Result<GlassMask, FormatError> {
    let mut mask = decode_label_png(path, width, height)?;
    let soft_pixels = snap_soft_edges(&mut mask);
    let mut present = [false; 256];
    mask.data.iter().for_each(|&v| present[usize::from(v)] = true);
    let labels: Vec<u32> = (1..256u32).filter(|&v| present[v as usize]).collect();
    check_plane_count(&labels)
        .map_err(|m| FormatError::new(path, format!("the mask holds {m}")))?;
    Ok(GlassMask { labels: mask, soft_pixels })
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
        assert_eq!(read_glass_mask(&p, 3, 2).expect("read").labels, mask());
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
        assert_eq!(read_glass_mask(&path, 3, 2).expect("read").labels, mask());
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
        assert_eq!(read_glass_mask(&path, 3, 2).expect("palette").labels, mask());
        // 4-bit gray: two pixels a byte, values not scaled up (1 stays 1, not 17).
        let rows = [0x01, 0x20, 0x00, 0x70];
        write_raw_png(&path, png::ColorType::Grayscale, png::BitDepth::Four, None, &rows);
        assert_eq!(read_glass_mask(&path, 3, 2).expect("4-bit").labels, mask());
        // 1-bit gray: a binary mask is label 1, not 255.
        let rows = [0b0100_0000, 0b1010_0000];
        write_raw_png(&path, png::ColorType::Grayscale, png::BitDepth::One, None, &rows);
        let binary = read_glass_mask(&path, 3, 2).expect("1-bit");
        assert_eq!(binary.labels.data, vec![0, 1, 0, 1, 0, 1]);
        // 16-bit gray: small values are labels, large ones an error.
        let rows = [0, 0, 0, 1, 0, 2, 0, 0, 0, 0, 0, 7];
        write_raw_png(&path, png::ColorType::Grayscale, png::BitDepth::Sixteen, None, &rows);
        assert_eq!(read_glass_mask(&path, 3, 2).expect("16-bit").labels, mask());
        let rows = [0, 0, 0, 1, 1, 0, 0, 0, 0, 0, 0, 7];
        write_raw_png(&path, png::ColorType::Grayscale, png::BitDepth::Sixteen, None, &rows);
        let err = read_glass_mask(&path, 3, 2).expect_err("label 256");
        assert_mentions(&err, &["m.png", "(2, 0)", "256"]);
    }

    /// A 0/255 disc of radius 12 in a 40x32 mask, blurred by a 5x5 box as a painting tool's
    /// soft brush or a resize leaves it: grey values at its edge.
    fn blurred_disc() -> Image<u8> {
        let (w, h) = (40i32, 32i32);
        let inside = |x: i32, y: i32| (x - 20).pow(2) + (y - 16).pow(2) <= 144;
        let mut data = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let mut sum = 0;
                for dy in -2..=2 {
                    for dx in -2..=2 {
                        sum += if inside(x + dx, y + dy) { 255 } else { 0 };
                    }
                }
                data.push(((sum + 12) / 25) as u8);
            }
        }
        Image { width: w as u32, height: h as u32, channels: 1, data }
    }

    #[test]
    fn a_blurred_mask_reads_as_its_two_labels() {
        let dir = scratch_dir("mask-soft");
        let path = dir.join("soft.png");
        let soft = blurred_disc();
        let grey = soft.data.iter().filter(|&&v| v != 0 && v != 255).count();
        assert!(grey > 50, "the edge is soft: {grey} grey pixels");
        write_glass_mask(&path, &soft).expect("write");
        let read = read_glass_mask(&path, 40, 32).expect("read");
        assert_eq!(read.soft_pixels, grey, "every grey pixel moved");
        let mask = read.labels;
        let mut values = mask.data.clone();
        values.sort_unstable();
        values.dedup();
        assert_eq!(values, [0, 255], "thresholded at the middle");
        // Each grey pixel went to the nearer of 0 and 255.
        for (&read, &written) in mask.data.iter().zip(&soft.data) {
            assert_eq!(read, if written >= 128 { 255 } else { 0 });
        }
    }

    #[test]
    fn a_mask_of_more_labels_than_planes_is_refused() {
        let dir = scratch_dir("mask-many");
        let path = dir.join("many.png");
        // Nine flat 8x8 squares of labels 1..=9 in a row.
        let mut mask = Image::<u8>::new(72, 8, 1);
        for (i, v) in mask.data.iter_mut().enumerate() {
            *v = (i % 72 / 8 + 1) as u8;
        }
        write_glass_mask(&path, &mask).expect("write");
        let err = read_glass_mask(&path, 72, 8).expect_err("nine labels");
        assert_mentions(&err, &["many.png", "9 labels", "1, 2, 3, 4, 5, 6, 7, 8, 9", "plane k"]);
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
