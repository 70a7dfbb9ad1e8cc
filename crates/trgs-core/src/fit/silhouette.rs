//! Refining a fitted rectangle against the glass masks themselves.
//!
//! The RANSAC fit ([`super::fit_rectangle`]) sees the Gaussians in a band around the mask
//! outline, and around a real pane those lie on its frame: the fitted plane is the frame's front
//! face, a few centimetres in front of the glass, and the rectangle is the frame's outer edge.
//! The masks say where the glass itself is: in every annotated view, the rectangle must cover the
//! view's mask pixels of its label and little else. [`refine_to_masks`] moves the rectangle
//! (offset along the normal, in-plane shift and turn, width and height) to the best such
//! agreement over all annotated views. The normal stays as fitted: the frame's face is parallel
//! to the glass, and a mask's outline pins the tilt only weakly (a walk-by at one height does
//! not pin the pitch at all), so freeing it let a pixel's worth of disagreement between masks
//! and rectangle turn the normal by a degree or more. Pixels where something in front hides the glass are
//! unlabelled and cost little (they count as [`SilhouetteSettings::outside_weight`]); a
//! labelled pixel the rectangle misses costs one.
use glam::{DMat3, DVec3};

use crate::Image;
use crate::scene::{Camera, ReflectionPlane};

/// Settings of [`refine_to_masks`].
#[derive(Clone, Debug, PartialEq)]
pub struct SilhouetteSettings {
    /// Cost of an unlabelled pixel inside the rectangle, against 1 for a labelled pixel outside.
    /// Below 1 because an object in front of the glass leaves it unlabelled.
    pub outside_weight: f64,
    /// Width in pixels of the soft edge that makes the cost smooth in the parameters.
    pub edge_px: f64,
    /// Margin around each view's mask in which unlabelled pixels are counted, as a fraction of
    /// the mask's bounding-box size (at least 4 pixels).
    pub margin: f64,
    /// Largest accepted change: offset along the normal and in-plane shift as a fraction of the
    /// rectangle's size (the square root of its area), and the factor on width and height.
    pub max_shift: f64,
    pub max_scale: f64,
    /// Cost evaluations of the pattern search at most.
    pub max_evaluations: usize,
    /// Keep the plane's offset along its normal: fit the rectangle within its plane only.
    pub hold_offset: bool,
}

impl Default for SilhouetteSettings {
    fn default() -> Self {
        Self {
            outside_weight: 0.25,
            edge_px: 0.5,
            margin: 0.15,
            max_shift: 0.25,
            max_scale: 1.5,
            max_evaluations: 4000,
            hold_offset: false,
        }
    }
}

/// What [`refine_to_masks`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct SilhouetteFit {
    pub plane: ReflectionPlane,
    /// The cost (labelled pixels missed plus weighted unlabelled pixels covered, each view's
    /// divided by its labelled pixel count, summed over views) before and after.
    pub cost_before: f64,
    pub cost_after: f64,
    /// How far the refined rectangle can move along its normal before its outline moves by a
    /// pixel across itself in the annotated view where it moves most: how closely the masks pin
    /// the plane's offset (infinite when no view shows an edge).
    pub offset_resolution: f64,
}

/// One annotated view's pixels near its mask: world-space ray and whether the pixel is labelled.
struct ViewPixels {
    origin: DVec3,
    rays: Vec<(DVec3, bool)>,
    focal: f64,
    labelled: f64,
}

