//! The eframe app: a control panel on the left, the render filling the rest of the window at its
//! exact pixel size (the trgs renderer draws into a texture that egui samples 1:1, on the same
//! device, with no copy through the CPU), plane overlays on top, a status line at the bottom.
#[path = "app_script.rs"]
mod script;
use crate::browser::{Browser, is_model_file};
use crate::camera::{ViewCamera, up_of};
use crate::frame_times::FrameTimes;
use crate::live::LiveFeed;
use crate::plane_outlines::{DROPPED, paint_plane_outlines, plane_colour};
use crate::scene::{Extent, LoadedModel, depth_range, load_for_viewer};
use crate::screenshot::{ShotInfo, save_screenshot};
use crate::{Script, Source, ViewerOptions};
use eframe::egui;
use egui::{Color32, Pos2, Rect, Sense};
use glam::DVec3;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Instant;
use trgs_core::pipeline::ReflectionModel;
use trgs_core::scene::{Camera, ReflectionPlane};
use trgs_render::{DisplayTarget, Frame, GpuContext, GpuScene, Layer, RenderOptions, Renderer};

/// The layers the selector offers, with their labels.
const LAYERS: [(Layer, &str); 8] = [
    (Layer::Color, "final"),
    (Layer::Transmission, "transmission"),
    (Layer::Reflection, "reflection"),
    (Layer::Strength, "strength R"),
    (Layer::StrengthRaw, "Fresnel R_raw"),
    (Layer::Mask, "mask M"),
    (Layer::Depth, "depth"),
    (Layer::Alpha, "alpha"),
];
/// Frames rendered before a scripted screenshot or benchmark starts (first-use compilation).
const WARMUP_FRAMES: u32 = 3;

/// The model being shown, on the GPU.
struct Shown {
    scene: GpuScene,
    planes: Vec<ReflectionPlane>,
    enabled: Vec<bool>,
    /// Candidate planes the run tried and dropped: outlines only.
    dropped: Vec<ReflectionPlane>,
    reflection: ReflectionModel,
    cameras: Vec<Camera>,
    extent: Extent,
    /// Gaussian centres, for the depth display's range.
    means: Vec<[f32; 3]>,
    test_views: Vec<String>,
    folder: Option<PathBuf>,
    name: String,
}

/// Progress of a scripted run (`--screenshot`, `--frames`).
#[derive(Default)]
struct ScriptState {
    /// Frames rendered.
    rendered: u32,
    /// UI frames shown since the first render.
    shown: u32,
    shot_requested: bool,
    bench: Vec<(f64, f64)>,
    last_ui: Option<Instant>,
    /// Set by the screenshot callback once the file is written.
    shot_saved: Arc<std::sync::atomic::AtomicBool>,
}

pub struct ViewerApp {
    ctx: GpuContext,
    renderer: Renderer,
    shown: Option<Shown>,
    live: Option<LiveFeed>,
    camera: ViewCamera,
    fly: bool,
    layer: Layer,
    overlays: bool,
    /// Render at 1/`scale` of the window's pixels (faster on slow adapters), shown enlarged.
    scale: u32,
    frame: Frame,
    target: Option<(DisplayTarget, egui::TextureId)>,
    dirty: bool,
    times: FrameTimes,
    /// The camera of the image on screen and where it is, in window pixels.
    last_view: Option<(Camera, [u32; 4])>,
    message: Option<(String, bool)>,
    browser: Browser,
    shot_result: Arc<Mutex<Option<Result<PathBuf, String>>>>,
    script: Script,
    script_state: ScriptState,
    pending_view: Option<usize>,
}

