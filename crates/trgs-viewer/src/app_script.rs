//! Scripted runs of the viewer (`--screenshot`, `--frames`, `--exit`): a screenshot once the first
//! frames are drawn, a frame-time benchmark, and closing when both are done.
use super::{ViewerApp, WARMUP_FRAMES};
use eframe::egui;
use std::time::Instant;

impl ViewerApp {
    /// Scripted runs: a screenshot after the warm-up frames, or a frame-time benchmark.
    pub(super) fn run_script(&mut self, ctx: &egui::Context) {
        // An error (a model that does not load, a frame the renderer refuses) stops a scripted
        // run with a failing exit status, instead of waiting forever for a frame to capture.
        let scripted = self.script.screenshot.is_some() || self.script.frames.is_some();
        if scripted && let Some((message, true)) = &self.message {
            if let Ok(mut failure) = self.script.failure.lock() {
                failure.get_or_insert_with(|| message.clone());
            }
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            return;
        }
        if self.last_view.is_some() {
            self.script_state.shown += 1;
        }
        if let Some(path) = self.script.screenshot.clone()
            && !self.script_state.shot_requested
            && self.script_state.shown >= WARMUP_FRAMES
        {
            self.script_state.shot_requested = true;
            self.screenshot(ctx, path);
        }
        if let Some(n) = self.script.frames {
            let bench = &self.script_state.bench;
            if bench.len() as u32 >= n {
                let mean = |f: fn(&(f64, f64)) -> f64| {
                    bench.iter().map(f).sum::<f64>() / bench.len() as f64
                };
                let (render, frame) = (mean(|b| b.0), mean(|b| b.1));
                let (w, h) = self.target.as_ref().map_or((0, 0), |(t, _)| t.size());
                let g = self.shown.as_ref().map_or(0, |s| s.scene.len());
                println!(
                    "viewer: {n} frames at {w}x{h}, {g} Gaussians, {}: render {render:.1} ms, \
                     frame {frame:.1} ms ({:.1} fps)",
                    self.ctx.info.name,
                    1000.0 / frame
                );
                self.script.frames = None;
            }
        }
        let shot_pending = self.script.screenshot.is_some()
            && !self.script_state.shot_saved.load(std::sync::atomic::Ordering::SeqCst);
        if self.script.exit && !shot_pending && self.script.frames.is_none() {
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
        }
        if self.script.screenshot.is_some() || self.script.frames.is_some() {
            self.script_state.last_ui = Some(Instant::now());
            ctx.request_repaint();
        }
    }
}
