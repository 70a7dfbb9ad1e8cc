//! The photos of a capture: gathered in file-name order (every n-th of a video's frames), each
//! decoded strictly (a photo cut short is named now, not after an hour of COLMAP), and written
//! upright into the scene folder: a photo with an EXIF orientation (phones store portrait shots
//! as landscape pixels with a tag) is turned and re-encoded, since COLMAP and trgs read pixels as
//! stored; the others are copied byte for byte.
use anyhow::{Context, Result, bail};
use image::{DynamicImage, ImageDecoder, ImageReader, RgbImage};
use std::path::{Path, PathBuf};
use trgs_core::io::{read_rgb8_image, write_atomic};

/// The quality of a photo re-encoded upright: high enough that features and training see the
/// photo, not its re-encoding.
const UPRIGHT_JPEG_QUALITY: u8 = 95;

/// The photos chosen from a folder.
#[derive(Debug)]
pub struct Chosen {
    /// How many images the folder holds.
    pub found: usize,
    pub kept: Vec<PathBuf>,
}

/// Every `every`-th image of `dir` (JPEG or PNG, by extension), in file-name order.
pub fn gather(dir: &Path, every: usize) -> Result<Chosen> {
    if every == 0 {
        bail!("--every 0: keep every n-th image, n at least 1");
    }
    let all = image_files(dir)?;
    if all.is_empty() {
        bail!("{}: no JPEG or PNG images in this folder", dir.display());
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

/// The JPEG and PNG files directly in `dir`, sorted by name.
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
    files.sort();
    Ok(files)
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
        match orientation(photo)? {
            image::metadata::Orientation::NoTransforms => {
                std::fs::copy(photo, &target).with_context(|| {
                    format!("copying {} to {}", photo.display(), target.display())
                })?;
                sizes.push((pixels.width, pixels.height));
            }
            o => {
                let rgb = RgbImage::from_raw(pixels.width, pixels.height, pixels.data)
                    .context("an image whose pixels do not fill its size")?;
                let mut upright = DynamicImage::ImageRgb8(rgb);
                upright.apply_orientation(o);
                let target = target.with_extension("jpg");
                write_atomic(&target, &encode_jpeg(&upright.to_rgb8())?)?;
                sizes.push((upright.width(), upright.height()));
                turned += 1;
            }
        }
    }
    if turned > 0 {
        say(format!(
            "photos: {turned} turned upright by their EXIF orientation (re-encoded as JPEG at \
             quality {UPRIGHT_JPEG_QUALITY})"
        ));
    }
    Ok(sizes)
}

/// A photo's EXIF orientation (none: as stored).
fn orientation(photo: &Path) -> Result<image::metadata::Orientation> {
    let what = || format!("{}: cannot read the photo's orientation", photo.display());
    let reader =
        ImageReader::open(photo).with_context(what)?.with_guessed_format().with_context(what)?;
    let mut decoder = reader.into_decoder().with_context(what)?;
    decoder.orientation().with_context(what)
}

fn encode_jpeg(image: &RgbImage) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, UPRIGHT_JPEG_QUALITY)
        .encode_image(image)
        .context("encoding an upright photo")?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::metadata::Orientation;
    use trgs_core::scratch::ScratchDir;

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
        assert_eq!(orientation(&images.join("a.jpg")).expect("tag"), Orientation::NoTransforms);
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
