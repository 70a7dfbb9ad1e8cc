//! Lens models: the distortion of COLMAP's camera models (OpenCV's formulas), its inverse, and
//! the pinhole view a photo through such a lens is resampled into ([`Undistortion`]).
//!
//! The rasteriser projects through a pinhole. A photo taken through a distorting lens is resampled
//! when it is loaded into the pinhole view COLMAP's `image_undistorter` would make of it, so that
//! nothing after the loader knows about lenses.
mod undistort;

pub use undistort::{Undistortion, UndistortionError};

use crate::scene::Intrinsics;

/// A lens's distortion in normalised camera coordinates: a ray `(x, y, 1)` of the pinhole camera
/// lands at `distort(x, y)` on the photo's normalised image plane, whose pixel is
/// `(fx x_d + cx, fy y_d + cy)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Distortion {
    /// OpenCV's radial-tangential model with its rational radial factor:
    /// `a = (1 + k1 r^2 + k2 r^4 + k3 r^6) / (1 + k4 r^2 + k5 r^4 + k6 r^6)`,
    /// `x_d = a x + 2 p1 x y + p2 (r^2 + 2 x^2)`, `y_d = a y + p1 (r^2 + 2 y^2) + 2 p2 x y`.
    /// COLMAP's SIMPLE_RADIAL (k1), RADIAL (k1, k2), OPENCV (k1, k2, p1, p2) and FULL_OPENCV (all
    /// eight) are this model with the other coefficients zero.
    RadialTangential { k: [f64; 6], p: [f64; 2] },
    /// OpenCV's fisheye model: `theta = atan(r)`, `theta_d = theta (1 + k1 theta^2 + k2 theta^4 +
    /// k3 theta^6 + k4 theta^8)` and the point scaled by `theta_d / r`. COLMAP's OPENCV_FISHEYE
    /// (k1..k4), SIMPLE_RADIAL_FISHEYE (k1) and RADIAL_FISHEYE (k1, k2).
    Fisheye { k: [f64; 4] },
}

/// Residual at which the inverse stops, in normalised coordinates (1e-9 px at a focal length of
/// 1e5 px).
const INVERSE_TOLERANCE: f64 = 1e-14;
const INVERSE_ITERATIONS: usize = 100;

impl Distortion {
    /// Whether the model moves no point (all coefficients zero).
    pub fn is_identity(&self) -> bool {
        match self {
            Distortion::RadialTangential { k, p } => k.iter().chain(p).all(|&v| v == 0.0),
            Distortion::Fisheye { .. } => false,
        }
    }

    /// Where the pinhole ray `(x, y, 1)` lands on the photo's normalised image plane.
    pub fn distort(&self, x: f64, y: f64) -> (f64, f64) {
        match *self {
            Distortion::RadialTangential { k, p } => {
                let r2 = x * x + y * y;
                let (a, _) = rational_radial(&k, r2);
                (
                    a * x + 2.0 * p[0] * x * y + p[1] * (r2 + 2.0 * x * x),
                    a * y + p[0] * (r2 + 2.0 * y * y) + 2.0 * p[1] * x * y,
                )
            }
            Distortion::Fisheye { k } => {
                let r = x.hypot(y);
                if r < 1e-300 {
                    return (x, y);
                }
                let s = fisheye_theta_d(&k, r.atan()).0 / r;
                (s * x, s * y)
            }
        }
    }

    /// The pinhole ray `(x, y)` that lands at `(xd, yd)`, or None where the model does not
    /// invert there (Newton's method does not converge, the map folds, or, for a fisheye, the
    /// direction is 90 degrees or more off the axis, which no pinhole shows).
    pub fn undistort(&self, xd: f64, yd: f64) -> Option<(f64, f64)> {
        let solution = match *self {
            Distortion::RadialTangential { k, p } => invert_radial_tangential(&k, &p, xd, yd),
            Distortion::Fisheye { k } => invert_fisheye(&k, xd, yd),
        }?;
        (solution.0.is_finite() && solution.1.is_finite()).then_some(solution)
    }