impl ViewerApp {
    pub fn new(cc: &eframe::CreationContext<'_>, options: ViewerOptions) -> anyhow::Result<Self> {
        let rs = cc
            .wgpu_render_state
            .as_ref()
            .ok_or_else(|| anyhow::anyhow!("the viewer needs eframe's wgpu renderer"))?;
        let ctx = GpuContext::from_device(
            rs.adapter.clone(),
            rs.device.clone(),
            rs.queue.clone(),
            &trgs_render::DeviceOptions::default(),
        )?;
        let renderer = Renderer::new(&ctx);
        let here = std::env::current_dir().unwrap_or_else(|_| PathBuf::from("."));
        let mut app = Self {
            renderer,
            shown: None,
            live: None,
            camera: ViewCamera::look_at(DVec3::new(0.0, 0.0, -3.0), DVec3::ZERO, DVec3::NEG_Y, 0.9),
            fly: false,
            layer: options.layer,
            overlays: options.overlays,
            scale: options.scale,
            frame: Frame::default(),
            target: None,
            dirty: true,
            times: FrameTimes::default(),
            last_view: None,
            message: None,
            browser: Browser::new(here),
            shot_result: Arc::default(),
            script: options.script,
            script_state: ScriptState::default(),
            pending_view: options.view,
            ctx,
        };
        match options.source {
            Source::Model(model) => app.show_model(*model),
            Source::Live(feed) => {
                app.message = Some(("waiting for the first snapshot of training".into(), false));
                app.live = Some(feed);
            }
            Source::Nothing => {
                app.message = Some(("open a model: Open… or drop a file here".into(), false));
            }
        }
        Ok(app)
    }

    /// Upload a model and put the camera on its first view (or in front of it).
    fn show_model(&mut self, model: LoadedModel) {
        match GpuScene::upload(&self.ctx, &model.gaussians, &model.planes) {
            Ok(scene) => {
                let extent = Extent::of(&model.gaussians);
                let n = model.planes.len();
                self.message = Some((
                    format!(
                        "{}: {} Gaussians, {} plane{}",
                        model.name,
                        scene.len(),
                        n,
                        if n == 1 { "" } else { "s" }
                    ),
                    false,
                ));
                // A new frame: the last model's buffers go, and its key totals do not size the
                // new model's lists.
                self.frame = Frame::default();
                self.shown = Some(Shown {
                    scene,
                    planes: model.planes,
                    enabled: vec![true; n],
                    dropped: model.dropped,
                    reflection: model.reflection,
                    cameras: model.cameras,
                    extent,
                    means: model.gaussians.means,
                    test_views: model.test_views,
                    folder: model.folder,
                    name: model.name,
                });
                let view = self.pending_view.take().unwrap_or(0);
                self.home(view);
            }
            Err(e) => self.message = Some((format!("{}: {e}", model.name), true)),
        }
    }

    /// Snap to dataset view `i`, or without views look at the model from the front.
    fn home(&mut self, i: usize) {
        let Some(s) = &self.shown else { return };
        let up = up_of(&s.cameras);
        self.camera = match s.cameras.get(i).or(s.cameras.first()) {
            Some(c) => {
                let d = (c.pose.centre() - s.extent.centre).length();
                ViewCamera::from_camera(c, up, d)
            }
            None => {
                let back = if up.dot(DVec3::NEG_Y) > 0.5 { DVec3::NEG_Z } else { DVec3::Y };
                let eye = s.extent.centre + back * 2.5 * s.extent.radius;
                ViewCamera::look_at(eye, s.extent.centre, up, 0.9)
            }
        };
        self.dirty = true;
    }

    fn open(&mut self, path: PathBuf) {
        match load_for_viewer(&path) {
            Ok(m) => {
                // Stop watching training: the trainer stops reading its scene back.
                if let Some(feed) = self.live.take() {
                    feed.close();
                }
                self.show_model(m);
            }
            Err(e) => self.message = Some((format!("{e:#}"), true)),
        }
    }

    /// Take the newest training snapshot, if any.
    fn poll_live(&mut self) {
        let Some(feed) = &self.live else { return };
        let Some(snap) = feed.take() else { return };
        let model = LoadedModel {
            gaussians: snap.gaussians,
            planes: snap.planes,
            reflection: snap.reflection,
            cameras: feed.cameras(),
            dropped: Vec::new(),
            test_views: Vec::new(),
            folder: feed.folder(),
            name: "training".into(),
        };
        let Some(s) = &mut self.shown else {
            self.show_model(model);
            return;
        };
        match GpuScene::upload(&self.ctx, &model.gaussians, &model.planes) {
            Ok(scene) => {
                s.enabled.resize(model.planes.len(), true);
                s.scene = scene;
                s.planes = model.planes;
                s.reflection = model.reflection;
                s.cameras = model.cameras;
                s.means = model.gaussians.means;
                s.folder = model.folder;
                self.dirty = true;
            }
            Err(e) => self.message = Some((format!("training snapshot: {e}"), true)),
        }
    }