/// `plane` moved to agree best with the pixels of `label` in `views` (camera, label image). None
/// when no view holds the label. The plane's front side (its normal) and material are kept. A
/// result beyond the [`SilhouetteSettings`] limits is refused (None), since then the masks and
/// the fit disagree about which rectangle this is; so is a search that goes well beyond them,
/// when it does ([`SEARCH_SLACK`]).
pub fn refine_to_masks(
    plane: &ReflectionPlane,
    views: &[(&Camera, &Image<u8>)],
    label: u8,
    settings: &SilhouetteSettings,
) -> Option<SilhouetteFit> {
    let (cameras, pixels): (Vec<&Camera>, Vec<ViewPixels>) =
        crate::parallel::map_in_order(views, |(c, m)| {
            Some((*c, view_pixels(c, m, label, settings.margin)?))
        })
        .into_iter()
        .flatten()
        .unzip();
    if pixels.is_empty() {
        return None;
    }
    let size = (plane.width * plane.height).sqrt();
    let start = Params::default();
    // Initial steps: 2% of the size for lengths, 2% for the log sizes, about 0.6 degrees for
    // the turn; the search halves them down to 1/256.
    let offset_step = if settings.hold_offset { 0.0 } else { 0.02 * size };
    let steps = [offset_step, 0.02 * size, 0.02 * size, 0.02, 0.02, 0.01];
    let cost = |p: &Params| total_cost(&p.apply(plane), &pixels, settings);
    let on_course = |p: &Params| within_limits(plane, &p.apply(plane), settings, SEARCH_SLACK);
    let cost_before = cost(&start);
    let (best, cost_after) =
        pattern_search(start, steps, settings.max_evaluations, &cost, &on_course)?;
    let moved = best.apply(plane);
    if !within_limits(plane, &moved, settings, 0.0) {
        return None;
    }
    let offset_resolution = offset_resolution(&moved, &cameras);
    Some(SilhouetteFit { plane: moved, cost_before, cost_after, offset_resolution })
}

/// How far beyond the [`SilhouetteSettings`] limits the search may go before it is refused, in
/// fractions of the size (shift) and in log size (scale): five of its first steps. The compass
/// search moves one coordinate a step at a time, so on its way to a result within the limits
/// it can overshoot a coordinate by a step and cross them (the shift limit is on the length of
/// a move along three coordinates); it should not be stopped there.
const SEARCH_SLACK: f64 = 0.1;

/// Whether `moved` is within the [`SilhouetteSettings`] limits of a move from `plane`, widened
/// by `slack` (added to the shift, and to the log of the scale).
fn within_limits(
    plane: &ReflectionPlane,
    moved: &ReflectionPlane,
    s: &SilhouetteSettings,
    slack: f64,
) -> bool {
    let size = (plane.width * plane.height).sqrt();
    let shift = (moved.centre - plane.centre).length() / size;
    let scale = (moved.width / plane.width).max(moved.height / plane.height);
    let shrink = (plane.width / moved.width).max(plane.height / moved.height);
    let most_scale = s.max_scale * slack.exp();
    shift <= s.max_shift + slack && scale <= most_scale && shrink <= most_scale
}

/// How far `plane` can move along its normal before some stretch of its outline in view of one
/// of `cameras` moves a pixel across itself (the motion along an edge leaves a mask as it is).
/// Measured by a small step at points along each edge.
fn offset_resolution(plane: &ReflectionPlane, cameras: &[&Camera]) -> f64 {
    const POINTS_PER_EDGE: usize = 16;
    let step = 1e-4 * (plane.width * plane.height).sqrt();
    let n = plane.unit_normal();
    let corners = plane.corners();
    // Pixels the outline moves across itself per unit of offset, at most.
    let mut rate = 0.0f64;
    for camera in cameras {
        for k in 0..4 {
            let (a, b) = (corners[k], corners[(k + 1) % 4]);
            let along = (b - a).normalize() * step;
            for i in 0..POINTS_PER_EDGE {
                let p = a + (b - a) * ((i as f64 + 0.5) / POINTS_PER_EDGE as f64);
                let (Some(u), Some(moved), Some(ahead)) = (
                    camera.image_point(p),
                    camera.project(p + n * step),
                    camera.project(p + along),
                ) else {
                    continue;
                };
                let Some(edge) = (ahead - u).try_normalize() else { continue };
                let across = (moved - u) - edge * (moved - u).dot(edge);
                rate = rate.max(across.length() / step);
            }
        }
    }
    if rate > 0.0 { 1.0 / rate } else { f64::INFINITY }
}

/// Offsets from the starting plane: along the normal, along the axis and the bitangent, log
/// width and height, turn about the normal.
#[derive(Clone, Copy, Debug, Default)]
struct Params([f64; 6]);

impl Params {
    fn apply(&self, plane: &ReflectionPlane) -> ReflectionPlane {
        let [dn, dt, db, lw, lh, turn] = self.0;
        let (n, t, b) = (plane.unit_normal(), plane.axis, plane.bitangent());
        let mut out = *plane;
        out.centre = plane.centre + n * dn + t * dt + b * db;
        out.axis = DMat3::from_axis_angle(n, turn) * t;
        out.width = plane.width * lw.exp();
        out.height = plane.height * lh.exp();
        out.orthogonalise_axis();
        out
    }
}

