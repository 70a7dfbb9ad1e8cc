//! The pinhole view of a photo through a lens, chosen as COLMAP's `image_undistorter` chooses it
//! (`UndistortCamera` with its defaults: no blank pixels, scale within [0.2, 2]), and the
//! resampling of the photo (bilinear) and its glass labels (nearest) into it.
use super::{Distortion, Lens};
use crate::image::Image;
use crate::scene::Intrinsics;

/// COLMAP's `--min_scale` and `--max_scale` defaults: the pinhole image is between a fifth and
/// twice the photo's size.
const MIN_SCALE: f64 = 0.2;
const MAX_SCALE: f64 = 2.0;

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum UndistortionError {
    #[error(
        "the {model} distortion does not invert at pixel ({u:.1}, {v:.1}) of the {w}x{h} photo: \
         no pinhole direction lands there (check the distortion coefficients)"
    )]
    NoInverse { model: String, u: f64, v: f64, w: u32, h: u32 },
    #[error(
        "the {model} distortion folds inside the {w}x{h} photo: its radial profile stops \
         increasing at {radius:.3} (normalised radius; the image reaches {reach:.3}), so two \
         directions land on one pixel (check the distortion coefficients)"
    )]
    Folds { model: String, radius: f64, reach: f64, w: u32, h: u32 },
    #[error("the photo is {got_w}x{got_h}, its {model} camera expects {want_w}x{want_h}")]
    PhotoSize { model: String, got_w: u32, got_h: u32, want_w: u32, want_h: u32 },
}

/// A lens and the pinhole camera its photos are resampled into.
#[derive(Clone, Debug, PartialEq)]
pub struct Undistortion {
    pub lens: Lens,
    pub pinhole: Intrinsics,
}

impl Undistortion {
    /// Check that the lens inverts over its whole photo and choose the pinhole camera as COLMAP
    /// does: the photo's focal lengths and principal point, the size scaled (each axis on its own)
    /// so that the pinhole image shows only what the photo shows, without blank borders.
    pub fn new(lens: Lens) -> Result<Self, UndistortionError> {
        let k = lens.intrinsics;
        let (w, h) = (f64::from(k.width), f64::from(k.height));
        // Pinhole pixel of photo pixel (u, v), with the pinhole's camera matrix equal to the
        // photo's (before scaling).
        let undistort = |u: f64, v: f64| -> Result<(f64, f64), UndistortionError> {
            let (x, y) = lens
                .distortion
                .undistort((u - k.cx) / k.fx, (v - k.cy) / k.fy)
                .ok_or_else(|| UndistortionError::NoInverse {
                    model: lens.model.clone(),
                    u,
                    v,
                    w: k.width,
                    h: k.height,
                })?;
            Ok((k.fx * x + k.cx, k.fy * y + k.cy))
        };
        let mut reach: f64 = 0.0;
        let mut track = |(x, y): (f64, f64)| {
            reach = reach.max(((x - k.cx) / k.fx).hypot((y - k.cy) / k.fy));
            (x, y)
        };
        // COLMAP's border sweep: the left and right columns and the top and bottom rows of
        // pixel centres, each pixel's undistorted position.
        let (mut left, mut right, mut top, mut bottom) = (
            [f64::MAX, f64::MIN],
            [f64::MAX, f64::MIN],
            [f64::MAX, f64::MIN],
            [f64::MAX, f64::MIN],
        );
        let widen = |r: &mut [f64; 2], v: f64| {
            r[0] = r[0].min(v);
            r[1] = r[1].max(v);
        };
        for y in 0..k.height {
            let v = f64::from(y) + 0.5;
            widen(&mut left, track(undistort(0.5, v)?).0);
            widen(&mut right, track(undistort(w - 0.5, v)?).0);
        }
        for x in 0..k.width {
            let u = f64::from(x) + 0.5;
            widen(&mut top, track(undistort(u, 0.5)?).1);
            widen(&mut bottom, track(undistort(u, h - 0.5)?).1);
        }
        if let Some(radius) = lens.distortion.fold_within(reach) {
            return Err(UndistortionError::Folds {
                model: lens.model.clone(),
                radius,
                reach,
                w: k.width,
                h: k.height,
            });
        }
        let (cx, cy) = (k.cx, k.cy);
        // The scale at which the pinhole image just fits inside the photo's outline (COLMAP's
        // `max_scale_x/y` for blank_pixels = 0); the pinhole image is that scale's inverse.
        let fit_x = f64::max(cx / (cx - left[1]), (w - 0.5 - cx) / (right[0] - cx));
        let fit_y = f64::max(cy / (cy - top[1]), (h - 0.5 - cy) / (bottom[0] - cy));
        let scale_x = (1.0 / fit_x).clamp(MIN_SCALE, MAX_SCALE);
        let scale_y = (1.0 / fit_y).clamp(MIN_SCALE, MAX_SCALE);
        let pw = (scale_x * w).max(1.0) as u32;
        let ph = (scale_y * h).max(1.0) as u32;
        let pinhole = Intrinsics {
            fx: k.fx,
            fy: k.fy,
            cx: cx * f64::from(pw) / w,
            cy: cy * f64::from(ph) / h,
            width: pw,
            height: ph,
        };
        Ok(Self { lens, pinhole })
    }

