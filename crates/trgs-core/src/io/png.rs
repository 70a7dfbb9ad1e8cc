//! Images: reading photos (PNG or JPEG) as RGB in [0, 1], writing RGB renders and gray label
//! images as PNG. Label images (glass masks) must be PNG: a lossy JPEG would invent labels at
//! edges. Other formats are recognised by their magic bytes so the error can say what to do.
//! Every photo is decoded strictly: a PNG or JPEG cut short or with corrupt data is an error, not
//! an image with grey or black rows (JPEG in [`super::jpeg`]).
use std::io::Cursor;
use std::path::Path;

use image::{DynamicImage, ExtendedColorType, ImageEncoder, ImageFormat, ImageReader};

use super::error::read_bytes;
use super::jpeg::decode_jpeg;
use super::{FormatError, write_atomic};
use crate::image::Image;

const PHOTO_FORMATS: &[ImageFormat] = &[ImageFormat::Png, ImageFormat::Jpeg];
const LABEL_FORMATS: &[ImageFormat] = &[ImageFormat::Png];

fn decode(path: &Path, allowed: &[ImageFormat]) -> Result<DynamicImage, FormatError> {
    let bytes = read_bytes(path)?;
    let reader = ImageReader::new(Cursor::new(&bytes))
        .with_guessed_format()
        .map_err(|e| FormatError::io(path, &e))?;
    let format = check_format(path, reader.format(), allowed)?;
    if format == ImageFormat::Jpeg {
        return decode_jpeg(path, &bytes);
    }
    reader
        .decode()
        .map_err(|e| FormatError::new(path, format!("cannot decode the {format:?} image: {e}")))
}

/// Decode a PNG of labels (a glass mask) to one u8 label a pixel, from the stored samples: a
/// palette PNG's indices (what PIL's mode "P" and VOC-style tools write), a gray PNG's values at
/// any bit depth (1, 2 and 4-bit values are not scaled up; 16-bit ones must be below 256), or an
/// RGB(A) PNG whose three channels are equal. Colours that are not labels are an error: taking one
/// channel of them would silently merge or drop planes.
///
/// The mask must be `width x height` (its image's size): that is checked on the header, before
/// the pixels are allocated, so a corrupt header cannot ask for terabytes.
pub(crate) fn decode_label_png(
    path: &Path,
    width: u32,
    height: u32,
) -> Result<Image<u8>, FormatError> {
    let bytes = read_bytes(path)?;
    let format = ImageReader::new(Cursor::new(&bytes))
        .with_guessed_format()
        .map_err(|e| FormatError::io(path, &e))?
        .format();
    check_format(path, format, LABEL_FORMATS)?;
    let bad =
        |e: &dyn std::fmt::Display| FormatError::new(path, format!("cannot decode the PNG: {e}"));
    let mut decoder = png::Decoder::new(Cursor::new(&bytes));
    // No expansion: palette indices and low-bit values are the labels themselves.
    decoder.set_transformations(png::Transformations::IDENTITY);
    let mut reader = decoder.read_info().map_err(|e| bad(&e))?;
    let header = reader.info();
    if (header.width, header.height) != (width, height) {
        let problem = format!(
            "the mask is {}x{} but its image is {width}x{height}: masks must have the image's size",
            header.width, header.height
        );
        return Err(FormatError::new(path, problem));
    }
    let size = reader.output_buffer_size().ok_or_else(|| bad(&"the image is too large"))?;
    let mut buf = vec![0u8; size];
    let info = reader.next_frame(&mut buf).map_err(|e| bad(&e))?;
    let channels = match info.color_type {
        png::ColorType::Grayscale | png::ColorType::Indexed => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
    };
    let bits = info.bit_depth as usize;
    let (w, h) = (info.width as usize, info.height as usize);
    // Sample `c` of pixel `x` in `row`, at any bit depth (big-endian, most significant bits first).
    let sample = |row: &[u8], x: usize, c: usize| -> u32 {
        let i = x * channels + c;
        match bits {
            16 => u32::from(u16::from_be_bytes([row[2 * i], row[2 * i + 1]])),
            8 => u32::from(row[i]),
            _ => {
                let bit = i * bits;
                u32::from(row[bit / 8] >> (8 - bits - bit % 8)) & ((1 << bits) - 1)
            }
        }
    };
    let mut data = Vec::with_capacity(w * h);
    for y in 0..h {
        let row = &buf[y * info.line_size..(y + 1) * info.line_size];
        for x in 0..w {
            let v = sample(row, x, 0);
            if channels >= 3 && (sample(row, x, 1) != v || sample(row, x, 2) != v) {
                let rgb = [v, sample(row, x, 1), sample(row, x, 2)];
                return Err(FormatError::new(
                    path,
                    format!(
                        "pixel ({x}, {y}) is the colour {rgb:?}: a mask holds labels (gray values, \
                         RGB with equal channels, or a palette PNG whose indices are the labels)"
                    ),
                ));
            }
            let label = u8::try_from(v).map_err(|_| {
                FormatError::new(
                    path,
                    format!("pixel ({x}, {y}) has the label {v}; labels must be below 256"),
                )
            })?;
            data.push(label);
        }
    }
    Ok(Image { width: info.width, height: info.height, channels: 1, data })
}

