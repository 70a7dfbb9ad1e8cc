//! The photos of a capture: gathered in natural file-name order (`frame_2` before `frame_10`;
//! every n-th of a video's frames), each decoded strictly (a photo cut short is named now, not
//! after an hour of COLMAP), and written upright into the scene folder: a photo with an EXIF
//! orientation (phones store portrait shots as landscape pixels with a tag) is turned and
//! re-encoded in its own format under its own name, its EXIF kept but for the orientation (COLMAP
//! takes its focal-length prior from the EXIF), since COLMAP and trgs read pixels as stored; the
//! others are copied byte for byte.
use anyhow::{Context, Result, bail};
use image::metadata::Orientation;
use image::{DynamicImage, ImageDecoder, ImageEncoder, ImageReader, RgbImage};
use std::cmp::Ordering;
use std::path::{Path, PathBuf};
use trgs_core::io::{read_rgb8_image, write_atomic};

/// The quality of a JPEG re-encoded upright: high enough that features and training see the
/// photo, not its re-encoding.
const UPRIGHT_JPEG_QUALITY: u8 = 95;

/// The photos chosen from a folder.
#[derive(Debug)]
pub struct Chosen {
    /// How many images the folder holds.
    pub found: usize,
    pub kept: Vec<PathBuf>,
}

/// Every `every`-th image of `dir` (JPEG or PNG, by extension), in natural file-name order.
pub fn gather(dir: &Path, every: usize) -> Result<Chosen> {
    if every == 0 {
        bail!("--every 0: keep every n-th image, n at least 1");
    }
    let all = image_files(dir)?;
    if all.is_empty() {
        bail!("{}: no JPEG or PNG images in this folder{}", dir.display(), other_media_hint(dir));
    }
    let kept: Vec<PathBuf> = all.iter().step_by(every).cloned().collect();
    if kept.len() < 3 {
        bail!(
            "{}: {} images kept of {} (--every {every}): COLMAP needs at least 3",
            dir.display(),
            kept.len(),
            all.len()
        );
    }
    Ok(Chosen { found: all.len(), kept })
}

/// The JPEG and PNG files directly in `dir`, in natural name order ([`natural_order`]).
pub fn image_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let entries = std::fs::read_dir(dir)
        .with_context(|| format!("{}: cannot list the folder of photos", dir.display()))?;
    let mut files = Vec::new();
    for e in entries {
        let path = e.with_context(|| format!("listing {}", dir.display()))?.path();
        let ext = path.extension().map(|e| e.to_string_lossy().to_lowercase());
        if path.is_file() && matches!(ext.as_deref(), Some("jpg" | "jpeg" | "png")) {
            files.push(path);
        }
    }
    files.sort_by(|a, b| natural_order(&file_name(a), &file_name(b)));
    Ok(files)
}

/// Whether COLMAP, which orders images by name as plain strings, orders `files` (in natural
/// order) as they are: not when frame numbers lack zero padding (`frame_10` before `frame_2`).
pub fn names_sort_as_numbered(files: &[PathBuf]) -> bool {
    files.windows(2).all(|w| file_name(&w[0]) <= file_name(&w[1]))
}

fn file_name(p: &Path) -> String {
    p.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default()
}

/// Names compared with their runs of digits as numbers: `frame_2` before `frame_10`, as the
/// frames of a video numbered without zero padding were taken. Equal numbers with different
/// padding, and everything else, fall back to the plain comparison.
pub fn natural_order(a: &str, b: &str) -> Ordering {
    fn runs(s: &str) -> Vec<(bool, &str)> {
        let mut out = Vec::new();
        let mut start = 0;
        let bytes = s.as_bytes();
        for i in 1..=bytes.len() {
            if i == bytes.len() || bytes[i].is_ascii_digit() != bytes[start].is_ascii_digit() {
                out.push((bytes[start].is_ascii_digit(), &s[start..i]));
                start = i;
            }
        }
        out
    }
    let (ra, rb) = (runs(a), runs(b));
    for (x, y) in ra.iter().zip(&rb) {
        let order = match (x, y) {
            ((true, dx), (true, dy)) => {
                let (tx, ty) = (dx.trim_start_matches('0'), dy.trim_start_matches('0'));
                tx.len().cmp(&ty.len()).then_with(|| tx.cmp(ty))
            }
            ((_, sx), (_, sy)) => sx.cmp(sy),
        };
        if order != Ordering::Equal {
            return order;
        }
    }
    ra.len().cmp(&rb.len()).then_with(|| a.cmp(b))
}

