//! A scene folder (docs/ARCHITECTURE.md, "File formats"): cameras and images from COLMAP
//! (`sparse/0/` + `images/`) or `transforms.json`, plus the optional `glass_masks/`,
//! `planes.json` and `test_views.txt`.
//! Opening checks everything that is cheap to check (files exist, cameras are pinhole and valid,
//! test names exist); pixels are read on demand, one view at a time.
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use super::FormatError;
use super::colmap::ColmapModel;
use super::masks::{GlassMask, mask_path, read_glass_mask};
use super::planes_json::{PlaneSpec, read_planes_json};
use super::ply::read_point_cloud_ply;
use super::png::read_rgb8_image;
use super::test_split::{default_test_views, read_test_views};
use super::transforms::{
    TransformsFrame, name_by_relative_path_if_needed, read_transforms, transforms_point_cloud,
};
use crate::image::Image;
use crate::lens::Undistortion;
use crate::scene::{Camera, Material};

/// One training or test view: its camera (named by the image), its image and its glass mask.
/// A photo through a distorting lens has an `undistortion`, and its camera is the pinhole view
/// the photo is resampled into; the files themselves are the photo's own size.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewSpec {
    pub camera: Camera,
    pub image_path: PathBuf,
    pub mask_path: Option<PathBuf>,
    pub undistortion: Option<Undistortion>,
}

impl ViewSpec {
    /// The size of the image file (and mask): the photo's, before any undistortion.
    pub fn photo_size(&self) -> (u32, u32) {
        match &self.undistortion {
            Some(u) => u.photo_size(),
            None => (self.camera.width(), self.camera.height()),
        }
    }
}

/// Which of a scene folder's views a command works on, by its test split.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Split {
    /// The test views (`test_views.txt`, or every 8th image).
    #[default]
    Test,
    /// The views training uses: every view outside the test split.
    Train,
    All,
}

impl Split {
    pub const NAMES: &'static str = "test, train or all";

    /// Whether a view whose test membership is `is_test` belongs to this split.
    pub fn holds(self, is_test: bool) -> bool {
        match self {
            Split::Test => is_test,
            Split::Train => !is_test,
            Split::All => true,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Split::Test => "test",
            Split::Train => "train",
            Split::All => "all",
        }
    }
}

impl std::str::FromStr for Split {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "test" => Ok(Split::Test),
            "train" => Ok(Split::Train),
            "all" => Ok(Split::All),
            _ => Err(format!("{s:?}: expected {}", Split::NAMES)),
        }
    }
}

/// An opened scene folder. Views are sorted by image name.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneFolder {
    pub root: PathBuf,
    pub views: Vec<ViewSpec>,
    /// The sparse point cloud (position, colour) for initialisation: COLMAP's points3D, or the
    /// PLY a transforms.json names as `ply_file_path` (nerfstudio); empty without one.
    pub points: Vec<([f64; 3], [u8; 3])>,
    pub plane_specs: Vec<PlaneSpec>,
    /// Names of the test views: `test_views.txt`, or every 8th image.
    pub test_views: Vec<String>,
}

