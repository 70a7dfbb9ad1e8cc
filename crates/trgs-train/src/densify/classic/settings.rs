//! What classic densification is set with, what it gathers between its steps and what each
//! step reports: the values its strategy, its GPU stages and its twin share.
use crate::settings::scale_len;
use trgs_render::toolkit::layout::{FLAG_VISIBLE, PROJECTED_GRAD_FLOATS, ProjectedGaussian};

/// The schedule and thresholds (3DGS defaults for 30k steps; lengths scale with the run).
#[derive(Clone, Debug, PartialEq)]
pub struct ClassicSettings {
    pub from: u32,
    pub until: u32,
    pub every: u32,
    /// Steps between opacity resets (0: none).
    pub opacity_reset_every: u32,
    /// Average norm of dL/d(mean in NDC) above which a Gaussian densifies.
    pub grad_threshold: f64,
    /// Fraction of the scene extent separating clone (smaller) from split (larger).
    pub percent_dense: f64,
    pub min_opacity: f64,
    /// Prune Gaussians whose largest scale exceeds this share of the scene extent (the
    /// training cameras' radius), after the first reset (3DGS: 0.1; infinite: never, the
    /// default).
    pub prune_scale: f64,
    /// Prune Gaussians whose screen radius exceeds this (pixels), after the first reset
    /// (infinite: no screen-size prune).
    pub max_screen_radius: f64,
    /// Never grow beyond this many Gaussians.
    pub max_gaussians: usize,
    /// Of the Gaussians over `grad_threshold` at a densification, the share that densifies:
    /// those with the largest average gradients (1: all of them, as 3DGS).
    pub grow_fraction: f64,
}

impl ClassicSettings {
    /// The start and end scale with the run; the interval does not (the statistics need about a
    /// hundred views' gradients each time, whatever the run's length), and the opacity reset comes
    /// at least ten densifications apart, so runs of 2000 steps or fewer have none: resets three
    /// densifications apart (steps 300 and 600 of 2000) leave a short run no time to recover,
    /// and plain 3DGS ended lower on the synthetic scenes with them.
    pub fn scaled(iterations: u32) -> Self {
        let every = 100;
        Self {
            from: scale_len(500, iterations),
            until: scale_len(15_000, iterations),
            every,
            opacity_reset_every: scale_len(3000, iterations).max(10 * every),
            grad_threshold: 2e-4,
            percent_dense: 0.01,
            min_opacity: 0.005,
            // Off, as Brush. 3DGS prunes over 0.1 of the cameras' radius, which assumes the
            // scene lies within the cameras' reach: a capture walked along a street or through
            // a room sees far beyond it, and that background is made of large Gaussians
            // (docs/captures.md, "The world-size prune").
            prune_scale: f64::INFINITY,
            // Off, as in effect in the references: INRIA's code zeroes the radii just before its
            // prune, so its 20-pixel test never fires, and gsplat disables it by default. A fixed
            // pixel radius would also mean a different share of the image at each resolution.
            max_screen_radius: f64::INFINITY,
            max_gaussians: 1_000_000,
            grow_fraction: 1.0,
        }
    }

    /// These settings for one densification from `stats`: under a `grow_fraction` below 1 the
    /// gradient threshold rises to the average gradient of the last Gaussian of that share of
    /// the candidates (ranked by average gradient), so the rules of `densify_plan` and its twin
    /// densify only that share. Candidates are counted before the transparent ones are left
    /// out, so a little less than the share may grow.
    pub fn for_densification(&self, stats: &DensifyStats) -> Self {
        let mut settings = self.clone();
        if self.grow_fraction >= 1.0 {
            return settings;
        }
        // As the rules compare: f32, `sum >= threshold * count`.
        let threshold = self.grad_threshold as f32;
        let mut averages: Vec<f32> = stats
            .grad_sum
            .iter()
            .zip(&stats.count)
            .filter(|&(&sum, &count)| count > 0 && sum as f32 >= threshold * count as f32)
            .map(|(&sum, &count)| sum as f32 / count as f32)
            .collect();
        let keep = (self.grow_fraction.max(0.0) * averages.len() as f64).ceil() as usize;
        if keep >= averages.len() {
            return settings;
        }
        if keep == 0 {
            settings.grad_threshold = f64::from(f32::MAX);
            return settings;
        }
        averages.select_nth_unstable_by(keep - 1, |a, b| b.total_cmp(a));
        // A hair below the last kept average, so that its own product rounds above it.
        let last = f64::from(averages[keep - 1]) * (1.0 - 1e-6);
        settings.grad_threshold = settings.grad_threshold.max(last);
        settings
    }

