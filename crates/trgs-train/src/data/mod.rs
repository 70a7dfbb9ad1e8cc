//! A scene folder loaded for training: every view's camera and image at the training resolution,
//! its glass mask if it has one, the train/test split, and the scene's extent (3DGS's
//! `cameras_extent`, which scales the position learning rate and the densification thresholds).
use anyhow::{Context, Result, bail};
use glam::DVec3;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use trgs_core::Image;
use trgs_core::io::{SceneFolder, Split, check_plane_count};
use trgs_core::lens::Undistortion;
use trgs_core::parallel::for_each_index;
use trgs_core::scene::{Camera, Material};

mod notes;
mod resize;

use notes::{LensNote, LoadNotes, Loaded, SoftMask, ViewReport};
pub use resize::resize_area_u8;

/// The longer side photos are trained at by default (the INRIA code's limit too): a 12 MP photo
/// at full size costs the renderer 6 times the pixels for detail the views rarely resolve.
pub const DEFAULT_LONG_SIDE: u32 = 1600;

/// How large the training images are.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Resolution {
    /// The images as they are.
    Original,
    /// The images as they are up to this longer side; larger ones scaled down to it.
    LongSide(u32),
    /// Divide both sides by this factor (rounded).
    Downscale(f64),
    /// This width; the height keeps the aspect ratio.
    Width(u32),
}

impl Default for Resolution {
    fn default() -> Self {
        Resolution::LongSide(DEFAULT_LONG_SIDE)
    }
}

impl Resolution {
    /// The resolution of a `--resolution W`, a `--downscale F` and a `--full-size` flag (in
    /// that order of precedence); without any, photos longer than `DEFAULT_LONG_SIDE` (1600) are
    /// scaled down to it.
    pub fn from_flags(width: Option<u32>, downscale: Option<f64>, full_size: bool) -> Self {
        match (width, downscale) {
            (Some(w), _) => Resolution::Width(w),
            (None, Some(f)) => Resolution::Downscale(f),
            (None, None) if full_size => Resolution::Original,
            (None, None) => Resolution::LongSide(DEFAULT_LONG_SIDE),
        }
    }
}

/// One view at the training resolution.
#[derive(Clone, Debug)]
pub struct View {
    pub camera: Camera,
    /// The photo, 8-bit RGB as it was stored (a quarter of f32's memory: a few hundred views at
    /// 1600 px fit beside the model).
    pub image: Image<u8>,
    /// Glass-mask labels (0: no glass, k: plane label k; soft edges moved to the nearest label,
    /// `trgs_core::io::masks`), nearest-neighbour resized.
    pub mask: Option<Image<u8>>,
    /// Which pixels the photo covers (1) and which it does not (0: the border of an undistorted
    /// photo, black in `image`), left out of the loss and the metrics. None: every pixel.
    pub covered: Option<Image<u8>>,
    /// How the photo was undistorted into this view (at this view's size), for other images of
    /// the same photo (`eval`'s ground truth).
    pub undistortion: Option<Undistortion>,
}

/// `progress(done, total)`: how many of the scene's photos are loaded, called from the loading
/// threads. It may borrow from its caller (`'a`).
pub type LoadProgress<'a> = dyn Fn(usize, usize) + Sync + 'a;

impl View {
    /// A view of `camera` showing `image` whole: no glass labels, every pixel covered, no lens.
    pub fn new(camera: Camera, image: Image<u8>) -> Self {
        Self { camera, image, mask: None, covered: None, undistortion: None }
    }
}

/// The loaded scene.
#[derive(Debug)]
pub struct TrainingData {
    pub train: Vec<View>,
    pub test: Vec<View>,
    /// Sparse points (position, colour in [0, 1]).
    pub points: Vec<(DVec3, [f64; 3])>,
    /// 1.1 times the largest distance of a training camera from their mean (3DGS).
    pub extent: f64,
    pub centre: DVec3,
    /// The material of each plane label (planes.json; glass where it says nothing).
    pub materials: Vec<(u32, Material)>,
    /// What loading did to the photos (scaled down, undistorted: a line per lens), for the
    /// run's log.
    pub notes: Vec<String>,
}

