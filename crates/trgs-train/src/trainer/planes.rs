//! The trainer's reflection planes: adding them with their glass Gaussians, stepping their
//! parameters, and the opacity perturbation of what the cameras see through them.
use super::Trainer;
use crate::gaussians::plan::gather;
use crate::planes::adam::{OffsetLimit, PlaneRates, plane_adam};
use crate::run::checkpoint::PlaneMoments;
use crate::settings::Stage;
use anyhow::{Context, Result};
use glam::DVec3;
use trgs_core::plane_carry::PlaneCarry;
use trgs_core::plane_grad::PlaneGrad;
use trgs_core::scene::{
    Attribute, Camera, Gaussians, Population, ReflectionPlane, attribute_widths,
};
use trgs_render::FrameImages;
use trgs_render::toolkit::gpu::PendingRead;

impl Trainer {
    /// Add reflection planes, the bounds on their offsets (`limits[i]` for `planes[i]`; free where
    /// missing or None) and the Gaussians that come with them (their glass Gaussians and
    /// reflection seeds; zero moments) to the optimisation.
    ///
    /// Under a strategy with a cap (MCMC), the set stays within it: the least opaque of the
    /// primary Gaussians already there are dropped to make room, as MCMC relocates its dead ones
    /// (the new Gaussians are kept, up to the cap). Returns how many were dropped.
    pub fn add_planes(
        &mut self,
        planes: &[ReflectionPlane],
        limits: &[Option<OffsetLimit>],
        glass: &Gaussians<f32>,
    ) -> Result<usize> {
        // A change of the set still pending goes in first (it was decided for the set as it is;
        // a run settles it before calling this, the next maintenance reports it otherwise).
        self.settle_unreported()?;
        let mut state = self.read_state()?;
        let n_old = state.gaussians.len();
        let g = &mut state.gaussians;
        g.means.extend_from_slice(&glass.means);
        g.rotations.extend_from_slice(&glass.rotations);
        g.log_scales.extend_from_slice(&glass.log_scales);
        g.opacity_logits.extend_from_slice(&glass.opacity_logits);
        g.sh.extend_from_slice(&glass.with_sh_degree(g.sh_degree).sh);
        g.mask_logits.extend_from_slice(&glass.mask_logits);
        g.log_reflections.extend_from_slice(&glass.log_reflections);
        g.populations.extend_from_slice(&glass.populations);
        let widths = attribute_widths(g.sh_coeffs());
        for a in Attribute::ALL {
            let len = (n_old + glass.len()) * widths[a];
            state.m[a].resize(len, 0.0);
            state.v[a].resize(len, 0.0);
        }
        let dropped = match self.densification.cap() {
            Some(cap) if state.gaussians.len() > cap => {
                let g = &state.gaussians;
                let sources = within_cap(&g.opacity_logits, &g.populations, n_old, cap);
                let dropped = state.gaussians.len() - sources.len();
                state = gather(&state, &sources);
                dropped
            }
            _ => 0,
        };
        let mut all = self.planes().to_vec();
        all.extend_from_slice(planes);
        self.gaussians.scene_mut().set_planes(&all).context("initialised planes")?;
        self.plane_moments.extend((0..planes.len()).map(|i| PlaneMoments {
            offset_limit: limits.get(i).copied().flatten(),
            ..PlaneMoments::default()
        }));
        self.set_state(&state)?;
        Ok(dropped)
    }