    /// The same lens and pinhole for a pinhole image of `width x height`: both camera matrices
    /// scale, the photo to the size it must be downscaled to first (the distortion coefficients,
    /// in normalised coordinates, do not change).
    pub fn resized(&self, width: u32, height: u32) -> Self {
        let sx = f64::from(width) / f64::from(self.pinhole.width);
        let sy = f64::from(height) / f64::from(self.pinhole.height);
        let k = self.lens.intrinsics;
        let photo_w = ((f64::from(k.width) * sx).round() as u32).max(1);
        let photo_h = ((f64::from(k.height) * sy).round() as u32).max(1);
        Self {
            lens: Lens { intrinsics: k.resized(photo_w, photo_h), ..self.lens.clone() },
            pinhole: self.pinhole.resized(width, height),
        }
    }

    /// The size the photo must have before [`Self::warp_image`].
    pub fn photo_size(&self) -> (u32, u32) {
        (self.lens.intrinsics.width, self.lens.intrinsics.height)
    }

    /// Where the centre of pinhole pixel `(x, y)` lies in the photo (continuous pixel position),
    /// or None when it falls outside the photo.
    pub fn source(&self, x: u32, y: u32) -> Option<(f64, f64)> {
        self.source_at(f64::from(x) + 0.5, f64::from(y) + 0.5)
    }

    /// Where continuous pinhole position `(px, py)` lies in the photo, or None outside it.
    pub fn source_at(&self, px: f64, py: f64) -> Option<(f64, f64)> {
        let p = &self.pinhole;
        let k = &self.lens.intrinsics;
        let rx = (px - p.cx) / p.fx;
        let ry = (py - p.cy) / p.fy;
        let (xd, yd) = self.lens.distortion.distort(rx, ry);
        let (u, v) = (k.fx * xd + k.cx, k.fy * yd + k.cy);
        let inside = u >= 0.0 && v >= 0.0 && u <= f64::from(k.width) && v <= f64::from(k.height);
        inside.then_some((u, v))
    }

    fn check_photo(&self, width: u32, height: u32) -> Result<(), UndistortionError> {
        let (want_w, want_h) = self.photo_size();
        if (width, height) == (want_w, want_h) {
            Ok(())
        } else {
            Err(UndistortionError::PhotoSize {
                model: self.lens.model.clone(),
                got_w: width,
                got_h: height,
                want_w,
                want_h,
            })
        }
    }

