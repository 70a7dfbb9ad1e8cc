//! The `render` command end to end: a model (PLY + planes.json) and a camera path
//! (transforms.json) give one PNG and one EXR per view; bad input names the file.
use std::path::PathBuf;
use std::process::Command;
use trgs_core::fixtures::{Scene, SceneSpec, random_scene};
use trgs_core::io::{TransformsFrame, write_planes_json, write_ply, write_transforms};
use trgs_core::scratch::ScratchDir;

fn tmp(name: &str) -> ScratchDir {
    ScratchDir::new(&format!("render-cli-{name}"))
}

/// A folder with a random one-plane scene's model.ply and planes.json (64x48 camera).
fn model_folder(name: &str) -> (ScratchDir, Scene) {
    let dir = tmp(name);
    let s = random_scene(&SceneSpec {
        planes: 1,
        gaussians: 300,
        width: 64,
        height: 48,
        ..SceneSpec::default()
    });
    write_ply(&dir.join("model.ply"), &s.gaussians.cast()).expect("ply");
    write_planes_json(&dir.join("planes.json"), &s.planes).expect("planes");
    (dir, s)
}

#[test]
fn renders_pngs_and_exrs_from_a_camera_path() {
    let (dir, s) = model_folder("ok");
    let mut second = s.camera.clone();
    second.name = "second.png".into();
    let frames: Vec<TransformsFrame> = [s.camera.clone(), second]
        .into_iter()
        .map(|camera| TransformsFrame {
            image_path: PathBuf::from(&camera.name),
            camera,
            undistortion: None,
        })
        .collect();
    write_transforms(&dir.join("path.json"), &frames).expect("transforms");
    let out = dir.join("out");
    let status = Command::new(env!("CARGO_BIN_EXE_trgs"))
        .arg("render")
        .args(["--model", dir.to_str().expect("utf-8"), "--cameras"])
        .arg(dir.join("path.json"))
        .arg("--out")
        .arg(&out)
        .output()
        .expect("run render");
    let stdout = String::from_utf8_lossy(&status.stdout);
    assert!(status.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&status.stderr));
    assert!(stdout.contains("1 plane;"), "{stdout}");
    for name in ["second"] {
        let png = image::open(out.join(format!("{name}.png"))).expect("png").to_rgb8();
        assert_eq!(png.dimensions(), (64, 48));
        let exr = std::fs::read(out.join(format!("{name}.exr"))).expect("exr");
        assert_eq!(&exr[..4], &[0x76, 0x2f, 0x31, 0x01], "EXR magic");
        let text = String::from_utf8_lossy(&exr);
        for ch in ["transmission.R", "reflection.B", "depth.Z", "strength.Y", "mask.Y"] {
            assert!(text.contains(ch), "EXR lacks channel {ch}");
        }
    }
    let pngs = std::fs::read_dir(&out)
        .expect("out")
        .filter(|e| e.as_ref().is_ok_and(|e| e.path().extension().is_some_and(|x| x == "png")));
    assert_eq!(pngs.count(), 2);
}

#[test]
fn missing_model_names_the_path() {
    let dir = tmp("missing");
    let out = Command::new(env!("CARGO_BIN_EXE_trgs"))
        .arg("render")
        .args(["--model", "/nonexistent/model.ply", "--cameras"])
        .arg(&dir)
        .output()
        .expect("run render");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("/nonexistent/model.ply"), "{err}");
}

/// `render --mirror 1`: the camera's mirrored view, flipped back into its pixels, is the
/// reflection pass's raw colour C_raw of the CPU twin wherever the camera's rays hit the plane;
/// a camera behind the plane is skipped; a plane the model lacks is refused.
#[test]
fn mirror_view_is_the_raw_reflection_inside_the_rectangle() {
    use trgs_core::pipeline::RenderSettings;
    use trgs_core::plane_math::{mirror_camera, ray_rectangle_hit};
    use trgs_core::reference::render;
    let (dir, s) = model_folder("mirror");
    // The model as the PLY holds it (f32).
    let g = s.gaussians.cast::<f32>();
    let mut front = s.camera.clone();
    front.name = "front.png".into();
    // The mirrored camera stands behind the plane: it sees no reflection.
    let mut behind = mirror_camera(&s.planes[0], &s.camera);
    behind.name = "behind.png".into();
    let frames: Vec<TransformsFrame> = [front.clone(), behind]
        .into_iter()
        .map(|camera| TransformsFrame {
            image_path: PathBuf::from(&camera.name),
            camera,
            undistortion: None,
        })
        .collect();
    write_transforms(&dir.join("path.json"), &frames).expect("transforms");
    let out = dir.join("out");
    let run = |plane: &str| {
        Command::new(env!("CARGO_BIN_EXE_trgs"))
            .arg("render")
            .args(["--model", dir.to_str().expect("utf-8"), "--cameras"])
            .arg(dir.join("path.json"))
            .arg("--out")
            .arg(&out)
            .args(["--mirror", plane])
            .output()
            .expect("run render")
    };
    let done = run("1");
    let stdout = String::from_utf8_lossy(&done.stdout);
    assert!(done.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&done.stderr));
    assert!(stdout.contains("skipped (behind the plane, no reflection): behind"), "{stdout}");
    assert!(!out.join("behind_mirror1.png").exists());
    let png = image::open(out.join("front_mirror1.png")).expect("png").to_rgb8();
    let twin = render(&g.cast(), &s.planes, &front, &RenderSettings::default()).expect("valid");
    let raw = &twin.planes[0].as_ref().expect("the camera sees the plane").raw_color;
    let (mut hits, mut worst) = (0, 0.0f64);
    for y in 0..48 {
        for x in 0..64 {
            if ray_rectangle_hit(&s.planes[0], front.pose.centre(), front.pixel_ray(x, y)).is_none()
            {
                continue;
            }
            hits += 1;
            for c in 0..3 {
                let want = raw.get(x, y, c).clamp(0.0, 1.0) * 255.0;
                let got = f64::from(png.get_pixel(x, y)[c as usize]);
                worst = worst.max((got - want).abs());
            }
        }
    }
    assert!(hits > 50, "{hits} hit pixels");
    assert!(worst <= 1.0, "8-bit mirror view against the twin's C_raw: off by {worst} levels");
    let refused = run("2");
    assert!(!refused.status.success());
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(err.contains("--mirror 2") && err.contains("has 1 planes"), "{err}");
}