    /// Remove the planes whose `keep` flag is false, with their moments, and the Gaussians of
    /// rows `rows` (ascending; read after [`Trainer::settle`], which this applies first, so
    /// that they are the rows it removes).
    pub fn remove_planes(&mut self, keep: &[bool], rows: &[usize]) -> Result<()> {
        self.settle_unreported()?;
        let state = self.read_state()?;
        let kept_rows: Vec<(usize, bool)> = (0..state.gaussians.len())
            .filter(|i| rows.binary_search(i).is_err())
            .map(|i| (i, true))
            .collect();
        let state = gather(&state, &kept_rows);
        let kept: Vec<ReflectionPlane> =
            self.planes().iter().zip(keep).filter(|(_, k)| **k).map(|(p, _)| *p).collect();
        self.gaussians.scene_mut().set_planes(&kept).context("the planes kept")?;
        let mut flags = keep.iter();
        self.plane_moments.retain(|_| flags.next().copied().unwrap_or(true));
        self.set_state(&state)?;
        Ok(())
    }

    /// Replace the planes' geometry (as many planes, in the same order: their moments stay), and
    /// move the Gaussians of rows `carried[k]` with plane `k` ([`PlaneCarry`]: those only its
    /// mirrored pass shows keep their mirror images; read after [`Trainer::settle`], which this
    /// applies first). The carried means' first moments turn with them.
    pub fn move_planes(
        &mut self,
        planes: &[ReflectionPlane],
        carried: &[Vec<usize>],
    ) -> Result<()> {
        let from = self.planes().to_vec();
        anyhow::ensure!(
            planes.len() == from.len(),
            "moving {} planes onto {} new ones",
            from.len(),
            planes.len()
        );
        if carried.iter().any(|rows| !rows.is_empty()) {
            self.settle_unreported()?;
            let mut state = self.read_state()?;
            let degree = state.gaussians.sh_degree;
            let width = attribute_widths(state.gaussians.sh_coeffs())[Attribute::Means];
            for ((old, new), rows) in from.iter().zip(planes).zip(carried) {
                let carry = PlaneCarry::between(old, new, degree);
                let turn = carry.linear();
                let moments = &mut state.m[Attribute::Means];
                for &i in rows {
                    carry.apply(&mut state.gaussians, i);
                    let m = &mut moments[width * i..width * (i + 1)];
                    let turned = turn * DVec3::new(m[0].into(), m[1].into(), m[2].into());
                    m.copy_from_slice(&turned.to_array().map(|v| v as f32));
                }
            }
            self.set_state(&state)?;
        }
        self.gaussians.scene_mut().set_planes(planes).context("moved planes")?;
        Ok(())
    }

    /// Every layer of `camera`'s render as if the planes were `planes` (the trainer's own are
    /// back when it returns): what a plane adds to a view.
    pub fn render_with_planes(
        &mut self,
        planes: &[ReflectionPlane],
        camera: &Camera,
    ) -> Result<FrameImages> {
        let own = self.planes().to_vec();
        self.gaussians.scene_mut().set_planes(planes).context("planes for a render")?;
        let images = self.render(camera).and_then(|f| Ok(f.read_images(&self.ctx)?));
        self.gaussians.scene_mut().set_planes(&own).context("restoring the planes")?;
        images
    }

    /// Adam on the planes' offset along the normal, normal and R0 logit ([`plane_adam`]).
    pub(super) fn step_planes(&mut self, grads: &[PlaneGrad], t: u32) -> Result<()> {
        if grads.is_empty() {
            return Ok(());
        }
        let r = &self.settings.rates;
        // Stage 3 fine-tunes the planes' position and normal at a tenth of the rate.
        let fine =
            if self.settings.stage(t - 1) == Stage::Joint { r.plane_stage3_factor } else { 1.0 };
        let mut planes = self.planes().to_vec();
        let rates = PlaneRates {
            offset: fine * r.plane_centre * self.extent,
            normal: fine * r.plane_normal,
            r0_logit: r.plane_r0,
        };
        let stage1 = self.settings.stage1;
        for ((plane, g), mom) in planes.iter_mut().zip(grads).zip(&mut self.plane_moments) {
            // Adam's bias correction counts the plane's own steps: its moments start at zero
            // when it is created (at the end of stage 1), and with the run's step count instead
            // the first steps would be several times the rate (1 - b2^t near 1 under a tiny v).
            // A checkpoint from before the count started: the planes began after stage 1.
            if mom.steps == 0 && mom.v.iter().any(|&v| v != 0.0) {
                mom.steps = t.saturating_sub(stage1 + 1);
            }
            mom.steps += 1;
            plane_adam(plane, g, mom, &rates, mom.steps);
        }
        let scene = self.gaussians.scene_mut();
        scene.set_planes(&planes).context("a plane step left an invalid plane")?;
        Ok(())
    }