/// The size of a photo from its header alone (PNG or JPEG): a file cut short after its header
/// has a size, and reading its pixels is what refuses it.
pub(crate) fn image_dimensions(path: &Path) -> Result<(u32, u32), FormatError> {
    let reader = ImageReader::open(path)
        .and_then(|r| r.with_guessed_format())
        .map_err(|e| FormatError::io(path, &e))?;
    check_format(path, reader.format(), PHOTO_FORMATS)?;
    reader
        .into_dimensions()
        .map_err(|e| FormatError::new(path, format!("cannot read the image header: {e}")))
}

fn check_format(
    path: &Path,
    format: Option<ImageFormat>,
    allowed: &[ImageFormat],
) -> Result<ImageFormat, FormatError> {
    let names: Vec<String> = allowed.iter().map(|f| format!("{f:?}").to_uppercase()).collect();
    match format {
        Some(f) if allowed.contains(&f) => Ok(f),
        Some(other) => Err(FormatError::new(
            path,
            format!(
                "this is a {other:?} image, but trgs reads only {} here: convert it",
                names.join(" or ")
            ),
        )),
        None => Err(FormatError::new(
            path,
            format!("not a {} file (unrecognised image signature)", names.join(" or ")),
        )),
    }
}

/// An RGB image in [0, 1] from a PNG or JPEG: gray is repeated into three channels, 16-bit
/// samples are divided by 65535, and an alpha channel is composited over black, the background
/// training renders against (Blender scenes store their transparent background with alpha 0
/// over arbitrary colour, and their edges unpremultiplied; 3DGS composites them the same way).
pub fn read_rgb_image(path: &Path) -> Result<Image<f32>, FormatError> {
    rgb_f32(&decode(path, PHOTO_FORMATS)?, path)
}

/// A decoded photo as RGB in [0, 1].
fn rgb_f32(img: &DynamicImage, path: &Path) -> Result<Image<f32>, FormatError> {
    let (width, height) = (img.width(), img.height());
    let u8s = |v: u8| f32::from(v) / 255.0;
    let u16s = |v: u16| f32::from(v) / 65535.0;
    let data = match img {
        DynamicImage::ImageLuma8(b) => rgb_of(b.as_raw(), 1, u8s),
        DynamicImage::ImageLumaA8(b) => rgb_of(b.as_raw(), 2, u8s),
        DynamicImage::ImageRgb8(b) => rgb_of(b.as_raw(), 3, u8s),
        DynamicImage::ImageRgba8(b) => rgb_of(b.as_raw(), 4, u8s),
        DynamicImage::ImageLuma16(b) => rgb_of(b.as_raw(), 1, u16s),
        DynamicImage::ImageLumaA16(b) => rgb_of(b.as_raw(), 2, u16s),
        DynamicImage::ImageRgb16(b) => rgb_of(b.as_raw(), 3, u16s),
        DynamicImage::ImageRgba16(b) => rgb_of(b.as_raw(), 4, u16s),
        other => {
            let problem = format!("unsupported PNG colour type {:?}", other.color());
            return Err(FormatError::new(path, problem));
        }
    };
    Ok(Image { width, height, channels: 3, data })
}

