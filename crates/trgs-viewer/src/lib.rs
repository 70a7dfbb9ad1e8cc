//! trgs-viewer: an egui app that renders trained models in real time with the trgs renderer (on
//! the same wgpu device as the UI), for model files and for a training run in progress.
//!
//! - [`run`] opens the window; [`ViewerOptions`] says what to show and how.
//! - [`LiveFeed`] connects a training loop to the viewer (`train --viewer`).
//! - [`camera::ViewCamera`] is the orbit and fly camera, usable without a window.
mod app;
mod browser;
pub mod camera;
mod frame_times;
pub mod live;
pub mod overlay;
mod plane_outlines;
pub mod scene;
pub mod screenshot;

pub use live::{LiveFeed, Snapshot};
pub use scene::{LoadedModel, load_for_viewer};

use eframe::egui;
use std::path::PathBuf;
use std::sync::Arc;
use trgs_render::{DeviceOptions, Layer, device_descriptor, pick_adapter};

/// What the window shows.
#[derive(Debug)]
pub enum Source {
    /// A model read from disk.
    Model(Box<LoadedModel>),
    /// Snapshots of a training run.
    Live(LiveFeed),
    /// Nothing yet: the user opens a file.
    Nothing,
}

/// Scripted actions, for tests and benchmarks.
#[derive(Clone, Debug, Default)]
pub struct Script {
    /// Save a screenshot (and its sidecar JSON) once the first frames are drawn.
    pub screenshot: Option<PathBuf>,
    /// Re-render every frame and print the mean render and frame times of this many frames.
    pub frames: Option<u32>,
    /// Close the window when the above are done.
    pub exit: bool,
    /// What went wrong in a scripted action (the screenshot could not be written): `run` returns
    /// it as an error once the window is closed, so that a script sees a failing exit status.
    pub failure: Arc<std::sync::Mutex<Option<String>>>,
}

#[derive(Debug)]
pub struct ViewerOptions {
    pub source: Source,
    /// Window inner size in points.
    pub window: [f32; 2],
    /// The dataset view to start from.
    pub view: Option<usize>,
    pub layer: Layer,
    pub overlays: bool,
    /// Render at 1/scale of the window's pixels (1, 2 or 4).
    pub scale: u32,
    pub script: Script,
}

impl Default for ViewerOptions {
    fn default() -> Self {
        Self {
            source: Source::Nothing,
            window: [1100.0, 700.0],
            view: None,
            layer: Layer::Color,
            overlays: true,
            scale: 1,
            script: Script::default(),
        }
    }
}

/// Open the viewer window and run until it is closed.
pub fn run(options: ViewerOptions) -> anyhow::Result<()> {
    let failure = Arc::clone(&options.script.failure);
    let device_options = DeviceOptions::default();
    let setup = eframe::egui_wgpu::WgpuSetupCreateNew {
        instance_descriptor: wgpu::InstanceDescriptor {
            backends: wgpu::Backends::PRIMARY,
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        },
        // The renderer's adapter choice (TRGS_ADAPTER, best device first), among the adapters
        // that can present to the window.
        native_adapter_selector: Some(Arc::new(|adapters, surface| {
            let usable: Vec<wgpu::Adapter> = adapters
                .iter()
                .filter(|a| surface.is_none_or(|s| a.is_surface_supported(s)))
                .cloned()
                .collect();
            pick_adapter(usable, &DeviceOptions::default()).map_err(|e| e.to_string())
        })),
        device_descriptor: Arc::new(move |adapter| device_descriptor(adapter, &device_options)),
        ..eframe::egui_wgpu::WgpuSetupCreateNew::without_display_handle()
    };
    let native = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title("trgs viewer")
            .with_inner_size(options.window)
            .with_drag_and_drop(true),
        renderer: eframe::Renderer::Wgpu,
        wgpu_options: eframe::egui_wgpu::WgpuConfiguration {
            wgpu_setup: eframe::egui_wgpu::WgpuSetup::CreateNew(setup),
            // Frame times measure the renderer, not the display's refresh rate.
            surface: eframe::egui_wgpu::SurfaceConfig {
                present_mode: wgpu::PresentMode::AutoNoVsync,
                ..eframe::egui_wgpu::SurfaceConfig::LOW_LATENCY
            },
            ..Default::default()
        },
        // Dithering would add up to half a level of noise to the render.
        dithering: false,
        ..Default::default()
    };
    eframe::run_native(
        "trgs viewer",
        native,
        Box::new(|cc| Ok(Box::new(app::ViewerApp::new(cc, options)?))),
    )
    .map_err(|e| anyhow::anyhow!("viewer: {e}"))?;
    match failure.lock().unwrap_or_else(|p| p.into_inner()).take() {
        Some(e) => Err(anyhow::anyhow!("viewer: {e}")),
        None => Ok(()),
    }
}
