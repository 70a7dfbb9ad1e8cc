//! Reflection-plane initialisation from the annotated glass masks at the end of stage 1 (the
//! paper's appendix A; docs/ARCHITECTURE.md, "Plane initialisation"): for each label, the
//! Gaussians whose centres project into a band around the mask's outline in most annotated views
//! are fitted with a RANSAC plane and a minimum-area rectangle (`trgs_core::fit`); the normal is
//! turned toward the annotated cameras; the rectangle is moved from the pane's frame onto the
//! glass that the masks outline (`trgs_core::fit::refine_to_masks`, not in the paper), which
//! then also bound how far training may move it along its normal ([`OffsetLimit`]); 1000
//! glass Gaussians are sampled on the rectangle.
use crate::data::View;
use crate::planes::adam::OffsetLimit;
use glam::{DMat3, DQuat, DVec3};
use trgs_core::Image;
use trgs_core::fit::{
    SilhouetteSettings, fit_rectangle, orient_towards, refine_to_masks, sample_rectangle,
};
use trgs_core::rng::Rng;
use trgs_core::scene::{Camera, Gaussians, Material, Population, ReflectionPlane};

/// Settings of the initialisation.
#[derive(Clone, Debug, PartialEq)]
pub struct PlaneInitSettings {
    /// Band half-width around the mask outline, in pixels at 800 pixels of image width (the
    /// paper's 20 px); scaled with the training width, at least 2 px.
    pub band_px_at_800: f64,
    /// RANSAC inlier distance as a fraction of the scene extent.
    pub ransac_threshold: f64,
    pub ransac_iterations: usize,
    /// Glass Gaussians sampled on each plane.
    pub glass_gaussians: usize,
    /// Opacity and mask value of the glass Gaussians.
    pub glass_opacity: f64,
    pub glass_mask: f64,
    /// The refinement of the fitted rectangle against the masks (None: the paper's fit alone).
    pub silhouette: Option<SilhouetteSettings>,
    /// How far training may move a refined plane along its normal, in pixels of outline motion
    /// in the annotated view where it moves most (the plane Adam's `OffsetLimit`; infinite: free).
    pub offset_limit_px: f64,
}

impl Default for PlaneInitSettings {
    fn default() -> Self {
        Self {
            band_px_at_800: 20.0,
            ransac_threshold: 0.01,
            ransac_iterations: 2000,
            glass_gaussians: 1000,
            glass_opacity: 0.5,
            glass_mask: 0.99,
            silhouette: Some(SilhouetteSettings::default()),
            offset_limit_px: 1.0,
        }
    }
}

/// Pixels within `radius` of the outline of label `label` in `mask` (the outline: pixels of the
/// label with a 4-neighbour of another value).
pub fn outline_band(mask: &Image<u8>, label: u8, radius: f64) -> Vec<bool> {
    let (w, h) = (mask.width as i64, mask.height as i64);
    let at = |x: i64, y: i64| mask.data[(y * w + x) as usize];
    let mut band = vec![false; (w * h) as usize];
    let r = radius.ceil() as i64;
    for y in 0..h {
        for x in 0..w {
            if at(x, y) != label {
                continue;
            }
            let edge = [(1, 0), (-1, 0), (0, 1), (0, -1)].iter().any(|(dx, dy)| {
                let (nx, ny) = (x + dx, y + dy);
                (0..w).contains(&nx) && (0..h).contains(&ny) && at(nx, ny) != label
            });
            if !edge {
                continue;
            }
            for dy in -r..=r {
                for dx in -r..=r {
                    let (nx, ny) = (x + dx, y + dy);
                    if (0..w).contains(&nx)
                        && (0..h).contains(&ny)
                        && ((dx * dx + dy * dy) as f64) <= radius * radius
                    {
                        band[(ny * w + nx) as usize] = true;
                    }
                }
            }
        }
    }
    band
}