/// What to do with the videos or HEIC photos of a folder without JPEG or PNG images.
fn other_media_hint(dir: &Path) -> String {
    let mut extensions: Vec<String> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| e.path().extension().map(|x| x.to_string_lossy().to_lowercase()))
        .collect();
    extensions.sort();
    extensions.dedup();
    let has = |names: &[&str]| extensions.iter().any(|x| names.contains(&x.as_str()));
    let mut hint = String::new();
    if !extensions.is_empty() {
        hint += &format!(" (it holds .{} files)", extensions.join(", ."));
    }
    if has(&["mp4", "mov", "m4v", "avi", "mkv", "webm"]) {
        hint += "; for a video, extract its frames first, e.g. `ffmpeg -i VIDEO -qscale:v 2 \
                 frames/frame_%04d.jpg`, then prepare frames/ with --matching sequential";
    }
    if has(&["heic", "heif"]) {
        hint += "; for HEIC photos (an iPhone's default), convert them to JPEG first, e.g. with \
                 `heif-convert` or `magick mogrify -format jpg *.HEIC`";
    }
    hint
}

/// Write `photos` upright into `images` under their own names; returns each one's upright size.
pub fn write_upright(
    photos: &[PathBuf],
    images: &Path,
    say: &mut dyn FnMut(String),
) -> Result<Vec<(u32, u32)>> {
    std::fs::create_dir_all(images).with_context(|| format!("creating {}", images.display()))?;
    let mut turned = 0;
    let mut sizes = Vec::with_capacity(photos.len());
    for photo in photos {
        let name = photo.file_name().context("a photo without a file name")?;
        let target = images.join(name);
        // Strictly, with the error naming the file (and what is wrong with it).
        let pixels = read_rgb8_image(photo)?;
        let (orientation, exif) = orientation_and_exif(photo)?;
        if orientation == Orientation::NoTransforms {
            std::fs::copy(photo, &target)
                .with_context(|| format!("copying {} to {}", photo.display(), target.display()))?;
            sizes.push((pixels.width, pixels.height));
            continue;
        }
        let rgb = RgbImage::from_raw(pixels.width, pixels.height, pixels.data)
            .context("an image whose pixels do not fill its size")?;
        let mut upright = DynamicImage::ImageRgb8(rgb);
        upright.apply_orientation(orientation);
        let upright = upright.to_rgb8();
        let bytes = encode_like(photo, &upright, exif)
            .with_context(|| format!("{}: encoding the photo upright", photo.display()))?;
        write_atomic(&target, &bytes)?;
        sizes.push(upright.dimensions());
        turned += 1;
    }
    if turned > 0 {
        say(format!(
            "photos: {turned} turned upright by their EXIF orientation (re-encoded: JPEG at \
             quality {UPRIGHT_JPEG_QUALITY}, PNG lossless; the rest of the EXIF kept)"
        ));
    }
    Ok(sizes)
}

/// What the photos stage depends on, for `prepare`'s progress file: the folder, `every`, and
/// each chosen photo's name, size and modification time (a photo replaced under its name counts
/// as a change), hashed (FNV-1a) to one line.
pub fn fingerprint(dir: &Path, every: usize, photos: &[PathBuf]) -> Result<String> {
    let folder = std::fs::canonicalize(dir).unwrap_or_else(|_| dir.to_path_buf());
    let mut text = format!("{} every {every}", folder.display());
    for photo in photos {
        let meta = std::fs::metadata(photo)
            .with_context(|| format!("{}: cannot read", photo.display()))?;
        let modified = meta
            .modified()
            .ok()
            .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
            .map_or(0, |d| d.as_nanos());
        text += &format!("|{}:{}:{modified}", file_name(photo), meta.len());
    }
    let hash = text
        .bytes()
        .fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3));
    Ok(format!("{} photos, {hash:016x}", photos.len()))
}