    fn controls(&mut self, ui: &mut egui::Ui) {
        ui.heading("trgs viewer");
        if ui.button("Open…").clicked() {
            self.browser.open = true;
        }
        ui.separator();
        ui.label("Layer");
        for (layer, label) in LAYERS {
            if ui.radio_value(&mut self.layer, layer, label).changed() {
                self.dirty = true;
            }
        }
        ui.separator();
        ui.horizontal(|ui| {
            ui.label("Camera");
            ui.radio_value(&mut self.fly, false, "orbit");
            ui.radio_value(&mut self.fly, true, "fly");
        });
        ui.small(if self.fly {
            "drag: look · WASD/QE: move · shift: faster"
        } else {
            "drag: orbit · right drag: pan · wheel: zoom · WASD/QE: move"
        });
        let views = self.shown.as_ref().map_or(0, |s| s.cameras.len());
        if views > 0 {
            let mut go = None;
            egui::ComboBox::from_label("dataset view").selected_text("snap to…").show_ui(
                ui,
                |ui| {
                    if let Some(s) = &self.shown {
                        for (i, c) in s.cameras.iter().enumerate() {
                            let test = if s.test_views.contains(&c.name) { " (test)" } else { "" };
                            let label = format!("{i}: {}{test}", c.name);
                            if ui.selectable_label(false, label).clicked() {
                                go = Some(i);
                            }
                        }
                    }
                },
            );
            if let Some(i) = go {
                self.home(i);
            }
        }
        if ui.button("Reset view").clicked() {
            self.home(0);
        }
        let before = self.scale;
        egui::ComboBox::from_label("resolution")
            .selected_text(if self.scale == 1 {
                "full".into()
            } else {
                format!("1/{}", self.scale)
            })
            .show_ui(ui, |ui| {
                for s in [1, 2, 4] {
                    let label = if s == 1 { "full".into() } else { format!("1/{s}") };
                    ui.selectable_value(&mut self.scale, s, label);
                }
            });
        if self.scale != before {
            self.dirty = true;
        }
        ui.separator();
        ui.checkbox(&mut self.overlays, "plane overlays");
        let mut planes_changed = false;
        if let Some(s) = &mut self.shown {
            for (k, plane) in s.planes.iter_mut().enumerate() {
                let colour = plane_colour(k);
                ui.horizontal(|ui| {
                    ui.colored_label(colour, format!("plane {}", k + 1));
                    planes_changed |= ui.checkbox(&mut s.enabled[k], "on").changed();
                });
                let mut r0 = plane.r0();
                if ui.add(egui::Slider::new(&mut r0, 0.0..=1.0).text("R0")).changed() {
                    let r = r0.clamp(1e-4, 1.0 - 1e-4);
                    plane.r0_logit = (r / (1.0 - r)).ln();
                    planes_changed = true;
                }
            }
            if !s.dropped.is_empty() {
                ui.colored_label(
                    DROPPED,
                    format!("{} candidate planes tried and dropped (outlines)", s.dropped.len()),
                );
            }
            if planes_changed {
                if let Err(e) = s.scene.set_planes(&s.planes) {
                    self.message = Some((format!("planes: {e}"), true));
                }
                self.dirty = true;
            }
        }
        ui.separator();
        if ui.button("Screenshot (F12)").clicked() {
            self.screenshot(ui.ctx(), self.default_shot_path());
        }
        ui.separator();
        if let Some(ms) = self.times.render_ms.0 {
            ui.label(format!("render {ms:.1} ms"));
        }
        if let Some(ms) = self.times.frame_ms.0 {
            ui.label(format!("frame {ms:.1} ms ({:.1} fps)", 1000.0 / ms.max(1e-3)));
        }
        if let Some((c, _)) = &self.last_view {
            ui.label(format!("{}x{}", c.width(), c.height()));
        }
        ui.small(self.ctx.adapter());
    }