/// A plane for every label that could be fitted, with its glass Gaussians.
#[derive(Clone, Debug)]
pub struct InitialisedPlanes {
    pub planes: Vec<ReflectionPlane>,
    /// The label of each plane.
    pub labels: Vec<u32>,
    pub glass: Gaussians<f32>,
    /// Labels whose fit failed, with why.
    pub failed: Vec<(u32, String)>,
    /// What the refinement against the masks did to each plane, in words.
    pub refined: Vec<String>,
    /// Per plane, the bounds the masks set on its offset (None where they pin nothing).
    pub offset_limits: Vec<Option<OffsetLimit>>,
}

/// Fit the planes of `labels` from the primary Gaussians `g` and the annotated `views`.
pub fn initialise_planes(
    g: &Gaussians<f32>,
    views: &[View],
    labels: &[(u32, Material)],
    extent: f64,
    settings: &PlaneInitSettings,
    rng: &mut Rng,
) -> InitialisedPlanes {
    let mut out = InitialisedPlanes {
        planes: Vec::new(),
        labels: Vec::new(),
        glass: Gaussians::empty(g.sh_degree),
        failed: Vec::new(),
        refined: Vec::new(),
        offset_limits: Vec::new(),
    };
    let annotated: Vec<&View> = views.iter().filter(|v| v.mask.is_some()).collect();
    let masks: Vec<(&Camera, &Image<u8>)> =
        annotated.iter().filter_map(|v| Some((&v.camera, v.mask.as_ref()?))).collect();
    for &(label, material) in labels {
        let Ok(label8) = u8::try_from(label) else { continue };
        let mut plane = match fit_to_outline(g, &masks, label8, material, extent, settings, rng) {
            Ok(plane) => plane,
            Err(why) => {
                out.failed.push((label, why));
                continue;
            }
        };
        let mut offset_limit = None;
        if let Some(silhouette) = &settings.silhouette {
            out.refined.push(match refine_to_masks(&plane, &masks, label8, silhouette) {
                Some(r) => {
                    let moved = (r.plane.centre - plane.centre).dot(plane.unit_normal());
                    let text = format!(
                        "moved onto the masks: {moved:+.3} along the normal, {:.2} x {:.2} \
                         (fit from the outline: {:.2} x {:.2}), mask cost {:.3} -> {:.3}",
                        r.plane.width,
                        r.plane.height,
                        plane.width,
                        plane.height,
                        r.cost_before,
                        r.cost_after
                    );
                    let tolerance = settings.offset_limit_px * r.offset_resolution;
                    let limit = OffsetLimit { anchor: r.plane.centre.to_array(), tolerance };
                    offset_limit = limit.is_valid().then_some(limit);
                    plane = r.plane;
                    match offset_limit {
                        Some(l) => {
                            format!("{text}; kept within {:.3} along the normal", l.tolerance)
                        }
                        None => text,
                    }
                }
                None => "kept as fitted: the masks pin no rectangle within the refinement's limits"
                    .into(),
            });
        }
        append_glass(&mut out.glass, &plane, settings, rng);
        out.planes.push(plane);
        out.labels.push(label);
        out.offset_limits.push(offset_limit);
    }
    out
}

/// The centres of the primary Gaussians of `g` around the outline of `label` in `masks`
/// (camera, label image): those whose centres project into a band around the outline
/// ([`PlaneInitSettings::band_px_at_800`]) in at least half the views that see them. Around a
/// pane's outline lies its frame.
pub fn outline_gaussians(
    g: &Gaussians<f32>,
    masks: &[(&Camera, &Image<u8>)],
    label: u8,
    settings: &PlaneInitSettings,
) -> Vec<DVec3> {
    let means: Vec<DVec3> = g.means.iter().map(|m| DVec3::from_array(m.map(f64::from))).collect();
    // Votes: views where the centre falls in the band / views where it falls in the image.
    let mut in_band = vec![0u32; means.len()];
    let mut seen = vec![0u32; means.len()];
    for (camera, mask) in masks.iter().filter(|(_, m)| m.data.contains(&label)) {
        let k = &camera.intrinsics;
        let radius = (settings.band_px_at_800 * f64::from(k.width) / 800.0).max(2.0);
        let band = outline_band(mask, label, radius);
        for (i, (m, pop)) in means.iter().zip(&g.populations).enumerate() {
            if *pop != Population::Primary {
                continue;
            }
            let Some(u) = camera.image_point(*m) else { continue };
            seen[i] += 1;
            if band[(u.y as usize) * k.width as usize + u.x as usize] {
                in_band[i] += 1;
            }
        }
    }
    (0..means.len())
        .filter(|&i| in_band[i] > 0 && 2 * in_band[i] >= seen[i])
        .map(|i| means[i])
        .collect()
}

