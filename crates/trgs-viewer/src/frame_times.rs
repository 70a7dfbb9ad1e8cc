//! The viewer's render and frame times, smoothed for display. egui draws a frame only on input,
//! so the frame time is taken between two consecutive UI frames that both rendered the view, and
//! gaps far over the render time (a drag held still) are idle time, not frames.
use std::time::Instant;

/// Milliseconds between two rendering frames beyond the render time that count as idle.
const IDLE_GAP_MS: f64 = 500.0;

/// A running mean that forgets slowly.
#[derive(Default)]
pub struct Smoothed(pub Option<f64>);

impl Smoothed {
    pub fn add(&mut self, v: f64) {
        self.0 = Some(self.0.map_or(v, |m| 0.9 * m + 0.1 * v));
    }
}

pub struct FrameTimes {
    /// Render and display of the view, waited for.
    pub render_ms: Smoothed,
    /// Between the starts of consecutive rendering frames.
    pub frame_ms: Smoothed,
    /// When this UI frame started.
    frame_start: Instant,
    /// When the previous UI frame started, if it rendered the view.
    last_render_frame: Option<Instant>,
    /// The same, taken at the start of this frame's render area.
    previous_render_frame: Option<Instant>,
}

impl Default for FrameTimes {
    fn default() -> Self {
        Self {
            render_ms: Smoothed::default(),
            frame_ms: Smoothed::default(),
            frame_start: Instant::now(),
            last_render_frame: None,
            previous_render_frame: None,
        }
    }
}

impl FrameTimes {
    /// A UI frame starts; whether it renders is known later ([`Self::rendered`]).
    pub fn start_frame(&mut self) {
        self.frame_start = Instant::now();
        self.previous_render_frame = self.last_render_frame.take();
    }

    /// This frame rendered the view in `ms` milliseconds.
    pub fn rendered(&mut self, ms: f64) {
        self.render_ms.add(ms);
        if let Some(previous) = self.previous_render_frame {
            let gap = self.frame_start.duration_since(previous).as_secs_f64() * 1e3;
            if gap < ms + IDLE_GAP_MS {
                self.frame_ms.add(gap);
            }
        }
        self.last_render_frame = Some(self.frame_start);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn frames_count_only_between_rendering_frames() {
        let mut t = FrameTimes::default();
        t.start_frame();
        t.rendered(10.0);
        assert!(t.frame_ms.0.is_none(), "one frame has no interval");
        // A frame that does not render breaks the chain.
        t.start_frame();
        t.start_frame();
        t.rendered(10.0);
        assert!(t.frame_ms.0.is_none());
        // Back to back: counted.
        std::thread::sleep(Duration::from_millis(5));
        t.start_frame();
        t.rendered(10.0);
        assert!(t.frame_ms.0.is_some_and(|ms| ms >= 5.0));
        assert_eq!(t.render_ms.0, Some(10.0));
    }
}