/// How [`TrainingData::load`] loads a scene folder.
#[derive(Clone, Copy, Default)]
pub struct LoadOptions<'a> {
    /// The size of the views (of their pinhole cameras: photos through a distorting lens are
    /// downscaled as they are, then undistorted into the pinhole view).
    pub resolution: Resolution,
    /// None: every view, for training. `Some(split)`: only the views `split` evaluates on (those
    /// of [`TrainingData::eval_views`] for the test split of a scene without test views), and
    /// only those decoded, in `test`: `eval` of a capture of hundreds of photos then loads only
    /// the few it measures. `train` then holds the views of a scene without test views and is
    /// empty otherwise; `extent` and `centre` are those of training; `materials` are only those
    /// of the labels in `train`'s masks.
    pub evaluate: Option<Split>,
    /// Called as `progress(done, total)` from the loading threads after each view.
    pub progress: Option<&'a LoadProgress<'a>>,
}

impl std::fmt::Debug for LoadOptions<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LoadOptions")
            .field("resolution", &self.resolution)
            .field("evaluate", &self.evaluate)
            .field("progress", &self.progress.is_some())
            .finish()
    }
}

impl LoadOptions<'_> {
    /// Every view at `resolution`, silently.
    pub fn at(resolution: Resolution) -> Self {
        Self { resolution, ..Self::default() }
    }
}

impl TrainingData {
    /// Load the views of `folder` as `options` say.
    pub fn load(folder: &SceneFolder, options: &LoadOptions<'_>) -> Result<Self> {
        let silent = |_: usize, _: usize| {};
        let progress = options.progress.unwrap_or(&silent);
        match options.evaluate {
            None => Self::load_training(folder, options.resolution, progress),
            Some(split) => Self::load_evaluation(folder, options.resolution, split, progress),
        }
    }

    fn load_training(
        folder: &SceneFolder,
        resolution: Resolution,
        progress: &LoadProgress<'_>,
    ) -> Result<Self> {
        let every: Vec<usize> = (0..folder.views.len()).collect();
        let (views, notes) = load_views(folder, &every, resolution, progress)?;
        let (test, train): (Vec<View>, Vec<View>) =
            views.into_iter().partition(|v| folder.is_test(&v.camera.name));
        if train.is_empty() {
            bail!("{}: every view is a test view; nothing to train on", folder.root.display());
        }
        Self::assemble(folder, train, test, notes.lines(resolution))
    }

    fn load_evaluation(
        folder: &SceneFolder,
        resolution: Resolution,
        split: Split,
        progress: &LoadProgress<'_>,
    ) -> Result<Self> {
        let (tests, trains): (Vec<usize>, Vec<usize>) =
            (0..folder.views.len()).partition(|&i| folder.is_test(&folder.views[i].camera.name));
        let no_test_views = split == Split::Test && tests.is_empty();
        let chosen = match split {
            Split::Test if no_test_views => trains[..trains.len().min(4)].to_vec(),
            Split::Test => tests,
            Split::Train => trains,
            Split::All => (0..folder.views.len()).collect(),
        };
        if chosen.is_empty() {
            bail!("{}: no views in the {} split", folder.root.display(), split.name());
        }
        let (mut views, notes) = load_views(folder, &chosen, resolution, progress)?;
        if split == Split::All {
            views.sort_by(|a, b| a.camera.name.cmp(&b.camera.name));
        }
        let (train, test) = if no_test_views { (views, Vec::new()) } else { (Vec::new(), views) };
        Self::assemble(folder, train, test, notes.lines(resolution))
    }