/// The upright sizes of `photos` as an earlier run wrote them into `images` (read from the files'
/// headers).
pub fn sizes_in(photos: &[PathBuf], images: &Path) -> Result<Vec<(u32, u32)>> {
    photos
        .iter()
        .map(|photo| {
            let name = photo.file_name().context("a photo without a file name")?;
            let written = images.join(name);
            image::image_dimensions(&written).with_context(|| {
                format!("{}: reading the size of a photo the earlier run wrote", written.display())
            })
        })
        .collect()
}

/// A photo's EXIF orientation (none: as stored) and its EXIF with the orientation cleared, for
/// the upright copy.
fn orientation_and_exif(photo: &Path) -> Result<(Orientation, Option<Vec<u8>>)> {
    let what = || format!("{}: cannot read the photo's EXIF", photo.display());
    let reader =
        ImageReader::open(photo).with_context(what)?.with_guessed_format().with_context(what)?;
    let mut decoder = reader.into_decoder().with_context(what)?;
    let Some(mut exif) = decoder.exif_metadata().with_context(what)? else {
        return Ok((Orientation::NoTransforms, None));
    };
    let orientation = Orientation::remove_from_exif_chunk(&mut exif);
    Ok((orientation.unwrap_or(Orientation::NoTransforms), Some(exif)))
}

/// `image` in the format of `photo` (PNG stays lossless, anything else is a JPEG), with `exif`.
fn encode_like(photo: &Path, image: &RgbImage, exif: Option<Vec<u8>>) -> Result<Vec<u8>> {
    let png = photo.extension().is_some_and(|e| e.eq_ignore_ascii_case("png"));
    let mut bytes = Vec::new();
    let (w, h) = image.dimensions();
    let colour = image::ExtendedColorType::Rgb8;
    if png {
        let mut encoder = image::codecs::png::PngEncoder::new(&mut bytes);
        if let Some(exif) = exif {
            encoder.set_exif_metadata(exif).map_err(image::ImageError::Unsupported)?;
        }
        encoder.write_image(image.as_raw(), w, h, colour)?;
    } else {
        let mut encoder =
            image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, UPRIGHT_JPEG_QUALITY);
        if let Some(exif) = exif {
            encoder.set_exif_metadata(exif).map_err(image::ImageError::Unsupported)?;
        }
        encoder.write_image(image.as_raw(), w, h, colour)?;
    }
    Ok(bytes)
}