impl SceneFolder {
    pub fn open(root: &Path) -> Result<Self, FormatError> {
        if !root.is_dir() {
            return Err(FormatError::new(root, "not a folder (expected a scene folder)"));
        }
        // The test views a Blender scene's split files name (None: the folder's own rule).
        let mut split_file_tests: Option<Vec<String>> = None;
        let (cameras, points) = if let Some(sparse) = colmap_dir(root) {
            open_colmap(root, &sparse)?
        } else if root.join("transforms.json").is_file() {
            let json = root.join("transforms.json");
            let frames = read_transforms(&json)?;
            let points = match transforms_point_cloud(&json)? {
                Some(ply) if !ply.is_file() => {
                    let problem = "named by `ply_file_path` in transforms.json, but missing";
                    return Err(FormatError::new(&ply, problem));
                }
                Some(ply) => read_point_cloud_ply(&ply)?,
                None => Vec::new(),
            };
            (frames.into_iter().map(|f| (f.camera, f.image_path, f.undistortion)).collect(), points)
        } else if root.join("transforms_train.json").is_file() {
            let (frames, tests) = read_blender_split_files(root)?;
            split_file_tests = tests;
            let cameras =
                frames.into_iter().map(|f| (f.camera, f.image_path, f.undistortion)).collect();
            (cameras, Vec::new())
        } else {
            return Err(FormatError::new(
                root,
                "not a scene folder: found neither a COLMAP model (sparse/0/cameras.bin or \
                 sparse/0/cameras.txt, with images/) nor transforms.json (or Blender's \
                 transforms_train.json and transforms_test.json); to make one from a folder of \
                 photos or video frames: `prepare PHOTOS --out SCENE` (COLMAP), then \
                 `train --data SCENE`",
            ));
        };
        if cameras.is_empty() {
            return Err(FormatError::new(
                root,
                "the scene has no views (no registered images or frames)",
            ));
        }

        let masks_dir = root.join("glass_masks");
        let mut views = Vec::with_capacity(cameras.len());
        for (camera, image_path, undistortion) in cameras {
            if !image_path.is_file() {
                return Err(FormatError::new(
                    &image_path,
                    format!("the image of view {:?} is missing", camera.name),
                ));
            }
            let mask_path = mask_path(&masks_dir, &camera.name);
            views.push(ViewSpec { camera, image_path, mask_path, undistortion });
        }
        views.sort_by(|a, b| a.camera.name.cmp(&b.camera.name));
        if let Some(w) = views.windows(2).find(|w| w[0].camera.name == w[1].camera.name) {
            let problem = format!(
                "two views are named {:?} ({} and {}); image names must be unique",
                w[0].camera.name,
                w[0].image_path.display(),
                w[1].image_path.display()
            );
            return Err(FormatError::new(root, problem));
        }

        let planes_path = root.join("planes.json");
        let plane_specs =
            if planes_path.is_file() { read_planes_json(&planes_path)? } else { Vec::new() };
        let names: Vec<String> = views.iter().map(|v| v.camera.name.clone()).collect();
        let split_path = root.join("test_views.txt");
        let test_views = if split_path.is_file() {
            read_test_views(&split_path, &names)?
        } else if let Some(tests) = split_file_tests {
            tests
        } else {
            default_test_views(&names)
        };
        Ok(Self { root: root.to_path_buf(), views, points, plane_specs, test_views })
    }

    fn view(&self, i: usize) -> Result<&ViewSpec, FormatError> {
        self.views.get(i).ok_or_else(|| {
            FormatError::new(
                &self.root,
                format!("view {i} does not exist (the scene has {})", self.views.len()),
            )
        })
    }

    /// The RGB image file of view `i` as it is, 8 bits per sample (the photo's own size,
    /// distorted if its lens distorts: [`ViewSpec::undistortion`] resamples it).
    pub fn load_image(&self, i: usize) -> Result<Image<u8>, FormatError> {
        let view = self.view(i)?;
        let image = read_rgb8_image(&view.image_path)?;
        let (w, h) = view.photo_size();
        if (image.width, image.height) != (w, h) {
            let problem = format!(
                "the image is {}x{} but its camera expects {w}x{h} (images must match the camera model; \
                 resize them or use the matching model)",
                image.width, image.height
            );
            return Err(FormatError::new(&view.image_path, problem));
        }
        Ok(image)
    }

    /// The glass mask of view `i`, if it has one, at the photo's own size, its soft edges moved
    /// to the nearest label ([`super::masks`]).
    pub fn load_mask(&self, i: usize) -> Result<Option<GlassMask>, FormatError> {
        let view = self.view(i)?;
        let (w, h) = view.photo_size();
        match &view.mask_path {
            Some(path) => read_glass_mask(path, w, h).map(Some),
            None => Ok(None),
        }
    }

    pub fn is_test(&self, name: &str) -> bool {
        self.test_views.iter().any(|t| t == name)
    }