/// [`read_rgb_image`] at 8 bits per sample (16-bit files rounded): a quarter of the memory, for
/// photos decoded only to be downscaled.
pub fn read_rgb8_image(path: &Path) -> Result<Image<u8>, FormatError> {
    let img = decode(path, PHOTO_FORMATS)?;
    let (width, height) = (img.width(), img.height());
    match img {
        DynamicImage::ImageRgb8(b) => Ok(Image { width, height, channels: 3, data: b.into_raw() }),
        // Gray, alpha (premultiplied as read_rgb_image does) or 16 bits: through f32, rounded.
        other => Ok(rgb_f32(&other, path)?.quantised()),
    }
}

/// Interleaved samples with `channels` per pixel to RGB: gray repeated, alpha dropped.
fn rgb_of<T: Copy>(raw: &[T], channels: usize, scale: impl Fn(T) -> f32) -> Vec<f32> {
    let mut out = Vec::with_capacity(raw.len() / channels * 3);
    for px in raw.chunks_exact(channels) {
        let rgb = if channels < 3 { [px[0]; 3] } else { [px[0], px[1], px[2]] };
        // Gray+alpha and RGBA carry alpha last.
        let alpha = if channels.is_multiple_of(2) { scale(px[channels - 1]) } else { 1.0 };
        out.extend(rgb.map(|v| scale(v) * alpha));
    }
    out
}

/// Write an RGB image in [0, 1] as an 8-bit PNG (clamped, rounded to nearest).
pub fn write_png_rgb(path: &Path, image: &Image<f32>) -> Result<(), FormatError> {
    check_layout(path, image.width, image.height, image.channels, image.data.len(), 3)?;
    encode(path, &image.to_u8(), image.width, image.height, ExtendedColorType::Rgb8)
}

/// Write an RGB image in [0, 1] as a JPEG of `quality` (1-100), as a camera writes its photos.
pub fn write_jpeg_rgb(path: &Path, image: &Image<f32>, quality: u8) -> Result<(), FormatError> {
    check_layout(path, image.width, image.height, image.channels, image.data.len(), 3)?;
    let mut jpeg = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut jpeg, quality.clamp(1, 100))
        .write_image(&image.to_u8(), image.width, image.height, ExtendedColorType::Rgb8)
        .map_err(|e| FormatError::new(path, format!("cannot encode the JPEG: {e}")))?;
    write_atomic(path, &jpeg)
}

/// Write an 8-bit RGB image (e.g. a plot) as a PNG.
pub fn write_png_rgb8(path: &Path, image: &Image<u8>) -> Result<(), FormatError> {
    check_layout(path, image.width, image.height, image.channels, image.data.len(), 3)?;
    encode(path, &image.data, image.width, image.height, ExtendedColorType::Rgb8)
}

/// Write a one-channel 8-bit image (e.g. a label mask) as a gray PNG.
pub fn write_png_gray(path: &Path, image: &Image<u8>) -> Result<(), FormatError> {
    check_layout(path, image.width, image.height, image.channels, image.data.len(), 1)?;
    encode(path, &image.data, image.width, image.height, ExtendedColorType::L8)
}

/// The encoder panics on a buffer of the wrong length; refuse it with an error instead.
fn check_layout(
    path: &Path,
    w: u32,
    h: u32,
    c: u32,
    len: usize,
    want: u32,
) -> Result<(), FormatError> {
    if c != want {
        return Err(FormatError::new(
            path,
            format!("cannot write a {c}-channel image as {want}-channel PNG"),
        ));
    }
    let expected = w as usize * h as usize * c as usize;
    if len != expected || w == 0 || h == 0 {
        let problem = format!(
            "image of {w}x{h}x{c} has {len} samples (expected {expected}, and a nonzero size)"
        );
        return Err(FormatError::new(path, problem));
    }
    Ok(())
}

