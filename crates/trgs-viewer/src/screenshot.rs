//! Screenshots: the whole window as a PNG (atomically written) and a JSON file beside it that
//! says where the scene is in it and with which camera it was rendered (one `cameras.json`
//! entry), so that the scene can be rendered again offscreen and compared.
use anyhow::{Context, Result};
use eframe::egui;
use std::path::PathBuf;
use trgs_core::Image;
use trgs_core::io::{encode_cameras_json, write_atomic, write_png_rgb};
use trgs_core::scene::Camera;
use trgs_render::Layer;

/// What a screenshot shows.
#[derive(Clone, Debug)]
pub struct ShotInfo {
    pub path: PathBuf,
    /// The scene's (x, y, width, height) in window pixels.
    pub scene_rect: [u32; 4],
    pub camera: Camera,
    pub layer: Layer,
}

/// The sidecar's path: `shot.png` → `shot.json`.
pub fn sidecar_path(png: &std::path::Path) -> PathBuf {
    png.with_extension("json")
}

pub fn save_screenshot(image: &egui::ColorImage, info: &ShotInfo) -> Result<()> {
    let [w, h] = image.size;
    let mut rgb = Image::new(w as u32, h as u32, 3);
    for (p, c) in image.pixels.iter().enumerate() {
        for (ch, v) in [c.r(), c.g(), c.b()].into_iter().enumerate() {
            rgb.data[p * 3 + ch] = f32::from(v) / 255.0;
        }
    }
    if let Some(dir) = info.path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("creating the screenshot folder {}", dir.display()))?;
    }
    write_png_rgb(&info.path, &rgb)?;
    let camera: serde_json::Value =
        serde_json::from_str(&encode_cameras_json(std::slice::from_ref(&info.camera)))?;
    let sidecar = serde_json::json!({
        "screenshot": info.path.file_name().map(|n| n.to_string_lossy().into_owned()),
        "window_size": [w, h],
        "scene_rect": info.scene_rect,
        "layer": info.layer.name(),
        "camera": camera[0],
    });
    let path = sidecar_path(&info.path);
    write_atomic(&path, serde_json::to_string_pretty(&sidecar)?.as_bytes())
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}