    /// The loaded views with the folder's points, materials, and the extent of its training
    /// cameras (their poses do not depend on which photos were decoded); an error when the
    /// views' masks together hold more labels than `trgs_core::io::MAX_PLANES`, before any
    /// training work starts.
    fn assemble(
        folder: &SceneFolder,
        train: Vec<View>,
        test: Vec<View>,
        notes: Vec<String>,
    ) -> Result<Self> {
        let mut labels: Vec<u32> = train
            .iter()
            .chain(&test)
            .filter_map(|v| v.mask.as_ref())
            .flat_map(|m| m.data.iter().filter(|&&v| v > 0).map(|&v| u32::from(v)))
            .collect();
        labels.sort_unstable();
        labels.dedup();
        if let Err(problem) = check_plane_count(&labels) {
            bail!("{}: the glass masks together hold {problem}", folder.root.display());
        }
        let training = folder.views.iter().filter(|v| !folder.is_test(&v.camera.name));
        let centres: Vec<DVec3> = training.map(|v| v.camera.pose.centre()).collect();
        let centre = centres.iter().copied().sum::<DVec3>() / centres.len().max(1) as f64;
        let radius = centres.iter().map(|c| c.distance(centre)).fold(0.0, f64::max);
        // One camera (or all at one spot): the scene's scale is unknown; 1 as 3DGS would give.
        let extent = if radius > 0.0 { 1.1 * radius } else { 1.0 };
        let points = folder
            .points
            .iter()
            .map(|(p, c)| (DVec3::from_array(*p), c.map(|v| f64::from(v) / 255.0)))
            .collect();
        let mut data = Self { train, test, points, extent, centre, materials: Vec::new(), notes };
        data.materials = data.mask_labels().into_iter().map(|l| (l, folder.material(l))).collect();
        Ok(data)
    }

    /// The width and height of the training images (of the evaluated ones, for data loaded by
    /// [`LoadOptions::evaluate`]).
    pub fn size(&self) -> (u32, u32) {
        let c = &self.train.first().or(self.test.first()).expect("a loaded view").camera;
        (c.width(), c.height())
    }

    /// The views a run is evaluated on: the test split, or the first four training views of a
    /// scene without one.
    pub fn eval_views(&self) -> &[View] {
        if self.test.is_empty() { &self.train[..self.train.len().min(4)] } else { &self.test }
    }

    /// What `eval_views` holds, for reports: "test", or a scene without test views says that
    /// its scores are on training views.
    pub fn eval_views_name(&self) -> &'static str {
        if self.test.is_empty() { "training (the scene has no test views)" } else { "test" }
    }

    /// The glass-mask labels some training view uses, ascending.
    pub fn mask_labels(&self) -> Vec<u32> {
        let mut labels: Vec<u32> = self
            .train
            .iter()
            .filter_map(|v| v.mask.as_ref())
            .flat_map(|m| m.data.iter().filter(|&&v| v > 0).map(|&v| u32::from(v)))
            .collect();
        labels.sort_unstable();
        labels.dedup();
        labels
    }
}

/// The views of `folder` that have a glass mask, at `resolution`: what `trgs merge` holds the
/// blocks' planes against (a capture's masked views are few).
pub fn load_masked_views(folder: &SceneFolder, resolution: Resolution) -> Result<Vec<View>> {
    let masked: Vec<usize> =
        (0..folder.views.len()).filter(|&i| folder.views[i].mask_path.is_some()).collect();
    let silent = |_: usize, _: usize| {};
    Ok(load_views(folder, &masked, resolution, &silent)?.0)
}

/// Loading threads: enough to keep the cores decoding, few enough that the full-size photos
/// they hold at once (36 MB for 12 MP at 8 bits) stay small.
const LOAD_THREADS: usize = 8;

/// The views `indices` of `folder` at `resolution`, in that order, and what loading did to
/// them, decoded on up to [`LOAD_THREADS`] threads. The first failure in that order is the error; the other threads
/// stop taking views once one fails.
fn load_views(
    folder: &SceneFolder,
    indices: &[usize],
    resolution: Resolution,
    progress: &LoadProgress<'_>,
) -> Result<(Vec<View>, LoadNotes)> {
    let n = indices.len();
    let done = AtomicUsize::new(0);
    let slots: Vec<Mutex<Option<Result<Loaded>>>> = (0..n).map(|_| Mutex::new(None)).collect();
    for_each_index(n, LOAD_THREADS, |i| {
        let loaded = load_view(folder, indices[i], resolution);
        let ok = loaded.is_ok();
        if let Ok(mut slot) = slots[i].lock() {
            *slot = Some(loaded);
        }
        progress(done.fetch_add(1, Ordering::Relaxed) + 1, n);
        ok
    });
    let mut views = Vec::with_capacity(n);
    let mut notes = LoadNotes::default();
    for slot in slots {
        match slot.into_inner().ok().flatten() {
            Some(loaded) => {
                let (view, report) = loaded?;
                notes.add(report);
                views.push(view);
            }
            // Not taken: a view failed, and its error comes first or later in this loop.
            None => continue,
        }
    }
    Ok((views, notes))
}