/// Compass search: try each coordinate's step both ways, keep any improvement, halve the steps
/// when none improves. Derivative-free and monotone, which suits a cost summed over pixels;
/// no optimisation crate is needed for six parameters.
///
/// None as soon as an improvement lies outside `within` (or the start does): the search is then
/// on its way to a rectangle the limits refuse. Its steps never grow, so from a start far from
/// the masks' rectangle it would otherwise spend the whole evaluation budget getting there
/// (the likely cause of the slow plane initialisation that docs/captures.md records).
fn pattern_search(
    start: Params,
    mut steps: [f64; 6],
    max_evaluations: usize,
    cost: &impl Fn(&Params) -> f64,
    within: &impl Fn(&Params) -> bool,
) -> Option<(Params, f64)> {
    if !within(&start) {
        return None;
    }
    let mut best = start;
    let mut best_cost = cost(&best);
    let mut evaluations = 1;
    let mut halvings = 0;
    while halvings < 8 && evaluations < max_evaluations {
        let mut improved = false;
        // A coordinate held (a step of zero) is never tried.
        for k in (0..6).filter(|&k| steps[k] > 0.0) {
            for sign in [1.0, -1.0] {
                let mut trial = best;
                trial.0[k] += sign * steps[k];
                let c = cost(&trial);
                evaluations += 1;
                if c < best_cost {
                    if !within(&trial) {
                        return None;
                    }
                    (best, best_cost, improved) = (trial, c, true);
                    break;
                }
            }
        }
        if !improved {
            steps.iter_mut().for_each(|s| *s *= 0.5);
            halvings += 1;
        }
    }
    Some((best, best_cost))
}

