//! JPEG photos decoded strictly: a file cut short or with image data that does not decode is an
//! error that says so, not a picture whose missing rows are grey. `image` runs zune-jpeg in its
//! lenient mode, which fills what it cannot decode and says nothing; here zune-jpeg runs in its
//! strict mode, which refuses image data that does not decode. Strict mode alone still accepts a
//! file cut inside its last row of blocks (it checks for the end of the data only between rows),
//! so the segments are walked first, to the end-of-image marker.
use std::path::Path;

use image::{DynamicImage, GrayImage, RgbImage};
use zune_core::bytestream::ZCursor;
use zune_core::colorspace::ColorSpace;
use zune_core::options::DecoderOptions;
use zune_jpeg::JpegDecoder;
use zune_jpeg::errors::DecodeErrors;

use super::FormatError;

/// Decode the JPEG `bytes` of `path`: 8-bit gray for a gray JPEG, 8-bit RGB for any other.
pub(crate) fn decode_jpeg(path: &Path, bytes: &[u8]) -> Result<DynamicImage, FormatError> {
    check_complete(bytes).map_err(|m| FormatError::new(path, m))?;
    let corrupt = |e: DecodeErrors| {
        let problem =
            format!("the JPEG's image data is corrupt (or uses a feature trgs cannot read): {e}");
        FormatError::new(path, problem)
    };
    // The headers say whether the photo is gray; the decoder's colour conversion is chosen when
    // it reads them, so the pixels come from a second decoder told the output first.
    let mut headers = JpegDecoder::new_with_options(ZCursor::new(bytes), options(ColorSpace::RGB));
    headers.decode_headers().map_err(corrupt)?;
    let gray = headers.input_colorspace() == Some(ColorSpace::Luma);
    let out = if gray { ColorSpace::Luma } else { ColorSpace::RGB };
    let mut decoder = JpegDecoder::new_with_options(ZCursor::new(bytes), options(out));
    let pixels = decoder.decode().map_err(corrupt)?;
    let (w, h) = decoder.dimensions().unwrap_or_default();
    let (w, h) = (w as u32, h as u32);
    let image = if gray {
        GrayImage::from_raw(w, h, pixels).map(DynamicImage::ImageLuma8)
    } else {
        RgbImage::from_raw(w, h, pixels).map(DynamicImage::ImageRgb8)
    };
    image.ok_or_else(|| {
        FormatError::new(path, format!("the decoded JPEG has fewer pixels than its {w}x{h}"))
    })
}

/// Strict decoding to `out`, up to JPEG's own limit of 65535 pixels a side (zune-jpeg's default
/// limit, 16384, is below what panoramas reach).
fn options(out: ColorSpace) -> DecoderOptions {
    DecoderOptions::default()
        .set_strict_mode(true)
        .set_max_width(usize::from(u16::MAX))
        .set_max_height(usize::from(u16::MAX))
        .jpeg_set_out_colorspace(out)
}

/// Walk the segments from the start-of-image marker to the end-of-image marker, skipping each
/// by its length (so that an EXIF thumbnail's own markers are not mistaken for the photo's) and
/// each scan's image data to the marker after it. A file cut short ends before the end-of-image
/// marker. What follows that marker (padding some cameras write, a second image such as a gain
/// map) is not this image's and is ignored, as every decoder does.
fn check_complete(bytes: &[u8]) -> Result<(), String> {
    let len = bytes.len();
    let cut = |place: &str| format!("the JPEG ends {place}: the file is cut short ({len} bytes)");
    // After the start-of-image marker, which the format check has seen.
    let mut at = 2;
    let mut scans = 0;
    loop {
        // Bytes between segments are tolerated here (the decoder judges them); FF bytes before a
        // marker's code are fill, which the standard allows.
        while bytes.get(at).is_some_and(|&b| b != 0xFF) {
            at += 1;
        }
        while bytes.get(at) == Some(&0xFF) {
            at += 1;
        }
        let Some(&code) = bytes.get(at) else {
            return Err(cut("before its end-of-image marker"));
        };
        let marker_at = at - 1;
        at += 1;
        match code {
            0xD9 if scans > 0 => return Ok(()),
            0xD9 => return Err("the JPEG ends (FF D9) before any image data".into()),
            // Markers without a length.
            0x00 | 0x01 | 0xD0..=0xD8 => continue,
            _ => {}
        }
        let name = segment_name(code);
        let Some(field) = bytes.get(at..at + 2) else {
            return Err(cut(&format!("inside its {name} at byte {marker_at}")));
        };
        let length = usize::from(u16::from_be_bytes([field[0], field[1]]));
        if length < 2 {
            return Err(format!(
                "the {name} at byte {marker_at} has the length {length}, less than its own \
                 length field: the file is corrupt"
            ));
        }
        at += length;
        if at > len {
            return Err(cut(&format!(
                "inside its {name} at byte {marker_at} ({length} bytes long)"
            )));
        }
        if code == 0xDA {
            scans += 1;
            at = scan_end(bytes, at)
                .ok_or_else(|| cut("inside its image data, before its end-of-image marker"))?;
            let next = bytes[at + 1];
            if !may_follow_scan(next) {
                return Err(format!(
                    "the marker FF {next:02X} at byte {at} lies inside the image data, where \
                     only the end of the image, tables or another scan may follow: the image \
                     data is corrupt"
                ));
            }
        }
    }
}

/// Where the image data that starts at `from` ends: the FF of the first marker that is neither a
/// stuffed zero (FF 00), a restart marker (FF D0-D7) nor fill (FF FF). None: the file ends first.
fn scan_end(bytes: &[u8], from: usize) -> Option<usize> {
    (from..bytes.len().saturating_sub(1))
        .find(|&i| bytes[i] == 0xFF && !matches!(bytes[i + 1], 0x00 | 0xFF | 0xD0..=0xD7))
}

/// Markers the standard allows after a scan: the end of the image, another scan, tables (Huffman,
/// arithmetic conditioning, quantisation), a restart interval, the number of lines, comments and
/// application data.
fn may_follow_scan(code: u8) -> bool {
    matches!(code, 0xD9 | 0xDA | 0xC4 | 0xCC | 0xDB | 0xDD | 0xDC | 0xFE | 0xE0..=0xEF)
}

fn segment_name(code: u8) -> String {
    let what = match code {
        0xC4 => "Huffman table",
        0xDB => "quantisation table",
        0xDA => "start-of-scan header",
        0xDD => "restart interval",
        0xFE => "comment",
        0xE0..=0xEF => "application segment",
        0xC0..=0xCF => "frame header",
        _ => "segment",
    };
    format!("{what} (FF {code:02X})")
}
