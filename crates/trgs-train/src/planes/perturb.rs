//! Opacity perturbation (paper, appendix "Opacity perturbation"): every so often in stage 3, the
//! primary Gaussians seen through a plane get uniform noise on their opacity, which shakes both
//! the depth variance and the gradient similarity out of a local optimum; the Gaussians that
//! belong in the transmission recover, reflection ghosts behind the glass do not. Training runs
//! it on the GPU (stage `perturb`, [`GpuPerturb`]); [`seen_through_planes`] and
//! [`perturb_opacities`] are its twin.
use crate::layout::{PerturbParams, PerturbPlane};
use glam::DVec3;
use trgs_core::reference::pcg_hash;
use trgs_core::scene::{Attribute, Gaussians, Population, ReflectionPlane};
use trgs_render::toolkit::gpu::{self, Kernel, Recorder, grid_1d, range};
use trgs_render::{GpuContext, GpuScene};

pub use crate::settings::PERTURB_AMPLITUDE;

/// Opacities are clamped into [this, 1 - this] after the noise, so that their logits stay finite.
pub const OPACITY_CLAMP: f64 = 1e-3;

/// How far behind a plane a Gaussian's centre must lie to be perturbed, as a fraction of the
/// plane rectangle's shorter side (11.5 cm for the synthetic 1.77 x 1.15 m fit).
pub const BEHIND_MARGIN: f64 = 0.1;

/// Which primary Gaussians some training camera sees through a plane: the Gaussian's centre lies
/// behind the plane by more than [`BEHIND_MARGIN`] of its shorter side, and the segment from a
/// camera on the front side to it crosses the plane's rectangle. (The paper selects the Gaussians
/// whose projection onto the plane from a training view falls inside it. Two deviations, both
/// because the ghosts the perturbation is for sit behind the glass at the depth of what it
/// reflects: those in front of the glass are left alone, and so are those that straddle the
/// plane, i.e. the window frame and the wall around it, which are seen outside the glass too:
/// perturbing them costs accuracy outside the glass region, where the perturbation has nothing
/// to separate.)
pub fn seen_through_planes(
    g: &Gaussians<f32>,
    planes: &[ReflectionPlane],
    camera_centres: &[DVec3],
) -> Vec<bool> {
    let mut selected = vec![false; g.len()];
    for plane in planes {
        let n = plane.unit_normal();
        let bitangent = plane.bitangent();
        let margin = BEHIND_MARGIN * plane.width.min(plane.height);
        for &c in camera_centres {
            let side = (c - plane.centre).dot(n);
            if side <= 0.0 {
                continue;
            }
            for (i, m) in g.means.iter().enumerate() {
                if selected[i] || g.populations[i] != Population::Primary {
                    continue;
                }
                let mu = DVec3::new(f64::from(m[0]), f64::from(m[1]), f64::from(m[2]));
                if (mu - plane.centre).dot(n) >= -margin {
                    continue;
                }
                let d = mu - c;
                let denom = d.dot(n);
                // Ray c + t d meets the plane at t = -side / (d . n) > 0.
                let hit = c + d * (-side / denom) - plane.centre;
                selected[i] = hit.dot(plane.axis).abs() <= 0.5 * plane.width
                    && hit.dot(bitangent).abs() <= 0.5 * plane.height;
            }
        }
    }
    selected
}

/// The uniform number in [0, 1) of Gaussian `i`'s noise at `seed` (24 bits, which f32 holds).
fn noise_uniform(seed: u32, i: u32) -> f64 {
    f64::from(pcg_hash(i ^ pcg_hash(seed)) >> 8) / 16_777_216.0
}