#[cfg(test)]
fn encode_jpeg(image: &RgbImage) -> Result<Vec<u8>> {
    encode_like(Path::new("x.jpg"), image, None)
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::metadata::Orientation;
    use trgs_core::scratch::ScratchDir;

    #[test]
    fn numbered_names_in_the_order_they_were_taken() {
        let mut names = ["frame_10.jpg", "frame_2.jpg", "frame_1.jpg", "a.jpg", "frame_02.jpg"];
        names.sort_by(|a, b| natural_order(a, b));
        assert_eq!(names, ["a.jpg", "frame_1.jpg", "frame_02.jpg", "frame_2.jpg", "frame_10.jpg"]);
        let padded: Vec<PathBuf> =
            ["f_001.jpg", "f_002.jpg", "f_010.jpg"].map(PathBuf::from).into();
        assert!(names_sort_as_numbered(&padded));
        let bare: Vec<PathBuf> = ["f_1.jpg", "f_2.jpg", "f_10.jpg"].map(PathBuf::from).into();
        assert!(!names_sort_as_numbered(&bare));
    }

    #[test]
    fn a_folder_of_videos_or_heic_photos_says_what_to_do() {
        let dir = ScratchDir::new("prepare-other-media");
        for name in ["clip.MOV", "shot.heic"] {
            std::fs::write(dir.join(name), b"x").expect("file");
        }
        let err = gather(&dir, 1).expect_err("no JPEG or PNG").to_string();
        assert!(err.contains(".heic, .mov files"), "{err}");
        assert!(err.contains("ffmpeg") && err.contains("heif-convert"), "{err}");
    }

    #[test]
    fn every_nth_image_in_name_order() {
        let dir = ScratchDir::new("prepare-gather");
        for name in ["b.jpg", "a.PNG", "c.jpeg", "d.txt", "e.png"] {
            std::fs::write(dir.join(name), b"x").expect("file");
        }
        let all = gather(&dir, 1).expect("all");
        let names: Vec<_> = all.kept.iter().map(|p| p.file_name().map(|n| n.to_owned())).collect();
        assert_eq!(all.found, 4);
        assert_eq!(names.len(), 4);
        assert!(gather(&dir, 2).expect_err("2 of 4").to_string().contains("at least 3"));
        assert!(gather(&dir, 0).is_err());
    }

    /// A JPEG of `w x h` whose EXIF says "rotate 90 degrees clockwise to view" (orientation 6,
    /// what a phone held upright writes).
    fn jpeg_with_orientation_6(w: u32, h: u32) -> Vec<u8> {
        let pixels = RgbImage::from_fn(w, h, |x, y| image::Rgb([(x * 4) as u8, (y * 4) as u8, 90]));
        let plain = encode_jpeg(&pixels).expect("encode");
        // APP1 "Exif": a little-endian TIFF header and one IFD entry, Orientation (0x0112),
        // SHORT, count 1, value 6.
        let mut tiff = b"II*\0\x08\0\0\0".to_vec();
        tiff.extend([1, 0, 0x12, 0x01, 3, 0, 1, 0, 0, 0, 6, 0, 0, 0, 0, 0, 0, 0]);
        let payload = [b"Exif\0\0".as_slice(), &tiff].concat();
        let length = (payload.len() + 2) as u16;
        let app1 = [&[0xFF, 0xE1][..], &length.to_be_bytes(), &payload].concat();
        [&plain[..2], &app1, &plain[2..]].concat()
    }

    #[test]
    fn a_photo_with_an_exif_orientation_is_written_upright() {
        let dir = ScratchDir::new("prepare-upright");
        let (input, images) = (dir.join("in"), dir.join("images"));
        std::fs::create_dir_all(&input).expect("input");
        std::fs::write(input.join("a.jpg"), jpeg_with_orientation_6(40, 24)).expect("turned");
        let plain = encode_jpeg(&RgbImage::new(40, 24)).expect("plain");
        std::fs::write(input.join("b.jpg"), &plain).expect("plain");
        let mut lines = Vec::new();
        let photos = [input.join("a.jpg"), input.join("b.jpg")];
        let sizes = write_upright(&photos, &images, &mut |l| lines.push(l)).expect("write");
        assert_eq!(sizes, [(24, 40), (40, 24)]);
        let turned = read_rgb8_image(&images.join("a.jpg")).expect("turned photo");
        assert_eq!((turned.width, turned.height), (24, 40), "stored landscape, shown portrait");
        let (tag, exif) = orientation_and_exif(&images.join("a.jpg")).expect("EXIF");
        assert_eq!(tag, Orientation::NoTransforms);
        assert!(exif.is_some(), "the EXIF is kept (COLMAP's focal-length prior)");
        assert_eq!(std::fs::read(images.join("b.jpg")).expect("copied"), plain, "byte for byte");
        assert!(lines.iter().any(|l| l.contains("1 turned upright")), "{lines:?}");
    }

    #[test]
    fn a_photo_cut_short_is_named_before_colmap_runs() {
        let dir = ScratchDir::new("prepare-cut");
        let bytes = encode_jpeg(&RgbImage::new(64, 48)).expect("encode");
        std::fs::write(dir.join("cut.jpg"), &bytes[..bytes.len() / 3]).expect("cut");
        let err = write_upright(&[dir.join("cut.jpg")], &dir.join("images"), &mut |_| {})
            .expect_err("cut short")
            .to_string();
        assert!(err.contains("cut.jpg") && err.contains("cut short"), "{err}");
    }
}