    /// Camera input on the scene's area. Returns whether the camera moved.
    fn navigate(&mut self, ui: &egui::Ui, response: &egui::Response, height_px: f64) -> bool {
        let ppp = f64::from(ui.ctx().pixels_per_point());
        let before = self.camera.clone();
        let d = response.drag_delta();
        let (dx, dy) = (f64::from(d.x) * ppp, f64::from(d.y) * ppp);
        if response.dragged_by(egui::PointerButton::Primary) {
            if self.fly {
                self.camera.look(dx, dy);
            } else {
                self.camera.orbit(dx, dy);
            }
        } else if response.dragged_by(egui::PointerButton::Secondary)
            || response.dragged_by(egui::PointerButton::Middle)
        {
            self.camera.pan(dx, dy, height_px);
        }
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                self.camera.zoom(f64::from(scroll) / 50.0);
            }
        }
        if !ui.ctx().egui_wants_keyboard_input() {
            let (dir, fast, dt) = ui.input(|i| {
                let k = |key| if i.key_down(key) { 1.0 } else { 0.0 };
                let dir = DVec3::new(
                    k(egui::Key::D) - k(egui::Key::A),
                    k(egui::Key::Q) - k(egui::Key::E),
                    k(egui::Key::W) - k(egui::Key::S),
                );
                (dir, i.modifiers.shift, f64::from(i.stable_dt.min(0.1)))
            });
            if dir != DVec3::ZERO {
                let radius = self.shown.as_ref().map_or(1.0, |s| s.extent.radius);
                let speed = 0.5 * radius * if fast { 4.0 } else { 1.0 };
                self.camera.fly(dir.normalize(), speed * dt);
                ui.ctx().request_repaint();
            }
        }
        self.camera != before
    }

    /// The render area: draw (when something changed), show, overlay.
    fn scene(&mut self, ui: &mut egui::Ui, frame: &eframe::Frame) {
        let ppp = ui.ctx().pixels_per_point();
        let rect = ui.max_rect();
        let (min, max) = ((rect.min.to_vec2() * ppp).round(), (rect.max.to_vec2() * ppp).round());
        let (w, h) = ((max.x - min.x).max(1.0) as u32, (max.y - min.y).max(1.0) as u32);
        let shown_rect = Rect::from_min_max((min / ppp).to_pos2(), (max / ppp).to_pos2());
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        let (rw, rh) = ((w / self.scale).max(1), (h / self.scale).max(1));
        if self.navigate(ui, &response, f64::from(h)) {
            self.dirty = true;
        }
        let Some(s) = &self.shown else {
            ui.painter().rect_filled(rect, 0.0, Color32::from_gray(20));
            return;
        };
        let Some(rs) = frame.wgpu_render_state() else { return };
        if self.target.as_ref().is_none_or(|(t, _)| t.size() != (rw, rh)) {
            let target = match DisplayTarget::new(&self.ctx, rw, rh) {
                Ok(t) => t,
                Err(e) => {
                    self.message = Some((format!("display: {e}"), true));
                    return;
                }
            };
            let mut egui_renderer = rs.renderer.write();
            let id = match self.target.take() {
                Some((_, id)) => {
                    egui_renderer.update_egui_texture_from_wgpu_texture(
                        &rs.device,
                        target.texture_view(),
                        wgpu::FilterMode::Nearest,
                        id,
                    );
                    id
                }
                None => egui_renderer.register_native_texture(
                    &rs.device,
                    target.texture_view(),
                    wgpu::FilterMode::Nearest,
                ),
            };
            self.target = Some((target, id));
            self.dirty = true;
        }
        let Some((target, texture)) = &self.target else { return };
        if self.dirty || self.script.frames.is_some() {
            let camera = self.camera.camera(rw, rh);
            let options = RenderOptions {
                enabled_planes: s.enabled.clone(),
                reflection: s.reflection,
                ..Default::default()
            };
            let range = if self.layer == Layer::Depth {
                depth_range(&s.means, &camera)
            } else {
                [0.2, 100.0]
            };
            let t = Instant::now();
            let (renderer, layer) = (&self.renderer, self.layer);
            let show = |f: &Frame| -> anyhow::Result<()> {
                Ok(renderer.display(f, layer, range, target)?)
            };
            let drawn = renderer
                .render_finished(&s.scene, &camera, &options, &mut self.frame, show)
                .map_err(|e| format!("{e:#}"));
            match drawn {
                Ok(()) => {
                    let ms = t.elapsed().as_secs_f64() * 1e3;
                    self.times.rendered(ms);
                    self.script_state.rendered += 1;
                    if self.script.frames.is_some()
                        && self.script_state.rendered > WARMUP_FRAMES
                        && let Some(last) = self.script_state.last_ui
                    {
                        let frame_ms = last.elapsed().as_secs_f64() * 1e3;
                        self.script_state.bench.push((ms, frame_ms));
                    }
                    self.last_view = Some((camera, [min.x as u32, min.y as u32, w, h]));
                }
                Err(e) => self.message = Some((format!("render: {e}"), true)),
            }
            self.dirty = false;
        }
        let uv = Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0));
        ui.painter().image(*texture, shown_rect, uv, Color32::WHITE);
        if self.overlays
            && let Some((camera, _)) = &self.last_view
        {
            let (planes, on, dropped) = (&s.planes, &s.enabled, &s.dropped);
            paint_plane_outlines(ui.painter(), shown_rect, camera, planes, on, dropped);
        }
    }

    /// Where F12 saves: `screenshots/` in the open model's folder or the run's being watched (the
    /// working directory with nothing open), named by the time.
    fn default_shot_path(&self) -> PathBuf {
        let secs = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_secs());
        let folder = self.shown.as_ref().and_then(|s| s.folder.clone()).unwrap_or_default();
        folder.join("screenshots").join(format!("trgs-screenshot-{secs}.png"))
    }

    fn screenshot(&mut self, ctx: &egui::Context, path: PathBuf) {
        let Some((camera, rect)) = self.last_view.clone() else {
            self.message = Some(("nothing rendered yet to screenshot".into(), true));
            return;
        };
        let info = ShotInfo { path, scene_rect: rect, camera, layer: self.layer };
        let result = Arc::clone(&self.shot_result);
        let saved_flag = Arc::clone(&self.script_state.shot_saved);
        let repaint = ctx.clone();
        ctx.request_screenshot(move |image| {
            let saved = save_screenshot(&image, &info).map(|()| info.path.clone());
            *result.lock().unwrap_or_else(|p| p.into_inner()) =
                Some(saved.map_err(|e| format!("{e:#}")));
            saved_flag.store(true, std::sync::atomic::Ordering::SeqCst);
            repaint.request_repaint();
        });
        ctx.request_repaint();
    }
}