fn encode(
    path: &Path,
    data: &[u8],
    w: u32,
    h: u32,
    color: ExtendedColorType,
) -> Result<(), FormatError> {
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(data, w, h, color)
        .map_err(|e| FormatError::new(path, format!("cannot encode the PNG: {e}")))?;
    write_atomic(path, &png)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::test_util::{assert_mentions, scratch_dir};

    #[test]
    fn jpeg_photos_read_back_close_to_what_was_written() {
        let dir = scratch_dir("jpeg-rgb");
        let mut img = Image::<f32>::new(32, 24, 3);
        for (i, v) in img.data.iter_mut().enumerate() {
            *v = ((i / 3) % 32) as f32 / 31.0;
        }
        let path = dir.join("a.jpg");
        write_jpeg_rgb(&path, &img, 95).expect("write");
        let back = read_rgb8_image(&path).expect("read").to_f32();
        let psnr = crate::metrics::psnr(&back, &img).expect("same size");
        assert!(psnr > 35.0, "{psnr} dB");
    }

    #[test]
    fn rgb_round_trip_is_exact_at_8_bits() {
        let dir = scratch_dir("png-rgb");
        let data = (0..4 * 3 * 3).map(|i| (i * 7 % 256) as u8).collect::<Vec<_>>();
        let img = Image::from_u8(4, 3, 3, &data);
        let path = dir.join("a.png");
        write_png_rgb(&path, &img).expect("write");
        assert_eq!(read_rgb_image(&path).expect("read"), img);
        assert_eq!(image_dimensions(&path).expect("dims"), (4, 3));
    }

    #[test]
    fn gray_and_alpha_expand_to_rgb() {
        let dir = scratch_dir("png-expand");
        let path = dir.join("g.png");
        write_png_gray(&path, &Image { width: 2, height: 1, channels: 1, data: vec![0, 255] })
            .expect("write");
        let img = read_rgb_image(&path).expect("read");
        assert_eq!(img.data, [0.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
        // Alpha composites over black: transparent is black whatever colour it stores, opaque
        // keeps its colour, and half keeps half.
        let path = dir.join("rgba.png");
        let pixels = [10, 20, 30, 0, 10, 20, 30, 255, 200, 100, 50, 128];
        encode(&path, &pixels, 3, 1, ExtendedColorType::Rgba8).expect("write");
        assert_eq!(
            read_rgb_image(&path).expect("read").to_u8(),
            [0, 0, 0, 10, 20, 30, 100, 50, 25]
        );
        let path = dir.join("ga.png");
        encode(&path, &[200, 0, 200, 255], 2, 1, ExtendedColorType::La8).expect("write");
        assert_eq!(read_rgb_image(&path).expect("read").to_u8(), [0, 0, 0, 200, 200, 200]);
    }

    #[test]
    fn jpeg_photos_are_read() {
        let dir = scratch_dir("png-jpeg-ok");
        let path = dir.join("photo.jpg");
        let pixels: Vec<u8> = (0..8 * 6).flat_map(|i| [200u8, 100, (i * 5) as u8]).collect();
        let mut bytes = Vec::new();
        image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, 100)
            .write_image(&pixels, 8, 6, ExtendedColorType::Rgb8)
            .expect("encode");
        std::fs::write(&path, &bytes).expect("write");
        let img = read_rgb_image(&path).expect("read jpeg");
        assert_eq!((img.width, img.height, img.channels), (8, 6, 3));
        let back = img.to_u8();
        let worst = back.iter().zip(&pixels).map(|(a, b)| a.abs_diff(*b)).max().unwrap_or(0);
        assert!(worst <= 8, "quality-100 JPEG differs by {worst}");
        assert_eq!(image_dimensions(&path).expect("dims"), (8, 6));
    }

    #[test]
    fn jpeg_and_garbage_are_named() {
        let dir = scratch_dir("png-jpeg");
        let path = dir.join("a.jpg");
        std::fs::write(&path, [0xff, 0xd8, 0xff, 0xe0, 0, 16, b'J', b'F', b'I', b'F', 0])
            .expect("write");
        // A truncated JPEG is recognised and refused, naming the file.
        assert_mentions(&read_rgb_image(&path).expect_err("jpeg"), &["a.jpg", "cut short"]);
        // A JPEG is not accepted as a label image.
        assert_mentions(
            &decode_label_png(&path, 1, 1).expect_err("jpeg mask"),
            &["a.jpg", "only PNG"],
        );
        std::fs::write(&path, b"hello").expect("write");
        assert_mentions(&read_rgb_image(&path).expect_err("junk"), &["a.jpg", "not a PNG"]);
        let missing = dir.join("missing.png");
        assert_mentions(&read_rgb_image(&missing).expect_err("missing"), &["missing.png"]);
    }

    /// A 64x48 photo with texture (a gradient and noise), as a camera's JPEG holds: enough
    /// image data that a cut lands inside it.
    fn textured_jpeg(path: &Path) -> Vec<u8> {
        let mut rng = crate::rng::Rng::new(61);
        let mut img = Image::<f32>::new(64, 48, 3);
        for (i, v) in img.data.iter_mut().enumerate() {
            let (x, y) = ((i / 3) % 64, i / 3 / 64);
            *v = (0.5 * (x + y) as f32 / 110.0 + 0.5 * rng.uniform() as f32).min(1.0);
        }
        write_jpeg_rgb(path, &img, 90).expect("write the JPEG");
        std::fs::read(path).expect("read the JPEG back")
    }

    /// Where the first start-of-scan marker (FF DA) is.
    fn start_of_scan(jpeg: &[u8]) -> usize {
        jpeg.windows(2).position(|w| w == [0xFF, 0xDA]).expect("a start of scan")
    }

    #[test]
    fn a_cut_short_jpeg_is_refused_naming_the_file() {
        let dir = scratch_dir("jpeg-cut");
        let whole = textured_jpeg(&dir.join("whole.jpg"));
        assert_eq!(read_rgb8_image(&dir.join("whole.jpg")).expect("whole").width, 64);
        let cuts = [("scan40.jpg", start_of_scan(&whole) + 40), ("third.jpg", whole.len() / 3)];
        for (name, cut) in cuts {
            let path = dir.join(name);
            std::fs::write(&path, &whole[..cut]).expect("write");
            let size = format!("({cut} bytes)");
            assert_mentions(&read_rgb_image(&path).expect_err(name), &[name, "cut short", &size]);
            assert_mentions(&read_rgb8_image(&path).expect_err(name), &[name, "cut short"]);
        }
        // Cut a few bytes before its end, inside the last row of blocks.
        let path = dir.join("tail.jpg");
        std::fs::write(&path, &whole[..whole.len() - 6]).expect("write");
        assert_mentions(&read_rgb8_image(&path).expect_err("tail"), &["tail.jpg", "cut short"]);
    }

    #[test]
    fn a_jpeg_with_corrupt_image_data_is_refused() {
        let dir = scratch_dir("jpeg-corrupt");
        let mut bytes = textured_jpeg(&dir.join("a.jpg"));
        // Sixteen one bits (stuffed as FF 00) in the middle of the scan: no Huffman table has a
        // code of sixteen ones, so this cannot be read as image data.
        let at = start_of_scan(&bytes) + 200;
        bytes.splice(at..at + 16, [0xFF, 0x00].repeat(8));
        let path = dir.join("corrupt.jpg");
        std::fs::write(&path, &bytes).expect("write");
        assert_mentions(&read_rgb8_image(&path).expect_err("corrupt"), &["corrupt.jpg", "corrupt"]);
        // A marker that may not follow image data, inside it.
        let mut bytes = textured_jpeg(&dir.join("b.jpg"));
        let at = start_of_scan(&bytes) + 200;
        bytes.splice(at..at + 2, [0xFF, 0xC0]);
        std::fs::write(&path, &bytes).expect("write");
        assert_mentions(&read_rgb8_image(&path).expect_err("marker"), &["corrupt.jpg", "FF C0"]);
    }

    #[test]
    fn a_jpeg_with_metadata_and_bytes_after_its_end_reads() {
        let dir = scratch_dir("jpeg-extra");
        let plain = textured_jpeg(&dir.join("plain.jpg"));
        let expected = read_rgb8_image(&dir.join("plain.jpg")).expect("plain");
        // An APP1 (EXIF) segment holding a thumbnail with its own end-of-image marker, after the
        // start-of-image marker, and padding after the end, as cameras write.
        let thumbnail = [b"Exif\0\0".as_slice(), &[0xFF, 0xD8, 1, 2, 3, 0xFF, 0xD9]].concat();
        let length = (thumbnail.len() + 2) as u16;
        let mut bytes = vec![0xFF, 0xD8, 0xFF, 0xE1];
        bytes.extend(length.to_be_bytes());
        bytes.extend(&thumbnail);
        bytes.extend(&plain[2..]);
        bytes.extend([0u8; 300]);
        let path = dir.join("camera.jpg");
        std::fs::write(&path, &bytes).expect("write");
        assert_eq!(read_rgb8_image(&path).expect("camera JPEG"), expected);
        assert_eq!(image_dimensions(&path).expect("size"), (64, 48));
    }

    #[test]
    fn bad_layout_is_refused_not_panicking() {
        let dir = scratch_dir("png-layout");
        let img = Image { width: 2, height: 2, channels: 3, data: vec![0.0; 5] };
        assert_mentions(
            &write_png_rgb(&dir.join("x.png"), &img).expect_err("short"),
            &["x.png", "5 samples"],
        );
    }

    /// CRC-32 (ISO-HDLC, PNG's) of `bytes`, to write a valid chunk by hand.
    fn crc32(bytes: &[u8]) -> u32 {
        let mut c = !0u32;
        for &b in bytes {
            c ^= u32::from(b);
            for _ in 0..8 {
                c = if c & 1 == 1 { 0xedb8_8320 ^ (c >> 1) } else { c >> 1 };
            }
        }
        !c
    }

    #[test]
    fn a_mask_of_another_size_is_refused_before_its_pixels_are_read() {
        let dir = scratch_dir("png-mask-size");
        let path = dir.join("m.png");
        write_png_gray(&path, &Image { width: 4, height: 3, channels: 1, data: vec![1; 12] })
            .expect("write");
        assert_eq!(decode_label_png(&path, 4, 3).expect("same size").data, vec![1; 12]);
        assert_mentions(
            &decode_label_png(&path, 5, 3).expect_err("wrong size"),
            &["m.png", "4x3", "5x3"],
        );
        // A header that claims 60,000,000 x 2,147,483,647 pixels, its CRC made valid: refused
        // on the header, not by asking for 10^17 bytes.
        let mut bytes = std::fs::read(&path).expect("read");
        let ihdr = 8 + 4; // signature, then the chunk's length
        assert_eq!(&bytes[ihdr..ihdr + 4], b"IHDR");
        bytes[ihdr + 4..ihdr + 8].copy_from_slice(&60_000_000u32.to_be_bytes());
        bytes[ihdr + 8..ihdr + 12].copy_from_slice(&2_147_483_647u32.to_be_bytes());
        let crc = crc32(&bytes[ihdr..ihdr + 4 + 13]);
        bytes[ihdr + 17..ihdr + 21].copy_from_slice(&crc.to_be_bytes());
        std::fs::write(&path, &bytes).expect("write");
        assert_mentions(
            &decode_label_png(&path, 4, 3).expect_err("huge header"),
            &["m.png", "60000000x2147483647", "4x3"],
        );
    }
}