    /// Opacity perturbation after step `self.step`, when its schedule says so; returns the
    /// readback of how many Gaussians it perturbed.
    pub(super) fn perturb_step(&mut self) -> Result<Option<PendingRead>> {
        let t = self.step;
        let Some(p) = self.settings.perturb else { return Ok(None) };
        if self.planes().is_empty()
            || !self.settings.perturbs_at(t)
            || self.densification.resets_opacity_at(t)
        {
            return Ok(None);
        }
        // Only the opacity buffer changes: the moments and densification statistics stay. The
        // count is read when the maintenance settles, not to wait for it now.
        let seed = self.rng.next_u64() as u32;
        let (ctx, scene) = (&self.ctx, self.gaussians.scene());
        Ok(self.perturb.record(ctx, scene, &self.camera_centres, p.amplitude, seed)?)
    }
}

/// The rows kept when `cap` is smaller than the set of `opacity_logits.len()` Gaussians, of which
/// those from `n_old` on were just added: the glass Gaussians already there (MCMC never moves
/// them either), every added one (the first that fit if they alone exceed the room left), and
/// the most opaque of the other old ones (ties to the lower index); in their order, with their
/// moments.
fn within_cap(
    opacity_logits: &[f32],
    populations: &[Population],
    n_old: usize,
    cap: usize,
) -> Vec<(usize, bool)> {
    let n = opacity_logits.len();
    let (glass, mut primary): (Vec<usize>, Vec<usize>) =
        (0..n_old).partition(|&i| populations[i] == Population::Glass);
    let new = (n - n_old).min(cap.saturating_sub(glass.len()));
    primary.sort_by(|&a, &b| opacity_logits[b].total_cmp(&opacity_logits[a]).then(a.cmp(&b)));
    primary.truncate(cap.saturating_sub(glass.len() + new));
    let mut old: Vec<usize> = glass.into_iter().chain(primary).collect();
    old.sort_unstable();
    old.into_iter().chain(n_old..n_old + new).map(|i| (i, true)).collect()
}

#[cfg(test)]
mod tests {
    use super::within_cap;
    use trgs_core::scene::Population::{Glass, Primary};

    fn rows(logits: &[f32], glass: &[usize], n_old: usize, cap: usize) -> Vec<usize> {
        let pops: Vec<_> =
            (0..logits.len()).map(|i| if glass.contains(&i) { Glass } else { Primary }).collect();
        within_cap(logits, &pops, n_old, cap).into_iter().map(|(i, _)| i).collect()
    }

    #[test]
    fn the_least_opaque_make_room_for_the_added() {
        // Five old Gaussians, three added, a cap of six: the two least opaque old ones go.
        let logits = [0.5, -3.0, 2.0, -1.0, 0.0, 9.0, 9.0, 9.0];
        assert_eq!(rows(&logits, &[], 5, 6), [0, 2, 4, 5, 6, 7]);
        // A glass Gaussian stays however transparent: the two least opaque primary ones go.
        assert_eq!(rows(&logits, &[1], 5, 6), [0, 1, 2, 5, 6, 7]);
    }

    #[test]
    fn ties_keep_the_lower_index_and_the_added_alone_are_cut_to_the_cap() {
        assert_eq!(rows(&[1.0, 1.0, 1.0, 0.0], &[], 3, 3), [0, 1, 3]);
        assert_eq!(rows(&[1.0, 0.0, 0.0, 0.0], &[], 1, 2), [1, 2]);
    }
}
