//! The viewer in a real X window: under Xvfb (with lavapipe, or whatever Vulkan driver the
//! machine has) the `viewer` binary opens a small model with a reflection plane at its first
//! dataset view, draws it, saves a screenshot and exits. The screenshot's scene region must match
//! the offscreen renderer's image for the camera the viewer reports within a mean absolute
//! difference of 1/255: the window path (texture, egui's sampling, the surface, the readback)
//! must not change the render.
//!
//! Needs the `Xvfb` binary (Debian: xvfb). Without it the test says so and passes, unless
//! `TRGS_REQUIRE_XVFB=1` (set by scripts/test.sh, which installs xvfb as root): then it fails.
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use trgs_core::fixtures::{SceneSpec, random_scene};
use trgs_core::io::{
    parse_cameras_json, read_rgb_image, write_cameras_json, write_planes_json, write_ply,
};
use trgs_render::{GpuContext, GpuScene, Layer, RenderOptions, Renderer};

/// Kills the child (Xvfb, or a hung viewer) when dropped.
struct Reaper(Child);

impl Drop for Reaper {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn xvfb() -> Option<PathBuf> {
    std::env::var_os("PATH")?
        .to_str()?
        .split(':')
        .map(|d| Path::new(d).join("Xvfb"))
        .find(|p| p.is_file())
}

/// Start Xvfb on a free display; returns (display, guard).
fn start_xvfb(bin: &Path) -> (String, Reaper) {
    for n in 0..20 {
        let display = format!(":{}", 140 + (std::process::id() % 50) + n * 50);
        let lock = format!("/tmp/.X{}-lock", &display[1..]);
        if Path::new(&lock).exists() {
            continue;
        }
        let child = Command::new(bin)
            .args([&display, "-screen", "0", "1024x768x24", "-nolisten", "tcp"])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("Xvfb starts");
        let guard = Reaper(child);
        let t = Instant::now();
        while t.elapsed() < Duration::from_secs(10) {
            if Path::new(&lock).exists() {
                std::thread::sleep(Duration::from_millis(200));
                return (display, guard);
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }
    panic!("Xvfb did not start on any display tried");
}

fn write_model(dir: &Path) {
    let spec = SceneSpec {
        seed: 11,
        gaussians: 3000,
        planes: 1,
        width: 320,
        height: 240,
        view_angle_deg: 25.0,
        sh_degree: 1,
        glass_fraction: 0.2,
    };
    let scene = random_scene(&spec);
    write_ply(&dir.join("model.ply"), &scene.gaussians.cast::<f32>()).expect("ply");
    write_planes_json(&dir.join("planes.json"), &scene.planes).expect("planes");
    write_cameras_json(&dir.join("cameras.json"), &[scene.camera]).expect("cameras");
}

/// Xvfb's binary, or None when the machine has none and the test may be skipped.
fn xvfb_or_skip() -> Option<PathBuf> {
    let bin = xvfb();
    if bin.is_none() {
        assert!(
            !matches!(std::env::var("TRGS_REQUIRE_XVFB").as_deref(), Ok("1")),
            "TRGS_REQUIRE_XVFB=1 but there is no Xvfb on PATH (apt-get install xvfb)"
        );
        eprintln!("SKIPPED: no Xvfb on PATH (apt-get install xvfb); the viewer was not tested");
    }
    bin
}

/// Run the viewer on the model in `dir` at its first view with a scripted screenshot to `shot`
/// under a fresh Xvfb; returns its exit status.
fn scripted_screenshot(bin: &Path, dir: &Path, shot: &Path) -> std::process::ExitStatus {
    let (display, _xvfb) = start_xvfb(bin);
    let mut viewer = Reaper(
        Command::new(env!("CARGO_BIN_EXE_viewer"))
            .arg(dir)
            .args(["--view", "0", "--no-overlays", "--size", "640x480", "--exit"])
            .arg("--screenshot")
            .arg(shot)
            .env("DISPLAY", &display)
            .env_remove("WAYLAND_DISPLAY")
            .spawn()
            .expect("viewer starts"),
    );
    let t = Instant::now();
    loop {
        if let Some(s) = viewer.0.try_wait().expect("viewer status") {
            return s;
        }
        assert!(t.elapsed() < Duration::from_secs(600), "viewer did not exit within 10 minutes");
        std::thread::sleep(Duration::from_millis(100));
    }
}

#[test]
fn screenshot_scene_region_matches_the_offscreen_render() {
    let Some(bin) = xvfb_or_skip() else { return };
    let dir = trgs_core::scratch::ScratchDir::new("viewer-test");
    write_model(&dir);
    let shot = dir.join("shot.png");
    let status = scripted_screenshot(&bin, &dir, &shot);
    assert!(status.success(), "viewer exited with {status}");

    let sidecar: serde_json::Value =
        serde_json::from_slice(&std::fs::read(shot.with_extension("json")).expect("sidecar"))
            .expect("sidecar JSON");
    let rect: Vec<u32> = serde_json::from_value(sidecar["scene_rect"].clone()).expect("rect");
    let camera_json = serde_json::to_string(&[sidecar["camera"].clone()]).expect("camera");
    let camera = parse_cameras_json(&camera_json, Path::new("sidecar")).expect("camera")[0].clone();
    let (x0, y0, w, h) = (rect[0], rect[1], rect[2], rect[3]);
    assert_eq!((camera.width(), camera.height()), (w, h), "rendered at the region's size");
    assert!(w >= 300 && h >= 300, "scene region {w}x{h} too small");

    let shot_img = read_rgb_image(&shot).expect("screenshot PNG");
    let ctx = GpuContext::new().expect("device");
    let model = trgs_core::io::load_model(&dir, None).expect("model");
    let scene = GpuScene::upload(&ctx, &model.gaussians, &model.planes).expect("upload");
    let frame = Renderer::new(&ctx)
        .render(&scene, &camera, &RenderOptions::default())
        .expect("offscreen render");
    let offscreen = frame.read_layer(&ctx, Layer::Color).expect("readback").to_u8();
    let (mut sum, mut n) = (0.0f64, 0usize);
    for y in 0..h {
        for x in 0..w {
            for c in 0..3 {
                let s = shot_img.data[(((y0 + y) * shot_img.width + x0 + x) * 3 + c) as usize];
                let s = (f64::from(s) * 255.0).round();
                let o = f64::from(offscreen[((y * w + x) * 3 + c) as usize]);
                sum += (s - o).abs();
                n += 1;
            }
        }
    }
    let mad = sum / n as f64 / 255.0;
    eprintln!("scene region {w}x{h} at ({x0}, {y0}): mean |screenshot - offscreen| = {mad:.2e}");
    assert!(mad <= 1.0 / 255.0, "mean absolute difference {mad} > 1/255");
    // The region is not blank: the model is in view.
    assert!(offscreen.iter().any(|&v| v > 20), "offscreen render is black");

    // A screenshot that cannot be written (its folder would be a file) fails the scripted run
    // (same test: one Xvfb at a time).
    let status = scripted_screenshot(&bin, &dir, &dir.join("model.ply").join("shot.png"));
    assert!(!status.success(), "the viewer exited with {status} though the screenshot failed");
}