    /// The photo resampled (bilinear) into the pinhole view, and which pinhole pixels have a
    /// source in the photo (1) and which do not (0; their colour is black and they must not be
    /// trained on).
    pub fn warp_image(
        &self,
        photo: &Image<f32>,
    ) -> Result<(Image<f32>, Image<u8>), UndistortionError> {
        self.check_photo(photo.width, photo.height)?;
        let (pw, ph) = (self.pinhole.width, self.pinhole.height);
        let ch = photo.channels as usize;
        let mut out = Image::<f32>::new(pw, ph, photo.channels);
        let mut valid = Image::<u8>::new(pw, ph, 1);
        let at = |x: i64, y: i64, c: usize| -> f32 {
            let xi = x.clamp(0, i64::from(photo.width) - 1) as usize;
            let yi = y.clamp(0, i64::from(photo.height) - 1) as usize;
            photo.data[(yi * photo.width as usize + xi) * ch + c]
        };
        for y in 0..ph {
            for x in 0..pw {
                let Some((u, v)) = self.source(x, y) else { continue };
                // Pixel centres sit at +0.5.
                let (fu, fv) = (u - 0.5, v - 0.5);
                let (x0, y0) = (fu.floor(), fv.floor());
                let (tx, ty) = ((fu - x0) as f32, (fv - y0) as f32);
                let (x0, y0) = (x0 as i64, y0 as i64);
                let o = (y as usize * pw as usize + x as usize) * ch;
                for c in 0..ch {
                    let top = at(x0, y0, c) * (1.0 - tx) + at(x0 + 1, y0, c) * tx;
                    let bottom = at(x0, y0 + 1, c) * (1.0 - tx) + at(x0 + 1, y0 + 1, c) * tx;
                    out.data[o + c] = top * (1.0 - ty) + bottom * ty;
                }
                valid.data[y as usize * pw as usize + x as usize] = 1;
            }
        }
        Ok((out, valid))
    }

    /// Glass labels resampled by nearest label (labels must not blend); 0 where the pinhole pixel
    /// has no source.
    pub fn warp_labels(&self, labels: &Image<u8>) -> Result<Image<u8>, UndistortionError> {
        self.check_photo(labels.width, labels.height)?;
        let (pw, ph) = (self.pinhole.width, self.pinhole.height);
        let mut out = Image::<u8>::new(pw, ph, 1);
        for y in 0..ph {
            for x in 0..pw {
                let Some((u, v)) = self.source(x, y) else { continue };
                let xi = (u.floor() as u32).min(labels.width - 1) as usize;
                let yi = (v.floor() as u32).min(labels.height - 1) as usize;
                out.data[y as usize * pw as usize + x as usize] =
                    labels.data[(yi * labels.width as usize + xi) * labels.channels as usize];
            }
        }
        Ok(out)
    }
}