/// The rays of the pixels of `camera` within a margin of the bounding box of `label` in `mask`,
/// or None when the label is absent or the mask's size is not the camera's.
fn view_pixels(camera: &Camera, mask: &Image<u8>, label: u8, margin: f64) -> Option<ViewPixels> {
    if mask.width != camera.width() || mask.height != camera.height() || mask.channels != 1 {
        return None;
    }
    let (w, h) = (mask.width, mask.height);
    let (mut x0, mut y0, mut x1, mut y1) = (u32::MAX, u32::MAX, 0, 0);
    let mut labelled = 0usize;
    for y in 0..h {
        for x in 0..w {
            if mask.get(x, y, 0) == label {
                (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
                labelled += 1;
            }
        }
    }
    if labelled == 0 {
        return None;
    }
    let pad = |len: u32| ((margin * f64::from(len)).ceil() as u32).max(4);
    let (px, py) = (pad(x1 - x0 + 1), pad(y1 - y0 + 1));
    let (x0, y0) = (x0.saturating_sub(px), y0.saturating_sub(py));
    let (x1, y1) = ((x1 + px).min(w - 1), (y1 + py).min(h - 1));
    let mut rays = Vec::with_capacity(((x1 - x0 + 1) * (y1 - y0 + 1)) as usize);
    for y in y0..=y1 {
        for x in x0..=x1 {
            rays.push((camera.pixel_ray(x, y), mask.get(x, y, 0) == label));
        }
    }
    Some(ViewPixels {
        origin: camera.pose.centre(),
        rays,
        focal: 0.5 * (camera.intrinsics.fx + camera.intrinsics.fy),
        labelled: labelled as f64,
    })
}

/// The views' costs, summed in view order. The views are costed on all cores: each evaluation
/// traces every pixel near the glass in every view, hundreds of millions of rays for a pane
/// that fills 200 photos of 1280x960, and the search makes a hundred or more evaluations. The
/// sum is the sequential one, so the result does not depend on the thread count.
fn total_cost(plane: &ReflectionPlane, views: &[ViewPixels], s: &SilhouetteSettings) -> f64 {
    crate::parallel::map_in_order(views, |v| view_cost(plane, v, s)).iter().sum()
}

/// Missed labelled pixels plus `outside_weight` times covered unlabelled ones, with a soft
/// inside-ness: the logistic of the signed distance to the rectangle's edge (positive inside),
/// converted to pixels at the hit's distance, over `edge_px`. The logistic is shifted so that a
/// pixel on the edge counts as 1 / (1 + outside_weight) inside: with the two costs unequal, that
/// is where a soft edge balances them, so the cheapest rectangle's edge lies on the mask's edge
/// rather than `edge_px * ln(1 / outside_weight)` pixels outside it.
fn view_cost(plane: &ReflectionPlane, v: &ViewPixels, s: &SilhouetteSettings) -> f64 {
    let shift = (1.0 / s.outside_weight).ln();
    let (n, t, b) = (plane.unit_normal(), plane.axis, plane.bitangent());
    let (hw, hh) = (0.5 * plane.width, 0.5 * plane.height);
    let side = (v.origin - plane.centre).dot(n);
    let to_origin = v.origin - plane.centre;
    let mut cost = 0.0;
    for &(dir, labelled) in &v.rays {
        let toward = dir.dot(n);
        // A camera behind the plane, or a ray that never meets it, sees no glass there.
        let inside = if side > 0.0 && toward < 0.0 {
            let dist = -side / toward;
            let local = to_origin + dir * dist;
            let edge = (hw - local.dot(t).abs()).min(hh - local.dot(b).abs());
            let px = edge * v.focal / dist;
            logistic(px / s.edge_px + shift)
        } else {
            0.0
        };
        cost += if labelled { 1.0 - inside } else { s.outside_weight * inside };
    }
    cost / v.labelled
}

/// `1 / (1 + exp(-z))`, without the exponential where it is 1 or 0 to a part in 1e17: most of
/// the pixels a view's cost traces lie many soft-edge widths inside or outside the rectangle.
fn logistic(z: f64) -> f64 {
    if z > 40.0 {
        1.0
    } else if z < -40.0 {
        0.0
    } else {
        1.0 / (1.0 + (-z).exp())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Intrinsics, Material, Pose};

    fn glass() -> ReflectionPlane {
        ReflectionPlane::new(
            DVec3::new(0.2, 1.0, 0.0),
            DVec3::new(0.05, 0.0, 1.0),
            DVec3::X,
            2.4,
            1.4,
            Material::Glass,
        )
    }

    /// A walk past the pane at grazing and frontal angles, each camera looking at its centre.
    fn cameras(plane: &ReflectionPlane) -> Vec<Camera> {
        let k = Intrinsics::from_fov_x(60f64.to_radians(), 160, 120);
        [-2.5, -1.2, 0.0, 1.0, 2.2, 3.0]
            .iter()
            .enumerate()
            .map(|(i, &x)| {
                let eye = plane.centre + DVec3::new(x, 0.3 - 0.1 * i as f64, 2.2);
                Camera::new(format!("v{i}"), k, Pose::look_at(eye, plane.centre, DVec3::Y))
            })
            .collect()
    }

    /// Label 1 where a pixel's ray meets the true rectangle, unless a ball in front hides it.
    fn mask(camera: &Camera, plane: &ReflectionPlane, ball: Option<(DVec3, f64)>) -> Image<u8> {
        let mut m = Image::<u8>::new(camera.width(), camera.height(), 1);
        let o = camera.pose.centre();
        for y in 0..camera.height() {
            for x in 0..camera.width() {
                let d = camera.pixel_ray(x, y);
                let Some(s) = crate::plane_math::ray_rectangle_hit(plane, o, d) else { continue };
                let hidden = ball.is_some_and(|(c, r)| {
                    let along = (c - o).dot(d);
                    along > 0.0 && along < s && (o + d * along - c).length() < r
                });
                if !hidden {
                    m.data[(y * camera.width() + x) as usize] = 1;
                }
            }
        }
        m
    }

    /// The cameras of [`cameras`] and their masks of `plane`, with nothing in front of it.
    fn unhidden_views(plane: &ReflectionPlane) -> (Vec<Camera>, Vec<Image<u8>>) {
        let cams = cameras(plane);
        let masks = cams.iter().map(|c| mask(c, plane, None)).collect();
        (cams, masks)
    }

    fn refine_cost(plane: &ReflectionPlane, views: &[(&Camera, &Image<u8>)]) -> f64 {
        let s = SilhouetteSettings::default();
        let px: Vec<_> = views.iter().filter_map(|(c, m)| view_pixels(c, m, 1, s.margin)).collect();
        total_cost(plane, &px, &s)
    }

    fn angle_deg(a: DVec3, b: DVec3) -> f64 {
        a.normalize().dot(b.normalize()).clamp(-1.0, 1.0).acos().to_degrees()
    }

    #[test]
    fn a_frame_fit_moves_onto_the_glass() {
        let truth = glass();
        let cams = cameras(&truth);
        // A ball in front of the pane hides part of it in some views.
        let ball = Some((truth.centre + DVec3::new(0.3, -0.2, 0.5), 0.25));
        let masks: Vec<_> = cams.iter().map(|c| mask(c, &truth, ball)).collect();
        let views: Vec<(&Camera, &Image<u8>)> = cams.iter().zip(&masks).collect();
        // What the fit from the frame gives: 6 cm in front, the frame's 7 cm bars included;
        // and the rectangle turned a degree in its plane.
        let n = truth.unit_normal();
        let mut start = truth;
        start.centre += n * 0.06 + truth.axis * 0.03;
        start.width += 0.14;
        start.height += 0.14;
        start.axis = DMat3::from_axis_angle(n, 1f64.to_radians()) * truth.axis;
        let fit = refine_to_masks(&start, &views, 1, &SilhouetteSettings::default())
            .expect("the masks hold the label");
        let p = fit.plane;
        let size = (truth.width * truth.height).sqrt();
        // The search reaches the cost of the truth (its own optimum may differ by a hair).
        let at_truth = refine_cost(&truth, &views);
        assert!(fit.cost_after <= at_truth + 1e-3, "{} against {at_truth}", fit.cost_after);
        assert!((p.centre - truth.centre).length() < 0.002 * size, "centre {}", p.centre);
        assert_eq!(p.normal, start.normal, "the normal stays as fitted");
        assert!(angle_deg(p.axis, truth.axis) < 0.2, "axis {}", p.axis);
        assert!((p.width - truth.width).abs() < 0.005 * truth.width, "width {}", p.width);
        assert!((p.height - truth.height).abs() < 0.005 * truth.height, "height {}", p.height);
        assert_eq!(p.material, Material::Glass);
        assert!(p.normal.dot(truth.normal) > 0.0, "the front side is kept");
    }

    /// A camera straight in front of the rectangle at distance z: a step along the normal scales
    /// the outline about the image centre, so the longer side's edges move fastest, by
    /// f (w / 2) / z^2 pixels per unit of offset.
    #[test]
    fn the_offset_resolution_is_a_pixel_of_outline_motion() {
        let plane =
            ReflectionPlane::new(DVec3::ZERO, DVec3::Z, DVec3::X, 2.4, 1.4, Material::Glass);
        let k = Intrinsics::from_fov_x(70f64.to_radians(), 320, 240);
        let z = 3.0;
        let camera =
            Camera::new("front", k, Pose::look_at(DVec3::new(0.0, 0.0, z), DVec3::ZERO, DVec3::Y));
        let expected = z * z / (k.fx * 1.2);
        let got = offset_resolution(&plane, &[&camera]);
        assert!((got / expected - 1.0).abs() < 1e-2, "{got} against {expected}");
        // A camera that sees no edge pins nothing.
        let inside = Camera::new(
            "inside",
            Intrinsics::from_fov_x(10f64.to_radians(), 32, 24),
            Pose::look_at(DVec3::new(0.0, 0.0, 1.0), DVec3::ZERO, DVec3::Y),
        );
        assert_eq!(offset_resolution(&plane, &[&inside]), f64::INFINITY);
    }

    #[test]
    fn the_true_rectangle_stays_where_it_is() {
        let truth = glass();
        let (cams, masks) = unhidden_views(&truth);
        let views: Vec<(&Camera, &Image<u8>)> = cams.iter().zip(&masks).collect();
        let fit = refine_to_masks(&truth, &views, 1, &SilhouetteSettings::default())
            .expect("the masks hold the label");
        let size = (truth.width * truth.height).sqrt();
        assert!((fit.plane.centre - truth.centre).length() < 0.003 * size);
        assert!(fit.cost_after <= fit.cost_before);
    }

    #[test]
    fn a_search_that_leaves_the_limits_stops_there() {
        let evaluations = std::cell::Cell::new(0usize);
        // Distance to `at` along the first parameter, the others at 0; evaluations counted.
        let cost_to = |at: f64| {
            let evaluations = &evaluations;
            move |p: &Params| {
                evaluations.set(evaluations.get() + 1);
                (p.0[0] - at).powi(2) + p.0[1..].iter().map(|v| v * v).sum::<f64>()
            }
        };
        let limit = |p: &Params| p.0[0] <= 1.0;
        let steps = [0.02; 6];
        // A minimum far beyond the limit: the search stops when it crosses it, at about 11
        // evaluations a step of 0.02 (one forward, two each way for the other five) ...
        let far = cost_to(10.0);
        assert!(pattern_search(Params::default(), steps, 4000, &far, &limit).is_none());
        assert!(evaluations.get() < 600, "{} evaluations", evaluations.get());
        // ... where without a limit it spends the whole budget on its way there.
        evaluations.set(0);
        assert!(pattern_search(Params::default(), steps, 4000, &far, &|_| true).is_some());
        assert!(evaluations.get() >= 4000, "{} evaluations", evaluations.get());
        // A minimum within the limit: the same search as without one.
        let near = cost_to(0.5);
        let (a, ca) = pattern_search(Params::default(), steps, 4000, &near, &limit).expect("in");
        let (b, cb) = pattern_search(Params::default(), steps, 4000, &near, &|_| true).expect("in");
        assert_eq!((a.0, ca.to_bits()), (b.0, cb.to_bits()));
        assert!((a.0[0] - 0.5).abs() < 1e-3);
    }

    /// The search crosses the shift limit on its way to a result within it (the move along
    /// the axis and the bitangent overshoots a step each) and keeps that result.
    #[test]
    fn a_result_within_the_limits_is_kept_when_the_search_crossed_them() {
        let truth = glass();
        let (cams, masks) = unhidden_views(&truth);
        let views: Vec<(&Camera, &Image<u8>)> = cams.iter().zip(&masks).collect();
        let size = (truth.width * truth.height).sqrt();
        // Shifts along the axis and the bitangent, as fractions of the size, all within 0.25:
        // without the slack, the search from each was refused.
        for (t, b) in [(0.198, 0.152), (0.176, 0.176), (-0.176, -0.176), (-0.08, -0.23)] {
            let mut start = truth;
            start.centre += (truth.axis * t + truth.bitangent() * b) * size;
            let fit = refine_to_masks(&start, &views, 1, &SilhouetteSettings::default())
                .unwrap_or_else(|| panic!("({t}, {b}) is within the limits"));
            assert!((fit.plane.centre - truth.centre).length() < 0.003 * size, "({t}, {b})");
        }
    }

    #[test]
    fn a_rectangle_twice_the_glass_is_refused() {
        let truth = glass();
        let (cams, masks) = unhidden_views(&truth);
        let views: Vec<(&Camera, &Image<u8>)> = cams.iter().zip(&masks).collect();
        let mut start = truth;
        (start.width, start.height) = (2.0 * truth.width, 2.0 * truth.height);
        assert!(refine_to_masks(&start, &views, 1, &SilhouetteSettings::default()).is_none());
    }

    #[test]
    fn the_logistic_is_cut_off_only_where_it_is_flat() {
        let exact = |z: f64| 1.0 / (1.0 + (-z).exp());
        for z in [-60.0, -40.5, -40.0, -3.0, 0.0, 0.7, 40.0, 40.5, 60.0] {
            assert!((logistic(z) - exact(z)).abs() < 1e-17, "{z}");
        }
        // At and past the cut-off towards inside, the exact value is already 1.0 in f64.
        assert_eq!(logistic(40.5), exact(40.5));
        assert!(logistic(f64::NAN).is_nan());
    }

    #[test]
    fn no_labelled_view_gives_none() {
        let truth = glass();
        let cams = cameras(&truth);
        let empty = Image::<u8>::new(160, 120, 1);
        let views: Vec<(&Camera, &Image<u8>)> = cams.iter().map(|c| (c, &empty)).collect();
        assert!(refine_to_masks(&truth, &views, 1, &SilhouetteSettings::default()).is_none());
        // A mask of another size than its camera is not read.
        let small = Image::<u8>::new(80, 60, 1);
        let views: Vec<(&Camera, &Image<u8>)> = cams.iter().map(|c| (c, &small)).collect();
        assert!(refine_to_masks(&truth, &views, 1, &SilhouetteSettings::default()).is_none());
    }
}