    /// Whether a densification at step `t` also prunes Gaussians too large in the world
    /// (`prune_scale`) or on screen (`max_screen_radius`): after the first opacity reset, as
    /// 3DGS; never without resets, as 3DGS with its interval past the run's end.
    pub fn prunes_large_at(&self, t: u32) -> bool {
        self.opacity_reset_every > 0 && t > self.opacity_reset_every
    }

    /// Whether step `t` ends with an opacity reset: every `opacity_reset_every` steps while
    /// densification goes on (3DGS: 3000 ... 12000 of 15000), never when that is 0.
    pub fn resets_opacity_at(&self, t: u32) -> bool {
        self.opacity_reset_every > 0
            && t > 0
            && t < self.until
            && t.is_multiple_of(self.opacity_reset_every)
    }
}

/// Per-Gaussian statistics gathered between densification steps.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DensifyStats {
    /// Per Gaussian, the sum over its observations of its screen-space gradient norm (in NDC).
    pub grad_sum: Vec<f64>,
    /// Steps in which a pass saw the Gaussian.
    pub count: Vec<u32>,
    /// The largest screen radius in pixels it had.
    pub max_radius: Vec<f64>,
}

impl DensifyStats {
    pub fn new(n: usize) -> Self {
        Self { grad_sum: vec![0.0; n], count: vec![0; n], max_radius: vec![0.0; n] }
    }

    /// Add one step's screen-space gradients of an image `width x height` (the twin of the GPU's
    /// `densify_stats`, which training uses): the camera's pass, then
    /// any mirrored passes (whose images are the camera's). A Gaussian seen in any pass counts as
    /// one observation whose gradient is the sum of its passes' norms, as its mean's gradient is
    /// the sum of theirs: averaged as separate views, the faint reflection would dilute what the
    /// camera's pass measures, and a surface seen mostly in a reflection (the room behind the
    /// cameras) would be densified only from the few views that see it directly.
    pub fn add(
        &mut self,
        passes: &[(Vec<ProjectedGaussian>, Vec<[f32; PROJECTED_GRAD_FLOATS as usize]>)],
        width: u32,
        height: u32,
    ) {
        let (hw, hh) = (0.5 * f64::from(width), 0.5 * f64::from(height));
        for i in 0..self.count.len() {
            let mut seen = false;
            for (projected, grads) in passes {
                let (Some(p), Some(g)) = (projected.get(i), grads.get(i)) else { continue };
                if p.flags & FLAG_VISIBLE == 0 {
                    continue;
                }
                seen = true;
                // 3DGS measures the gradient in NDC: d/d(ndc) = d/d(pixel) * size / 2.
                let (gx, gy) = (f64::from(g[0]) * hw, f64::from(g[1]) * hh);
                self.grad_sum[i] += (gx * gx + gy * gy).sqrt();
                let r = f64::from(p.extent[0].max(p.extent[1]));
                self.max_radius[i] = self.max_radius[i].max(r);
            }
            if seen {
                self.count[i] += 1;
            }
        }
    }
}

/// What one densification step did: the count went from n to n + cloned + split - pruned (a
/// split replaces one Gaussian by two; children pruned at once count as pruned).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DensifyReport {
    pub cloned: usize,
    pub split: usize,
    pub pruned: usize,
    /// Gaussians drawn in a view since the last densification (their means had a gradient):
    /// those the frames' keys mostly come from, and the only ones that can densify.
    pub seen: usize,
}

impl DensifyReport {
    /// How many times the keys of a frame of the new set may grow: as many more as Gaussians
    /// cloned or split per Gaussian drawn. Those that densify are among the drawn, and often
    /// the larger of them, so the share of the Gaussians in view (most of which are hidden and
    /// make fewer keys) would undershoot; the undrawn ones' keys make this an overestimate.
    pub fn key_growth(&self) -> f64 {
        1.0 + (self.cloned + self.split) as f64 / self.seen.max(1) as f64
    }
}