/// One view of `folder` at `resolution`, and what loading did to it.
fn load_view(folder: &SceneFolder, i: usize, resolution: Resolution) -> Result<Loaded> {
    let spec = &folder.views[i];
    let photo = folder.load_image(i)?;
    let mask = folder.load_mask(i)?;
    let soft = match (&mask, &spec.mask_path) {
        (Some(m), Some(path)) if m.soft_pixels > 0 => {
            let shown = path.strip_prefix(&folder.root).unwrap_or(path);
            Some(SoftMask { path: shown.display().to_string(), pixels: m.soft_pixels })
        }
        _ => None,
    };
    let labels = mask.map(|m| m.labels);
    let full = (spec.camera.width(), spec.camera.height());
    let (w, h) = target_size(full.0, full.1, resolution)
        .with_context(|| format!("resizing {}", spec.image_path.display()))?;
    let scaled = ((w, h) != full).then_some((full, (w, h)));
    let mut report = ViewReport { size: (w, h), scaled, lens: None, soft };
    let mut camera = spec.camera.clone();
    camera.intrinsics = camera.intrinsics.resized(w, h);
    let Some(u) = &spec.undistortion else {
        let view = View {
            camera,
            image: resize_area_u8(&photo, w, h).quantised(),
            mask: labels.map(|m| m.resized_nearest(w, h)),
            covered: None,
            undistortion: None,
        };
        return Ok((view, report));
    };
    let u = u.resized(w, h);
    let (pw, ph) = u.photo_size();
    let context = || format!("undistorting {}", spec.image_path.display());
    let (image, covered) = u.warp_image(&resize_area_u8(&photo, pw, ph)).with_context(context)?;
    let mask = match labels {
        Some(m) => Some(u.warp_labels(&m.resized_nearest(pw, ph)).with_context(context)?),
        None => None,
    };
    let blank = covered.data.iter().filter(|&&c| c == 0).count();
    report.lens = Some(LensNote {
        lens: u.lens.model.clone(),
        describe: u.lens.distortion.describe(),
        photo: spec.photo_size(),
        pinhole: full,
        views: 1,
        blank,
        pixels: covered.data.len(),
    });
    let covered = (blank > 0).then_some(covered);
    let view = View { camera, image: image.quantised(), mask, covered, undistortion: Some(u) };
    Ok((view, report))
}

/// The size of an image of `w x h` at `resolution`.
pub fn target_size(w: u32, h: u32, resolution: Resolution) -> Result<(u32, u32)> {
    let (tw, th) = match resolution {
        Resolution::Original => (w, h),
        Resolution::LongSide(side) if w.max(h) > side => {
            let s = f64::from(side) / f64::from(w.max(h));
            ((f64::from(w) * s).round() as u32, (f64::from(h) * s).round() as u32)
        }
        Resolution::LongSide(_) => (w, h),
        Resolution::Downscale(f) => {
            if !(f >= 1.0 && f.is_finite()) {
                bail!("--downscale {f}: expected a factor of at least 1");
            }
            ((f64::from(w) / f).round() as u32, (f64::from(h) / f).round() as u32)
        }
        Resolution::Width(tw) => (tw, (f64::from(h) * f64::from(tw) / f64::from(w)).round() as u32),
    };
    if tw == 0 || th == 0 {
        bail!("{w}x{h} at {resolution:?} leaves an empty image");
    }
    Ok((tw, th))
}

#[cfg(test)]
mod tests {
    use super::*;
    use trgs_core::io::{read_glass_mask, write_glass_mask};
    use trgs_core::scratch::ScratchDir;