    /// Every plane label (k > 0) that some mask uses, ascending. Reads every mask.
    pub fn mask_labels(&self) -> Result<Vec<u32>, FormatError> {
        let mut labels = BTreeSet::new();
        for i in 0..self.views.len() {
            if let Some(mask) = self.load_mask(i)? {
                let data = &mask.labels.data;
                labels.extend(data.iter().filter(|&&v| v > 0).map(|&v| u32::from(v)));
            }
        }
        Ok(labels.into_iter().collect())
    }

    /// The material of plane `label`: from `planes.json`, glass when it does not list the label.
    pub fn material(&self, label: u32) -> Material {
        self.plane_specs.iter().find(|s| s.label == label).map(|s| s.material).unwrap_or_default()
    }
}

/// `sparse/0/` (COLMAP's layout) or `sparse/` itself, whichever holds a model.
pub fn colmap_dir(root: &Path) -> Option<PathBuf> {
    let has_model = |d: &Path| d.join("cameras.bin").is_file() || d.join("cameras.txt").is_file();
    [root.join("sparse").join("0"), root.join("sparse")].into_iter().find(|d| has_model(d))
}

type Cameras = Vec<(Camera, PathBuf, Option<Undistortion>)>;
type Points = Vec<([f64; 3], [u8; 3])>;

fn open_colmap(root: &Path, sparse: &Path) -> Result<(Cameras, Points), FormatError> {
    let model = ColmapModel::read(sparse)?;
    let cameras_file = if sparse.join("cameras.bin").is_file() {
        sparse.join("cameras.bin")
    } else {
        sparse.join("cameras.txt")
    };
    let images_dir = root.join("images");
    // `views` cannot know the file; name the one it came from.
    let views = model
        .views()
        .map_err(|e| FormatError { path: cameras_file.clone(), problem: e.problem })?;
    let cameras = model
        .images
        .iter()
        .zip(views)
        .map(|(image, (camera, undistortion))| (camera, images_dir.join(&image.name), undistortion))
        .collect();
    let points = model.points.iter().map(|p| (p.xyz, p.rgb)).collect();
    Ok((cameras, points))
}

/// A NeRF-synthetic (Blender) folder's `transforms_train.json` and `transforms_test.json`: every
/// frame of both (validation frames are left out, as 3DGS does), named by their paths
/// (`train/r_0.png`, `test/r_0.png`: the two files reuse file names), and the test frames' names,
/// which are the test split unless `test_views.txt` says otherwise.
fn read_blender_split_files(
    root: &Path,
) -> Result<(Vec<TransformsFrame>, Option<Vec<String>>), FormatError> {
    let mut frames = read_transforms(&root.join("transforms_train.json"))?;
    let train = frames.len();
    let test_file = root.join("transforms_test.json");
    if test_file.is_file() {
        frames.extend(read_transforms(&test_file)?);
    }
    name_by_relative_path_if_needed(&mut frames, root);
    // Without test frames the folder's own rule holds (every 8th image), as for transforms.json.
    let tests: Vec<String> = frames[train..].iter().map(|f| f.camera.name.clone()).collect();
    Ok((frames, (!tests.is_empty()).then_some(tests)))
}

/// The file stem under which outputs of view `name` are written (renders, layers): the name
/// without its extension, keeping its folders (`train/r_0.png` -> `train/r_0`, so that views of
/// the same file name in two folders stay apart) and dropping any `..`, root or `.` component
/// (an output never lands outside its folder). None when nothing is left.
pub fn view_output_stem(name: &str) -> Option<String> {
    let parts = plain_components(Path::new(name));
    let (last, folders) = parts.split_last()?;
    let stem = Path::new(last).file_stem().map(|s| s.to_string_lossy().into_owned())?;
    let mut out: Vec<String> = folders.to_vec();
    out.push(stem);
    Some(out.join("/"))
}