impl eframe::App for ViewerApp {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        self.times.start_frame();
        self.poll_live();
        if let Some(feed) = &self.live {
            ctx.request_repaint_after(std::time::Duration::from_millis(200));
            let status = feed.status();
            let showing_error = matches!(self.message, Some((_, true)));
            if !status.is_empty() && !showing_error {
                self.message = Some((status, false));
            }
        }
        let dropped: Vec<PathBuf> =
            ctx.input(|i| i.raw.dropped_files.iter().map(|f| f.path().to_path_buf()).collect());
        if let Some(p) = dropped.into_iter().next() {
            if p.is_dir() || is_model_file(&p) {
                self.open(p);
            } else {
                self.message =
                    Some((format!("{}: not a .ply, .glb, .spz or run folder", p.display()), true));
            }
        }
        if ctx.input(|i| i.key_pressed(egui::Key::F12)) {
            self.screenshot(&ctx, self.default_shot_path());
        }
        if let Some(done) = self.shot_result.lock().unwrap_or_else(|p| p.into_inner()).take() {
            if let (Err(e), Some(_)) = (&done, &self.script.screenshot) {
                *self.script.failure.lock().unwrap_or_else(|p| p.into_inner()) =
                    Some(format!("screenshot: {e}"));
            }
            self.message = Some(match done {
                Ok(p) => (format!("screenshot saved to {}", p.display()), false),
                Err(e) => (format!("screenshot: {e}"), true),
            });
        }
        if let Some(p) = self.browser.show(&ctx) {
            self.open(p);
        }
        egui::Panel::left("controls").resizable(false).exact_size(230.0).show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| self.controls(ui));
        });
        egui::Panel::bottom("status").show(ui, |ui| {
            let title = self.shown.as_ref().map_or("", |s| s.name.as_str()).to_string();
            match &self.message {
                Some((m, true)) => ui.colored_label(Color32::LIGHT_RED, m),
                Some((m, false)) => ui.label(m),
                None => ui.label(title),
            };
        });
        egui::CentralPanel::no_frame().show(ui, |ui| self.scene(ui, frame));
        self.run_script(&ctx);
    }

    fn on_exit(&mut self) {
        if let Some(feed) = &self.live {
            feed.close();
        }
    }
}