    /// The radial profile (distorted radius against the pinhole radius, along the x axis
    /// without tangential terms) is strictly increasing from the axis out to pinhole radius
    /// `r_max`: else two directions land on one pixel and the photo cannot be undistorted there.
    /// Returns the first radius where it stops increasing.
    pub fn fold_within(&self, r_max: f64) -> Option<f64> {
        const SAMPLES: usize = 4096;
        let profile = |r: f64| match *self {
            Distortion::RadialTangential { k, .. } => r * rational_radial(&k, r * r).0,
            Distortion::Fisheye { k } => fisheye_theta_d(&k, r.atan()).0,
        };
        let mut last = 0.0;
        for i in 1..=SAMPLES {
            let r = r_max * i as f64 / SAMPLES as f64;
            let v = profile(r);
            if !(v > last) {
                return Some(r);
            }
            last = v;
        }
        None
    }
}

/// The rational radial factor `a(r^2)` and its derivative with respect to `r^2`.
fn rational_radial(k: &[f64; 6], r2: f64) -> (f64, f64) {
    let num = 1.0 + r2 * (k[0] + r2 * (k[1] + r2 * k[2]));
    let den = 1.0 + r2 * (k[3] + r2 * (k[4] + r2 * k[5]));
    let dnum = k[0] + r2 * (2.0 * k[1] + 3.0 * r2 * k[2]);
    let dden = k[3] + r2 * (2.0 * k[4] + 3.0 * r2 * k[5]);
    (num / den, (dnum * den - num * dden) / (den * den))
}

/// `theta_d(theta)` of the fisheye model and its derivative.
fn fisheye_theta_d(k: &[f64; 4], theta: f64) -> (f64, f64) {
    let t2 = theta * theta;
    let poly = 1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3])));
    let dpoly = t2 * (2.0 * k[0] + t2 * (4.0 * k[1] + t2 * (6.0 * k[2] + t2 * 8.0 * k[3])));
    (theta * poly, poly + dpoly)
}

/// The residual of the radial-tangential model at `(x, y)` for target `(xd, yd)`, and its
/// Jacobian `[[dxd/dx, dxd/dy], [dyd/dx, dyd/dy]]`.
fn radial_tangential_residual(
    k: &[f64; 6],
    p: &[f64; 2],
    (x, y): (f64, f64),
    (xd, yd): (f64, f64),
) -> ((f64, f64), [f64; 4]) {
    let r2 = x * x + y * y;
    let (a, da) = rational_radial(k, r2);
    let fx = a * x + 2.0 * p[0] * x * y + p[1] * (r2 + 2.0 * x * x) - xd;
    let fy = a * y + p[0] * (r2 + 2.0 * y * y) + 2.0 * p[1] * x * y - yd;
    let cross = 2.0 * x * y * da + 2.0 * p[0] * x + 2.0 * p[1] * y;
    let j = [
        a + 2.0 * x * x * da + 2.0 * p[0] * y + 6.0 * p[1] * x,
        cross,
        cross,
        a + 2.0 * y * y * da + 6.0 * p[0] * y + 2.0 * p[1] * x,
    ];
    ((fx, fy), j)
}

/// Newton's method on the 2x2 system from the distorted point (the undistorted point of a mild
/// lens is near it), each step halved until the residual shrinks: far from the axis the full
/// step of a strong lens overshoots. At the solution the radial factor and the Jacobian's
/// determinant must be positive: past a fold of the profile a point has other preimages (one
/// mirrored through the axis), and none of them is the lens's inverse.
fn invert_radial_tangential(k: &[f64; 6], p: &[f64; 2], xd: f64, yd: f64) -> Option<(f64, f64)> {
    let target = (xd, yd);
    let tolerance = INVERSE_TOLERANCE * (1.0 + xd.abs().max(yd.abs()));
    let size = |f: (f64, f64)| f.0.abs().max(f.1.abs());
    let mut at = target;
    let (mut f, mut j) = radial_tangential_residual(k, p, at, target);
    for _ in 0..INVERSE_ITERATIONS {
        let det = j[0] * j[3] - j[1] * j[2];
        if size(f) <= tolerance {
            let radial = rational_radial(k, at.0 * at.0 + at.1 * at.1).0;
            return (det > 0.0 && radial > 0.0).then_some(at);
        }
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let step = ((j[3] * f.0 - j[1] * f.1) / det, (j[0] * f.1 - j[2] * f.0) / det);
        let mut t = 1.0;
        loop {
            let next = (at.0 - t * step.0, at.1 - t * step.1);
            let (fn_, jn) = radial_tangential_residual(k, p, next, target);
            if size(fn_) < size(f) || t < 1e-6 {
                (at, f, j) = (next, fn_, jn);
                break;
            }
            t *= 0.5;
        }
    }
    None
}

