//! What a scene is before and after its photos are traced: the [`Plan`] (cameras at the photos'
//! size, planes, sparse points, which views get masks, the size to trace at) and [`generate`],
//! which traces every view into a [`SyntheticScene`] held in memory.
use super::config::{SyntheticConfig, SyntheticLens};
use super::generate::{Layout, layout};
use super::points::sparse_points;
use super::render_views::{View, render_all};
use trgs_core::image::Image;
use trgs_core::scene::{Camera, ReflectionPlane};

/// Indices of `count` training views of the loop (views that are not every 8th) spread over it.
fn masked_view_indices(views: usize, count: usize) -> Vec<usize> {
    let train: Vec<usize> = (0..views).filter(|i| i % 8 != 0).collect();
    let count = count.min(train.len());
    (0..count).map(|j| train[(2 * j + 1) * train.len() / (2 * count)]).collect()
}

/// The longest side the scene is ray traced at. Larger photos (the scale fixture's phone-sized
/// ones) are traced at this size and enlarged bilinearly: ray tracing 200 photos of 12 MP would
/// take hours on a laptop, and what they are for (loading, memory, the default 1600 px
/// training size) does not need the detail. Such photos are named `.jpg` and written as JPEG,
/// as a camera writes them.
pub const TRACED_LONG_SIDE: u32 = 1600;

/// A generated dataset with its ground truth.
#[derive(Clone, Debug)]
pub struct SyntheticScene {
    /// The photos' cameras named `view_000.png`, ...: their camera matrices, with `lens`.
    pub cameras: Vec<Camera>,
    /// The lens every photo is taken through.
    pub lens: SyntheticLens,
    /// Final composites, RGB in [0, 1].
    pub images: Vec<Image<f32>>,
    /// Ground-truth transmission `C_t` (the scene with no pane at all), RGB in [0, 1].
    pub transmission: Vec<Image<f32>>,
    /// Glass labels for the masked training views, `None` for the others: k (1-based pane index)
    /// where a primary ray of the pixel's 2x2 subsamples has pane k, seen from its front side, as
    /// its nearest hit (the pane with most such subsamples, the lower index on a tie), 0
    /// elsewhere. Counting any subsample makes the composite equal the transmission bit for bit
    /// outside the masks; occluders in front of a pane cut its mask.
    pub masks: Vec<Option<Image<u8>>>,
    /// The truth planes, label k = index k - 1, with `r0_logit` set to the truth R0.
    pub planes: Vec<ReflectionPlane>,
    /// Sparse points on opaque surfaces (world position with a little noise, colour).
    pub points: Vec<([f64; 3], [u8; 3])>,
    /// For each point, the indices of the cameras that see it (at least two); it projects inside
    /// each of their images, in front of the camera.
    pub tracks: Vec<Vec<usize>>,
    /// Names of the test views (every 8th view of the loop, starting with the first).
    pub test_views: Vec<String>,
}

/// Everything about a scene but its photos, with the layout they are traced from: what
/// [`generate`] and [`super::write_generated`] share.
pub(crate) struct Plan {
    /// The tracer's layout, its cameras at the traced size.
    pub layout: Layout,
    /// The photos' cameras (at the photos' size, named as the files), lens and views.
    pub cameras: Vec<Camera>,
    pub lens: SyntheticLens,
    pub planes: Vec<ReflectionPlane>,
    pub points: Vec<([f64; 3], [u8; 3])>,
    pub tracks: Vec<Vec<usize>>,
    pub test_views: Vec<String>,
    /// The views that get a glass mask.
    pub masked: Vec<usize>,
    /// The photos' size, when larger than the traced one.
    pub enlarged: Option<(u32, u32)>,
}

pub(crate) fn plan(config: &SyntheticConfig) -> Plan {
    plan_traced_at(config, TRACED_LONG_SIDE)
}

/// [`plan`] with photos longer than `traced_long_side` traced at that size.
pub(crate) fn plan_traced_at(config: &SyntheticConfig, traced_long_side: u32) -> Plan {
    let long = config.width.max(config.height);
    let traced = if long > traced_long_side {
        let s = f64::from(traced_long_side) / f64::from(long);
        SyntheticConfig {
            width: ((f64::from(config.width) * s).round() as u32).max(1),
            height: ((f64::from(config.height) * s).round() as u32).max(1),
            ..config.clone()
        }
    } else {
        config.clone()
    };
    let enlarged = (long > traced_long_side).then_some((config.width, config.height));
    let layout = layout(&traced);
    let masked = if config.panes.is_empty() {
        Vec::new()
    } else {
        masked_view_indices(config.views, config.masked_views)
    };
    let (points, tracks) = sparse_points(&layout, config.sparse_points, config.seed);
    let mut cameras = layout.cameras.clone();
    if let Some((w, h)) = enlarged {
        for cam in &mut cameras {
            cam.intrinsics = cam.intrinsics.resized(w, h);
            cam.name = cam.name.replace(".png", ".jpg");
        }
    }
    let test_views = cameras[..config.views].iter().step_by(8).map(|c| c.name.clone()).collect();
    Plan {
        planes: layout.planes.clone(),
        layout,
        cameras,
        lens: config.lens,
        points,
        tracks,
        test_views,
        masked,
        enlarged,
    }
}

impl Plan {
    /// View `i` as traced, at the photos' size: enlarged bilinearly (labels by nearest label)
    /// when they are larger than the traced size.
    pub fn photo(&self, view: View) -> View {
        match self.enlarged {
            None => view,
            Some((w, h)) => View {
                image: view.image.resized_bilinear(w, h),
                transmission: view.transmission.resized_bilinear(w, h),
                labels: view.labels.resized_nearest(w, h),
            },
        }
    }
}

/// Generate the scene: layout, cameras, ray-traced images with their truth, masks and points.
/// Photos longer than [`TRACED_LONG_SIDE`] are traced at that size and enlarged. Every photo is
/// held in memory: [`super::write_generated`] writes large scenes view by view instead.
pub fn generate(config: &SyntheticConfig) -> SyntheticScene {
    let plan = plan(config);
    let views = render_all(&plan.layout);
    let mut scene = SyntheticScene {
        cameras: plan.cameras.clone(),
        lens: plan.lens,
        images: Vec::with_capacity(views.len()),
        transmission: Vec::with_capacity(views.len()),
        masks: Vec::with_capacity(views.len()),
        planes: plan.planes.clone(),
        points: plan.points.clone(),
        tracks: plan.tracks.clone(),
        test_views: plan.test_views.clone(),
    };
    for (i, view) in views.into_iter().enumerate() {
        let view = plan.photo(view);
        scene.images.push(view.image);
        scene.transmission.push(view.transmission);
        scene.masks.push(plan.masked.contains(&i).then_some(view.labels));
    }
    scene
}