/// Add uniform noise in [-amplitude, amplitude) to the opacity of the selected Gaussians and
/// clamp (the twin of `perturb`'s noise: Gaussian i's number is drawn from `seed` by its index);
/// returns how many were perturbed.
pub fn perturb_opacities(
    g: &mut Gaussians<f32>,
    selected: &[bool],
    amplitude: f64,
    seed: u32,
) -> usize {
    let mut count = 0;
    for (i, (logit, &sel)) in g.opacity_logits.iter_mut().zip(selected).enumerate() {
        if !sel {
            continue;
        }
        let o = 1.0 / (1.0 + (-f64::from(*logit)).exp());
        let noise = amplitude * (2.0 * noise_uniform(seed, i as u32) - 1.0);
        let noisy = (o + noise).clamp(OPACITY_CLAMP, 1.0 - OPACITY_CLAMP);
        *logit = (noisy / (1.0 - noisy)).ln() as f32;
        count += 1;
    }
    count
}

/// The planes as `perturb` reads them.
pub fn perturb_planes(planes: &[ReflectionPlane]) -> Vec<PerturbPlane> {
    let v = |v: DVec3, w: f64| [v.x as f32, v.y as f32, v.z as f32, w as f32];
    planes
        .iter()
        .map(|p| PerturbPlane {
            centre: v(p.centre, BEHIND_MARGIN * p.width.min(p.height)),
            normal: v(p.unit_normal(), 0.5 * p.width),
            axis: v(p.axis, 0.5 * p.height),
            bitangent: v(p.bitangent(), 0.0),
        })
        .collect()
}

/// How many Gaussians a perturbation changed, from the readback [`GpuPerturb::record`] returns.
pub fn read_count(ctx: &GpuContext, read: gpu::PendingRead) -> Result<usize, gpu::GpuError> {
    Ok(read.read::<u32>(ctx, 4)?[0] as usize)
}

/// Stage `perturb` on the GPU: the selection of [`seen_through_planes`] and the noise of
/// [`perturb_opacities`] in place, without reading the Gaussians back.
#[derive(Debug)]
pub struct GpuPerturb {
    kernel: Kernel,
}

impl GpuPerturb {
    pub fn new(ctx: &GpuContext) -> Self {
        Self { kernel: crate::kernels::TRAINING_KERNELS.perturb.build(ctx) }
    }

    /// Perturb the opacities of `scene`'s Gaussians that the cameras at `camera_centres` see
    /// through its planes; waits for the GPU and returns how many it perturbed (one counter
    /// read back).
    pub fn run(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        camera_centres: &[DVec3],
        amplitude: f64,
        seed: u32,
    ) -> Result<usize, gpu::GpuError> {
        match self.record(ctx, scene, camera_centres, amplitude, seed)? {
            Some(read) => read_count(ctx, read),
            None => Ok(0),
        }
    }