/// Newton's method on `theta_d(theta) = r_d`, which must stay increasing and below 90 degrees.
fn invert_fisheye(k: &[f64; 4], xd: f64, yd: f64) -> Option<(f64, f64)> {
    let rd = xd.hypot(yd);
    if rd < 1e-300 {
        return Some((xd, yd));
    }
    let mut theta = rd.min(1.5);
    for _ in 0..INVERSE_ITERATIONS {
        let (f, df) = fisheye_theta_d(k, theta);
        if !(df > 0.0) {
            return None;
        }
        let step = (f - rd) / df;
        theta -= step;
        if !(0.0..std::f64::consts::FRAC_PI_2).contains(&theta) {
            return None;
        }
        if step.abs() <= INVERSE_TOLERANCE * (1.0 + theta) {
            let s = theta.tan() / rd;
            return Some((s * xd, s * yd));
        }
    }
    None
}

/// A photo's own camera: its camera matrix and size, and its lens's distortion.
#[derive(Clone, Debug, PartialEq)]
pub struct Lens {
    /// COLMAP's name of the model it was read as (`"OPENCV"`, ...), for messages.
    pub model: String,
    pub intrinsics: Intrinsics,
    pub distortion: Distortion,
}

/// The camera matrix and distortion of a COLMAP camera model's parameter list. Pinhole models
/// have no distortion (None), nor do lens models whose coefficients are all zero. FOV and
/// THIN_PRISM_FISHEYE, which COLMAP's usual pipelines do not write, are refused with the list of
/// what is supported.
pub fn colmap_camera_model(
    model: &str,
    params: &[f64],
    width: u32,
    height: u32,
) -> Result<(Intrinsics, Option<Distortion>), String> {
    let intrinsics =
        |fx: f64, fy: f64, cx: f64, cy: f64| Intrinsics { fx, fy, cx, cy, width, height };
    let rt = |k: [f64; 6], p: [f64; 2]| Some(Distortion::RadialTangential { k, p });
    let (k, distortion) = match (model, params) {
        ("SIMPLE_PINHOLE", &[f, cx, cy]) => (intrinsics(f, f, cx, cy), None),
        ("PINHOLE", &[fx, fy, cx, cy]) => (intrinsics(fx, fy, cx, cy), None),
        ("SIMPLE_RADIAL", &[f, cx, cy, k1]) => {
            (intrinsics(f, f, cx, cy), rt([k1, 0.0, 0.0, 0.0, 0.0, 0.0], [0.0; 2]))
        }
        ("RADIAL", &[f, cx, cy, k1, k2]) => {
            (intrinsics(f, f, cx, cy), rt([k1, k2, 0.0, 0.0, 0.0, 0.0], [0.0; 2]))
        }
        ("OPENCV", &[fx, fy, cx, cy, k1, k2, p1, p2]) => {
            (intrinsics(fx, fy, cx, cy), rt([k1, k2, 0.0, 0.0, 0.0, 0.0], [p1, p2]))
        }
        ("FULL_OPENCV", &[fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6]) => {
            (intrinsics(fx, fy, cx, cy), rt([k1, k2, k3, k4, k5, k6], [p1, p2]))
        }
        ("OPENCV_FISHEYE", &[fx, fy, cx, cy, k1, k2, k3, k4]) => {
            (intrinsics(fx, fy, cx, cy), Some(Distortion::Fisheye { k: [k1, k2, k3, k4] }))
        }
        ("SIMPLE_RADIAL_FISHEYE", &[f, cx, cy, k1]) => {
            (intrinsics(f, f, cx, cy), Some(Distortion::Fisheye { k: [k1, 0.0, 0.0, 0.0] }))
        }
        ("RADIAL_FISHEYE", &[f, cx, cy, k1, k2]) => {
            (intrinsics(f, f, cx, cy), Some(Distortion::Fisheye { k: [k1, k2, 0.0, 0.0] }))
        }
        // A known model with the wrong count says so (COLMAP's table of counts); any other
        // model is not one trgs reads.
        (_, p) => {
            return Err(match crate::io::colmap::model_by_name(model) {
                Some((_, n)) if n != p.len() => {
                    format!("{model} takes {n} parameters, found {}", p.len())
                }
                _ => format!(
                    "the camera model {model} is not supported; trgs reads {} \
                     (undistort other models first, e.g. with `colmap image_undistorter`)",
                    read_models_list()
                ),
            });
        }
    };
    Ok((k, distortion.filter(|d| !d.is_identity())))
}