/// The names a path walks through, without its root, `.` and `..` components.
pub(crate) fn plain_components(path: &Path) -> Vec<String> {
    path.components()
        .filter_map(|c| match c {
            std::path::Component::Normal(s) => Some(s.to_string_lossy().into_owned()),
            _ => None,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::colmap::{ColmapCamera, ColmapImage, ColmapPoint};
    use crate::io::test_util::{assert_mentions, scratch_dir};
    use crate::io::transforms::{TransformsFrame, write_transforms};
    use crate::io::{write_glass_mask, write_png_rgb};
    use crate::scene::{Intrinsics, Pose};

    #[test]
    fn splits_parse_and_hold_their_views() {
        for split in [Split::Test, Split::Train, Split::All] {
            assert_eq!(split.name().parse::<Split>(), Ok(split));
        }
        let err = "val".parse::<Split>().expect_err("no such split");
        assert!(err.contains("\"val\"") && err.contains(Split::NAMES), "{err}");
        assert!(Split::Test.holds(true) && !Split::Test.holds(false));
        assert!(Split::Train.holds(false) && !Split::Train.holds(true));
        assert!(Split::All.holds(true) && Split::All.holds(false));
    }

    fn colmap_scene(tag: &str) -> crate::scratch::ScratchDir {
        let root = scratch_dir(tag);
        let image = |id, name: &str| ColmapImage {
            id,
            qvec: [1.0, 0.0, 0.0, 0.0],
            tvec: [0.0, 0.0, f64::from(id)],
            camera_id: 1,
            name: name.into(),
            points2d: vec![],
        };
        let model = ColmapModel {
            cameras: vec![ColmapCamera {
                id: 1,
                model: "PINHOLE".into(),
                width: 4,
                height: 3,
                params: vec![5.0, 5.0, 2.0, 1.5],
            }],
            images: vec![image(1, "b.png"), image(2, "a.png")],
            points: vec![ColmapPoint {
                id: 1,
                xyz: [1.0, 2.0, 3.0],
                rgb: [9, 8, 7],
                error: 0.1,
                track: vec![],
            }],
        };
        model.write_binary(&root.join("sparse/0")).expect("model");
        for name in ["a.png", "b.png"] {
            write_png_rgb(&root.join("images").join(name), &Image::filled(4, 3, 3, 0.5))
                .expect("image");
        }
        root
    }

    #[test]
    fn opens_colmap_scene_with_masks_planes_and_split() {
        let root = colmap_scene("ds-colmap");
        let mask = Image {
            width: 4,
            height: 3,
            channels: 1,
            data: vec![0, 0, 2, 2, 0, 0, 2, 2, 0, 0, 0, 5],
        };
        write_glass_mask(&root.join("glass_masks/b.png"), &mask).expect("mask");
        std::fs::write(
            root.join("planes.json"),
            r#"{"planes": [{"label": 2, "material": "mirror"}]}"#,
        )
        .expect("planes");
        std::fs::write(root.join("test_views.txt"), "b.png\n").expect("split");
        let scene = SceneFolder::open(&root).expect("open");
        let names: Vec<&str> = scene.views.iter().map(|v| v.camera.name.as_str()).collect();
        assert_eq!(names, ["a.png", "b.png"]);
        assert_eq!(scene.views[0].mask_path, None);
        assert_eq!(scene.views[1].mask_path, Some(root.join("glass_masks/b.png")));
        assert_eq!(scene.points, [([1.0, 2.0, 3.0], [9, 8, 7])]);
        assert!(scene.is_test("b.png") && !scene.is_test("a.png"));
        assert_eq!(scene.load_image(1).expect("image").data[0], 128);
        assert_eq!(scene.load_mask(1).expect("mask").map(|m| m.labels), Some(mask));
        assert_eq!(scene.load_mask(0).expect("no mask"), None);
        assert_eq!(scene.mask_labels().expect("labels"), [2, 5]);
        assert_eq!((scene.material(2), scene.material(5)), (Material::Mirror, Material::Glass));
        assert_mentions(&scene.load_image(7).expect_err("index"), &["view 7", "has 2"]);
    }

    #[test]
    fn default_split_without_test_views() {
        let root = colmap_scene("ds-split");
        let scene = SceneFolder::open(&root).expect("open");
        assert_eq!(scene.test_views, ["a.png"]);
    }

    #[test]
    fn empty_folder_says_what_was_looked_for() {
        let root = scratch_dir("ds-empty");
        let err = SceneFolder::open(&root).expect_err("empty");
        assert_mentions(
            &err,
            &[&root.display().to_string(), "sparse/0/cameras.bin", "transforms.json"],
        );
        std::fs::write(root.join("transforms_train.json"), "{}").expect("write");
        let err = SceneFolder::open(&root).expect_err("blender split");
        assert_mentions(&err, &["transforms_train.json", "frames"]);
        std::fs::write(root.join("transforms.json"), r#"{"frames": []}"#).expect("write");
        assert_mentions(&SceneFolder::open(&root).expect_err("no frames"), &["no views"]);
        let err = SceneFolder::open(&root.join("nope")).expect_err("missing");
        assert_mentions(&err, &["nope", "not a folder"]);
    }

    #[test]
    fn missing_image_is_named_at_open() {
        let root = colmap_scene("ds-missing");
        std::fs::remove_file(root.join("images/b.png")).expect("rm");
        let err = SceneFolder::open(&root).expect_err("missing image");
        assert_mentions(&err, &["images/b.png", "missing"]);
    }

    #[test]
    fn wrong_image_size_names_both_sizes() {
        let root = colmap_scene("ds-size");
        write_png_rgb(&root.join("images/a.png"), &Image::new(5, 3, 3)).expect("image");
        let scene = SceneFolder::open(&root).expect("open");
        assert_mentions(&scene.load_image(0).expect_err("size"), &["images/a.png", "5x3", "4x3"]);
    }

    #[test]
    fn output_stems_keep_folders_and_stay_inside() {
        assert_eq!(view_output_stem("0001.png").as_deref(), Some("0001"));
        assert_eq!(view_output_stem("./train/r_0.png").as_deref(), Some("train/r_0"));
        assert_eq!(view_output_stem("test/r_0").as_deref(), Some("test/r_0"));
        assert_eq!(view_output_stem("../../etc/x.png").as_deref(), Some("etc/x"));
        assert_eq!(view_output_stem("/abs/a.b.png").as_deref(), Some("abs/a.b"));
        assert_eq!(view_output_stem(""), None);
        assert_eq!(view_output_stem(".."), None);
    }

    #[test]
    fn distorted_colmap_camera_opens_as_its_pinhole_view() {
        let root = colmap_scene("ds-opencv");
        let sparse = root.join("sparse/0");
        let mut model = ColmapModel::read(&sparse).expect("read");
        model.cameras[0].model = "OPENCV".into();
        model.cameras[0].params = vec![5.0, 5.0, 2.0, 1.5, 0.1, 0.0, 0.0, 0.0];
        model.write_binary(&sparse).expect("write");
        let scene = SceneFolder::open(&root).expect("OPENCV is undistorted");
        let u = scene.views[0].undistortion.as_ref().expect("a lens");
        assert_eq!(scene.views[0].photo_size(), (4, 3), "the files keep the photo's size");
        assert_eq!(scene.views[0].camera.intrinsics, u.pinhole);
        assert_eq!(scene.load_image(0).expect("photo").width, 4);
        // A lens that does not invert over the photo is refused, naming the file.
        model.cameras[0].params = vec![1.0, 1.0, 2.0, 1.5, -0.5, 0.0, 0.0, 0.0];
        model.write_binary(&sparse).expect("write");
        let err = SceneFolder::open(&root).expect_err("folds");
        assert_mentions(&err, &["sparse/0/cameras.bin", "camera 1", "OPENCV"]);
    }

    #[test]
    fn opens_transforms_scene() {
        let root = scratch_dir("ds-transforms");
        let k = Intrinsics { fx: 5.0, fy: 5.0, cx: 2.0, cy: 1.5, width: 4, height: 3 };
        let frames: Vec<TransformsFrame> = ["z.png", "y.png"]
            .iter()
            .map(|n| {
                let image_path = root.join("rgb").join(n);
                write_png_rgb(&image_path, &Image::new(4, 3, 3)).expect("image");
                TransformsFrame {
                    camera: Camera::new(*n, k, Pose::default()),
                    image_path,
                    undistortion: None,
                }
            })
            .collect();
        write_transforms(&root.join("transforms.json"), &frames).expect("json");
        write_glass_mask(&root.join("glass_masks/z.png.png"), &Image::new(4, 3, 1)).expect("mask");
        let scene = SceneFolder::open(&root).expect("open");
        assert_eq!(scene.views[0].camera.name, "y.png");
        assert_eq!(scene.views[1].mask_path, Some(root.join("glass_masks/z.png.png")));
        assert!(scene.points.is_empty());
        assert_eq!(scene.mask_labels().expect("labels"), Vec::<u32>::new());

        // nerfstudio's `ply_file_path`: the sparse points seed the scene; a missing file is named.
        let json_path = root.join("transforms.json");
        let mut json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json_path).expect("json"))
                .expect("parse");
        json["ply_file_path"] = "sparse_pc.ply".into();
        std::fs::write(&json_path, json.to_string()).expect("json");
        let err = SceneFolder::open(&root).expect_err("missing cloud");
        assert_mentions(&err, &["sparse_pc.ply", "ply_file_path", "missing"]);
        let ply = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                   property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n\
                   end_header\n0.5 0 2 10 20 30\n";
        std::fs::write(root.join("sparse_pc.ply"), ply).expect("ply");
        let scene = SceneFolder::open(&root).expect("open with points");
        assert_eq!(scene.points, vec![([0.5, 0.0, 2.0], [10, 20, 30])]);
    }

    #[test]
    fn blender_split_files_are_read_with_their_test_split() {
        let root = scratch_dir("ds-blender");
        let k = Intrinsics { fx: 5.0, fy: 5.0, cx: 2.0, cy: 1.5, width: 4, height: 3 };
        // NeRF-synthetic reuses file names across its splits: train/r_0 and test/r_0.
        for (file, folder, names) in [
            ("transforms_train.json", "train", &["r_0.png", "r_1.png"][..]),
            ("transforms_test.json", "test", &["r_0.png"][..]),
            ("transforms_val.json", "val", &["r_0.png"][..]),
        ] {
            let frames: Vec<TransformsFrame> = names
                .iter()
                .map(|n| {
                    let image_path = root.join(folder).join(n);
                    write_png_rgb(&image_path, &Image::new(4, 3, 3)).expect("image");
                    TransformsFrame {
                        camera: Camera::new(*n, k, Pose::default()),
                        image_path,
                        undistortion: None,
                    }
                })
                .collect();
            write_transforms(&root.join(file), &frames).expect("json");
        }
        write_glass_mask(&root.join("glass_masks/test/r_0.png"), &Image::new(4, 3, 1))
            .expect("mask");
        let scene = SceneFolder::open(&root).expect("open");
        let names: Vec<&str> = scene.views.iter().map(|v| v.camera.name.as_str()).collect();
        assert_eq!(names, ["test/r_0.png", "train/r_0.png", "train/r_1.png"], "no val frames");
        assert_eq!(scene.test_views, ["test/r_0.png"]);
        assert_eq!(scene.views[0].mask_path, Some(root.join("glass_masks/test/r_0.png")));
        assert_eq!(scene.views[1].mask_path, None);
        // The same frames merged into one transforms.json get the same names.
        let mut merged =
            crate::io::read_transforms(&root.join("transforms_train.json")).expect("train");
        merged
            .extend(crate::io::read_transforms(&root.join("transforms_test.json")).expect("test"));
        write_transforms(&root.join("transforms.json"), &merged).expect("merged");
        let scene = SceneFolder::open(&root).expect("open merged");
        let names: Vec<&str> = scene.views.iter().map(|v| v.camera.name.as_str()).collect();
        assert_eq!(names, ["test/r_0.png", "train/r_0.png", "train/r_1.png"]);
        // Without transforms_test.json (nor transforms.json) the every-8th rule holds.
        std::fs::remove_file(root.join("transforms.json")).expect("rm");
        std::fs::remove_file(root.join("transforms_test.json")).expect("rm");
        let scene = SceneFolder::open(&root).expect("open train only");
        let names: Vec<String> = scene.views.iter().map(|v| v.camera.name.clone()).collect();
        assert_eq!(scene.test_views, default_test_views(&names));
        assert!(!scene.test_views.is_empty());
    }
}