    /// [`GpuPerturb::run`] recorded and submitted without waiting: the readback of the count
    /// (a trainer reports it a step late), or None when nothing can be selected.
    pub fn record(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        camera_centres: &[DVec3],
        amplitude: f64,
        seed: u32,
    ) -> Result<Option<gpu::PendingRead>, gpu::GpuError> {
        let planes = perturb_planes(scene.planes());
        if planes.is_empty() || camera_centres.is_empty() || scene.is_empty() {
            return Ok(None);
        }
        let scopes = gpu::ErrorScopes::open(ctx, "perturbing the opacities");
        let cameras: Vec<[f32; 4]> =
            camera_centres.iter().map(|c| [c.x as f32, c.y as f32, c.z as f32, 0.0]).collect();
        let planes_buffer = gpu::storage_init(ctx, "trgs.perturb.planes", &planes);
        let cameras_buffer = gpu::storage_init(ctx, "trgs.perturb.cameras", &cameras);
        let count = gpu::storage_init(ctx, "trgs.perturb.count", &[0u32]);
        let p = scene.parameters();
        let (means, opacity) = (p[Attribute::Means], p[Attribute::OpacityLogits]);
        let mut rec = Recorder::new(ctx, "trgs.perturb", false);
        for (first, n) in scene.chunks() {
            let params = PerturbParams {
                count: n,
                planes: planes.len() as u32,
                cameras: cameras.len() as u32,
                seed,
                amplitude: amplitude as f32,
                clamp: OPACITY_CLAMP as f32,
                first,
                pad0: 0,
            };
            let block = gpu::params(ctx, "trgs.perturb.params", &params);
            let (f, c) = (u64::from(first), u64::from(n));
            let bind = self.kernel.bind(
                ctx,
                &[
                    block.as_entire_binding(),
                    planes_buffer.as_entire_binding(),
                    cameras_buffer.as_entire_binding(),
                    range(means, f * 12, c * 12),
                    range(scene.populations(), f * 4, c * 4),
                    range(opacity, f * 4, c * 4),
                    count.as_entire_binding(),
                ],
            );
            rec.dispatch("perturb", &self.kernel, &bind, grid_1d(n.div_ceil(256)));
        }
        let read = rec.submit_read(ctx, &count, 4);
        Ok(Some(scopes.close_after(read)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use trgs_core::scene::Material;

    fn pane() -> ReflectionPlane {
        // The pane z = 0, 2 x 1, front side +z.
        ReflectionPlane::new(DVec3::ZERO, DVec3::Z, DVec3::X, 2.0, 1.0, Material::Glass)
    }

    #[test]
    fn selects_what_a_camera_sees_through_the_pane() {
        let mut g = Gaussians::<f32>::zeros(7, 0);
        g.means = vec![
            [0.2, 0.1, -1.0],   // behind the pane, straight through it
            [5.0, 0.0, -1.0],   // behind, but outside the rectangle from this camera
            [0.0, 0.0, 1.0],    // in front of the pane, on the camera's side
            [0.1, 0.0, -2.0],   // behind, but a glass Gaussian
            [0.0, 0.3, -0.5],   // behind and through
            [0.9, 0.45, -0.05], // on the frame, within the margin (0.1 of the 1 m side)
            [0.0, 0.0, -0.11],  // just past the margin
        ];
        g.populations[3] = Population::Glass;
        let centres = [DVec3::new(0.0, 0.0, 3.0)];
        let s = seen_through_planes(&g, &[pane()], &centres);
        assert_eq!(s, vec![true, false, false, false, true, false, true]);
        // A camera behind the pane sees no reflection through it.
        let s = seen_through_planes(&g, &[pane()], &[DVec3::new(0.0, 0.0, -3.0)]);
        assert!(s.iter().all(|&v| !v));
    }

    #[test]
    fn noise_stays_in_range_and_only_on_selected() {
        let mut g = Gaussians::<f32>::zeros(400, 0);
        for (i, l) in g.opacity_logits.iter_mut().enumerate() {
            *l = (i as f32 / 40.0) - 5.0;
        }
        let before = g.opacity_logits.clone();
        let selected: Vec<bool> = (0..400).map(|i| i % 2 == 0).collect();
        let n = perturb_opacities(&mut g, &selected, PERTURB_AMPLITUDE, 9);
        assert_eq!(n, 200);
        let sig = |l: f32| 1.0 / (1.0 + (-f64::from(l)).exp());
        let mut moved = 0;
        for i in 0..400 {
            let (a, b) = (sig(before[i]), sig(g.opacity_logits[i]));
            if selected[i] {
                let range = OPACITY_CLAMP * 0.99..=1.0 - OPACITY_CLAMP * 0.99;
                assert!(b.is_finite() && range.contains(&b), "opacity {b} outside the clamp");
                assert!((b - a).abs() <= PERTURB_AMPLITUDE + 1e-6, "noise beyond the amplitude");
                moved += usize::from((b - a).abs() > 1e-3);
            } else {
                assert_eq!(g.opacity_logits[i], before[i]);
            }
        }
        assert!(moved > 150, "the noise barely moved anything: {moved}");
    }
}