/// The COLMAP camera models [`colmap_camera_model`] reads (`prepare` refuses to map with any
/// other).
pub const READ_MODELS: [&str; 9] = [
    "SIMPLE_PINHOLE",
    "PINHOLE",
    "SIMPLE_RADIAL",
    "RADIAL",
    "OPENCV",
    "FULL_OPENCV",
    "OPENCV_FISHEYE",
    "SIMPLE_RADIAL_FISHEYE",
    "RADIAL_FISHEYE",
];

/// [`READ_MODELS`] as a list in a sentence.
pub fn read_models_list() -> String {
    let (last, rest) = READ_MODELS.split_last().expect("models");
    format!("{} and {last}", rest.join(", "))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn opencv() -> Distortion {
        Distortion::RadialTangential { k: [-0.28, 0.09, 0.0, 0.0, 0.0, 0.0], p: [0.0012, -0.0009] }
    }

    #[test]
    fn inverse_round_trips_and_keeps_the_axis() {
        for d in [opencv(), Distortion::Fisheye { k: [0.05, -0.01, 0.003, -0.0005] }] {
            assert_eq!(d.undistort(0.0, 0.0), Some((0.0, 0.0)));
            for &(x, y) in &[(0.3, -0.2), (-0.6, 0.45), (1e-9, 0.0), (0.0, -0.7)] {
                let (xd, yd) = d.distort(x, y);
                let (ux, uy) = d.undistort(xd, yd).expect("inverts");
                assert!((ux - x).abs() < 1e-12 && (uy - y).abs() < 1e-12, "{d:?} at {x}, {y}");
            }
        }
    }

    #[test]
    fn a_folding_lens_has_no_inverse_past_the_fold() {
        // Strong barrel distortion: r (1 - 0.5 r^2) peaks at r = 0.816, r_d = 0.544.
        let d = Distortion::RadialTangential { k: [-0.5, 0.0, 0.0, 0.0, 0.0, 0.0], p: [0.0; 2] };
        let fold = d.fold_within(1.0).expect("folds");
        assert!((fold - 0.8165).abs() < 1e-3, "{fold}");
        assert!(d.fold_within(0.8).is_none());
        assert!(d.undistort(0.6, 0.0).is_none(), "beyond the largest distorted radius");
        // A fisheye direction at 90 degrees or more is no pinhole ray.
        let f = Distortion::Fisheye { k: [0.0; 4] };
        assert!(f.undistort(1.6, 0.0).is_none());
        assert!(f.undistort(1.5, 0.0).is_some());
    }

    #[test]
    fn colmap_parameters_map_to_opencv_coefficients() {
        let (k, d) = colmap_camera_model(
            "FULL_OPENCV",
            &[800.0, 805.0, 640.0, 480.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8],
            1280,
            960,
        )
        .expect("valid");
        assert_eq!(
            (k.fx, k.fy, k.cx, k.cy, k.width, k.height),
            (800.0, 805.0, 640.0, 480.0, 1280, 960)
        );
        assert_eq!(
            d,
            Some(Distortion::RadialTangential { k: [0.1, 0.2, 0.5, 0.6, 0.7, 0.8], p: [0.3, 0.4] })
        );
        let (_, none) = colmap_camera_model("SIMPLE_RADIAL", &[500.0, 320.0, 240.0, 0.0], 640, 480)
            .expect("valid");
        assert_eq!(none, None, "zero distortion is a pinhole");
        let err = colmap_camera_model("OPENCV", &[1.0, 2.0], 640, 480).expect_err("count");
        assert!(err.contains("OPENCV takes 8 parameters, found 2"), "{err}");
        let err = colmap_camera_model("FOV", &[1.0; 5], 640, 480).expect_err("FOV");
        assert!(err.contains("FOV is not supported") && err.contains("OPENCV_FISHEYE"), "{err}");
    }

    #[test]
    fn every_model_prepare_may_map_with_is_read() {
        for model in READ_MODELS {
            let (_, count) = crate::io::colmap::model_by_name(model).expect("a COLMAP model");
            let mut params = vec![0.0; count];
            params[..3].copy_from_slice(&[500.0, 320.0, 240.0]);
            colmap_camera_model(model, &params, 640, 480).unwrap_or_else(|e| panic!("{e}"));
        }
        assert!(read_models_list().ends_with("SIMPLE_RADIAL_FISHEYE and RADIAL_FISHEYE"));
    }
}