impl Distortion {
    /// A short description for the loader's message ("k1 -0.28, k2 0.09, p1 0.0012, p2 -0.0009").
    pub fn describe(&self) -> String {
        let named = |names: &[&str], values: &[f64]| {
            names
                .iter()
                .zip(values)
                .filter(|(_, v)| **v != 0.0)
                .map(|(n, v)| format!("{n} {v}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        match self {
            Distortion::RadialTangential { k, p } => named(
                &["k1", "k2", "k3", "k4", "k5", "k6", "p1", "p2"],
                &[k[0], k[1], k[2], k[3], k[4], k[5], p[0], p[1]],
            ),
            Distortion::Fisheye { k } => named(&["k1", "k2", "k3", "k4"], k),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lens(distortion: Distortion, w: u32, h: u32, f: f64) -> Lens {
        Lens {
            model: "TEST".into(),
            intrinsics: Intrinsics {
                fx: f,
                fy: f,
                cx: f64::from(w) / 2.0,
                cy: f64::from(h) / 2.0,
                width: w,
                height: h,
            },
            distortion,
        }
    }

    #[test]
    fn barrel_lens_crops_and_every_pinhole_pixel_has_a_source() {
        let d = Distortion::RadialTangential { k: [-0.2, 0.0, 0.0, 0.0, 0.0, 0.0], p: [0.0; 2] };
        let u = Undistortion::new(lens(d, 64, 48, 60.0)).expect("inverts");
        // Barrel distortion: the photo's edges undistort outward, so a pinhole image without
        // blank pixels at the photo's focal length is at least as large as the photo.
        assert!(u.pinhole.width >= 64 && u.pinhole.height >= 48, "{:?}", u.pinhole);
        let mut photo = Image::<f32>::new(64, 48, 3);
        photo.data.iter_mut().for_each(|v| *v = 0.5);
        let (image, valid) = u.warp_image(&photo).expect("size matches");
        let blank = valid.data.iter().filter(|&&v| v == 0).count();
        // COLMAP's outline is measured at pixel centres; at most a border row may lack a source.
        assert!(blank <= (u.pinhole.width + u.pinhole.height) as usize, "{blank} blank pixels");
        for (i, &ok) in valid.data.iter().enumerate() {
            let c = &image.data[3 * i..3 * i + 3];
            if ok == 1 {
                assert!(c.iter().all(|&v| (v - 0.5).abs() < 1e-6));
            } else {
                assert!(c.iter().all(|&v| v == 0.0));
            }
        }
    }

    #[test]
    fn warp_follows_the_lens_and_labels_stay_labels() {
        // A photo whose value is its own pixel column: the pinhole image must read, at each
        // pixel, the column its ray lands on.
        let d = Distortion::Fisheye { k: [0.05, -0.01, 0.0, 0.0] };
        let u = Undistortion::new(lens(d, 80, 60, 50.0)).expect("inverts");
        let mut photo = Image::<f32>::new(80, 60, 1);
        for (i, v) in photo.data.iter_mut().enumerate() {
            *v = (i % 80) as f32 + 0.5;
        }
        let (image, valid) = u.warp_image(&photo).expect("size matches");
        for y in 0..u.pinhole.height {
            for x in 0..u.pinhole.width {
                let i = (y * u.pinhole.width + x) as usize;
                if let Some((su, _)) = u.source(x, y) {
                    if su > 1.0 && su < 79.0 {
                        assert!((f64::from(image.data[i]) - su).abs() < 1e-3, "pixel {x},{y}");
                    }
                    assert_eq!(valid.data[i], 1);
                }
            }
        }
        let mut labels = Image::<u8>::new(80, 60, 1);
        for (i, v) in labels.data.iter_mut().enumerate() {
            *v = if i % 80 < 40 { 1 } else { 2 };
        }
        let warped = u.warp_labels(&labels).expect("size matches");
        assert!(warped.data.iter().all(|&v| v <= 2));
        assert!(warped.data.contains(&1) && warped.data.contains(&2));
        assert!(u.warp_labels(&Image::<u8>::new(40, 30, 1)).is_err(), "wrong size is refused");
    }

    #[test]
    fn folding_lens_is_refused_with_what_went_wrong() {
        let d = Distortion::RadialTangential { k: [-0.5, 0.0, 0.0, 0.0, 0.0, 0.0], p: [0.0; 2] };
        // Corners at normalised radius (320, 240) / 200 = 2: far past the fold at 0.82.
        let err = Undistortion::new(lens(d, 640, 480, 200.0)).expect_err("folds").to_string();
        assert!(err.contains("does not invert") || err.contains("folds"), "{err}");
        assert!(err.contains("640x480"), "{err}");
    }

    #[test]
    fn resized_scales_both_cameras_together() {
        let d = Distortion::RadialTangential { k: [-0.1, 0.0, 0.0, 0.0, 0.0, 0.0], p: [0.0; 2] };
        let u = Undistortion::new(lens(d, 400, 300, 300.0)).expect("inverts");
        let half = u.resized(u.pinhole.width / 2, u.pinhole.height / 2);
        assert_eq!(half.photo_size(), (200, 150));
        // One point of the pinhole image lands on one point of the photo at both sizes.
        let sx = f64::from(half.pinhole.width) / f64::from(u.pinhole.width);
        let sy = f64::from(half.pinhole.height) / f64::from(u.pinhole.height);
        let (a, c) = u.source_at(101.0, 81.0).expect("inside");
        let (b, d) = half.source_at(101.0 * sx, 81.0 * sy).expect("inside");
        assert!((a / 2.0 - b).abs() < 1e-9 && (c / 2.0 - d).abs() < 1e-9, "{a},{c} {b},{d}");
    }
}