/// The plane of the primary Gaussians of `g` around the outline of `label` in `masks` (camera,
/// label image; [`outline_gaussians`]), fitted with a RANSAC plane and a minimum-area rectangle,
/// the normal turned toward the cameras that show the label. Around a pane's outline lies its
/// frame, which stands in the pane's plane. Err says why no plane fits.
pub fn fit_to_outline(
    g: &Gaussians<f32>,
    masks: &[(&Camera, &Image<u8>)],
    label: u8,
    material: Material,
    extent: f64,
    settings: &PlaneInitSettings,
    rng: &mut Rng,
) -> Result<ReflectionPlane, String> {
    let candidates = outline_gaussians(g, masks, label, settings);
    let cameras: Vec<DVec3> = masks
        .iter()
        .filter(|(_, m)| m.data.contains(&label))
        .map(|(c, _)| c.pose.centre())
        .collect();
    let fit = fit_rectangle(
        &candidates,
        settings.ransac_threshold * extent,
        settings.ransac_iterations,
        rng,
    )
    .ok_or_else(|| {
        format!("no plane fits the {} Gaussians on the mask outline", candidates.len())
    })?;
    let mut plane = fit.to_plane(material);
    plane.normal = orient_towards(fit.normal, fit.centre, &cameras);
    plane.orthogonalise_axis();
    Ok(plane)
}

/// Glass Gaussians on `plane`: flat discs of about the sample spacing, thin along the normal.
pub fn append_glass(
    glass: &mut Gaussians<f32>,
    plane: &ReflectionPlane,
    settings: &PlaneInitSettings,
    rng: &mut Rng,
) {
    let n = settings.glass_gaussians;
    let spacing = (plane.width * plane.height / n.max(1) as f64).sqrt();
    let n_hat = plane.unit_normal();
    let rot = DMat3::from_cols(plane.axis, plane.bitangent(), n_hat);
    let q = DQuat::from_mat3(&rot).normalize();
    let logit = |p: f64| (p / (1.0 - p)).ln() as f32;
    let coeffs = glass.sh_coeffs();
    for p in sample_rectangle(plane, n, rng) {
        glass.means.push(p.to_array().map(|v| v as f32));
        glass.rotations.push([q.w as f32, q.x as f32, q.y as f32, q.z as f32]);
        let s = spacing.ln() as f32;
        glass.log_scales.push([s, s, (0.1 * spacing).ln() as f32]);
        glass.opacity_logits.push(logit(settings.glass_opacity));
        glass.sh.extend(std::iter::repeat_n([0.0f32; 3], coeffs));
        glass.mask_logits.push(logit(settings.glass_mask));
        glass.log_reflections.push(0.0);
        glass.populations.push(Population::Glass);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn band_surrounds_the_outline() {
        let mut m = Image::<u8>::new(20, 20, 1);
        for y in 5..15 {
            for x in 5..15 {
                m.data[y * 20 + x] = 1;
            }
        }
        let band = outline_band(&m, 1, 2.0);
        assert!(band[10 * 20 + 5] && band[10 * 20 + 3] && band[10 * 20 + 6]);
        assert!(!band[10 * 20 + 10], "the interior is not on the band");
        assert!(!band[10 * 20], "far outside is not on the band");
    }
}