    /// The small synthetic scene written to a folder, each of its glass masks replaced by what
    /// `mask(view, width, height)` paints.
    fn scene_with_masks(tag: &str, mask: impl Fn(usize, u32, u32) -> Vec<u8>) -> ScratchDir {
        let dir = ScratchDir::new(tag);
        let scene = trgs_synthetic::generate(&trgs_synthetic::SyntheticConfig::small());
        trgs_synthetic::write_dataset(&scene, &dir).expect("write the dataset");
        let mut paths: Vec<_> = std::fs::read_dir(dir.join("glass_masks"))
            .expect("masks")
            .map(|e| e.expect("entry").path())
            .collect();
        paths.sort();
        assert!(paths.len() >= 3, "the scene has masked views");
        for (k, path) in paths.iter().enumerate() {
            let (w, h) = (scene.cameras[0].width(), scene.cameras[0].height());
            let data = mask(k, w, h);
            let image = Image { width: w, height: h, channels: 1, data };
            write_glass_mask(path, &image).expect("write a mask");
        }
        dir
    }

    #[test]
    fn soft_edged_masks_load_as_their_labels_with_a_note() {
        // A 0/255 disc with a ramp of grey a few pixels wide at its edge, as a soft brush paints.
        let disc = |_: usize, w: u32, h: u32| -> Vec<u8> {
            let (cx, cy, r) = (f64::from(w) / 2.0, f64::from(h) / 2.0, f64::from(h) / 3.0);
            (0..w * h)
                .map(|i| {
                    let (x, y) = (f64::from(i % w) + 0.5, f64::from(i / w) + 0.5);
                    let d = (x - cx).hypot(y - cy);
                    (255.0 * ((r - d) / 3.0 + 0.5).clamp(0.0, 1.0)).round() as u8
                })
                .collect()
        };
        let dir = scene_with_masks("soft-masks", disc);
        let folder = SceneFolder::open(&dir).expect("open");
        let data =
            TrainingData::load(&folder, &LoadOptions::at(Resolution::Original)).expect("load");
        assert_eq!(data.mask_labels(), [255], "one plane, not one per grey level");
        let note = data.notes.iter().find(|n| n.contains("soft edges")).expect("a soft-edge note");
        let masked = data.train.iter().filter(|v| v.mask.is_some()).count();
        assert!(note.starts_with(&format!("{masked} glass masks have soft edges")), "{note}");
        assert!(note.contains("(first: glass_masks/") && note.contains("nearest label"), "{note}");
        let first = folder.views.iter().find_map(|v| v.mask_path.clone()).expect("a mask");
        let read = read_glass_mask(&first, 64, 48).expect("read");
        assert!(note.contains(&format!("{} pixels between labels", read.soft_pixels)), "{note}");
    }

    #[test]
    fn masks_with_more_labels_than_planes_together_are_refused() {
        // Three flat bands a mask, of labels no other mask uses: nine labels in all.
        let bands = |k: usize, w: u32, h: u32| -> Vec<u8> {
            (0..w * h).map(|i| (3 * k as u32 + 1 + 3 * (i % w) / w) as u8).collect()
        };
        let dir = scene_with_masks("many-masks", bands);
        let folder = SceneFolder::open(&dir).expect("open");
        let err = TrainingData::load(&folder, &LoadOptions::at(Resolution::Original))
            .expect_err("nine labels")
            .to_string();
        for part in ["9 labels", "1, 2, 3, 4, 5, 6, 7, 8, 9", "more than the 8 planes", "plane k"] {
            assert!(err.contains(part), "{err}");
        }
    }

    #[test]
    fn sizes_follow_the_resolution() {
        assert_eq!(
            target_size(1000, 750, Resolution::Downscale(4.0)).expect("valid size"),
            (250, 188)
        );
        assert_eq!(target_size(1000, 750, Resolution::Width(256)).expect("valid size"), (256, 192));
        assert!(target_size(10, 10, Resolution::Downscale(0.5)).is_err());
        assert!(target_size(10, 10, Resolution::Width(0)).is_err());
        // The default keeps photos up to 1600 px and scales larger ones down to it.
        let default = Resolution::from_flags(None, None, false);
        assert_eq!(target_size(4000, 3000, default).expect("valid"), (1600, 1200));
        assert_eq!(target_size(3000, 4000, default).expect("valid"), (1200, 1600));
        assert_eq!(target_size(1280, 960, default).expect("valid"), (1280, 960));
        let full = Resolution::from_flags(None, None, true);
        assert_eq!(target_size(4000, 3000, full).expect("valid"), (4000, 3000));
    }
}
