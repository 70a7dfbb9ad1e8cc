//! Drawing the planes over the rendered view: each plane's outline and normal in its colour
//! (faded when switched off), and the outlines of candidate planes the run dropped in grey. The
//! geometry is `overlay`'s; this module only paints it.
use crate::overlay::plane_overlay;
use eframe::egui::{Color32, Painter, Rect, Stroke, Vec2};
use trgs_core::scene::{Camera, ReflectionPlane};

/// Each plane's colour, in turn, in the controls and over the view.
pub const PLANE_COLOURS: [Color32; 4] = [
    Color32::from_rgb(255, 200, 40),
    Color32::from_rgb(80, 220, 255),
    Color32::from_rgb(255, 90, 200),
    Color32::from_rgb(140, 255, 110),
];
/// The outline of a candidate plane the run dropped.
pub const DROPPED: Color32 = Color32::from_rgb(150, 150, 150);

/// The colour of plane `k`.
pub fn plane_colour(k: usize) -> Color32 {
    PLANE_COLOURS[k % PLANE_COLOURS.len()]
}

/// Paint `planes` (faded where `enabled` is false) and the `dropped` candidates as `camera`
/// sees them, into `shown`, the rectangle its render fills (which may be larger than the render).
pub fn paint_plane_outlines(
    painter: &Painter,
    shown: Rect,
    camera: &Camera,
    planes: &[ReflectionPlane],
    enabled: &[bool],
    dropped: &[ReflectionPlane],
) {
    let sx = shown.width() / camera.width() as f32;
    let sy = shown.height() / camera.height() as f32;
    let to_screen = |p: glam::DVec2| shown.min + Vec2::new(p.x as f32 * sx, p.y as f32 * sy);
    let painter = painter.with_clip_rect(shown);
    for (k, plane) in planes.iter().enumerate() {
        let on = enabled.get(k).copied().unwrap_or(true);
        let colour = if on { plane_colour(k) } else { plane_colour(k).gamma_multiply(0.35) };
        let overlay = plane_overlay(camera, plane);
        for (a, b) in overlay.edges {
            painter.line_segment([to_screen(a), to_screen(b)], Stroke::new(1.5, colour));
        }
        if let Some((a, b)) = overlay.normal {
            painter.arrow(to_screen(a), to_screen(b) - to_screen(a), Stroke::new(2.0, colour));
        }
    }
    for plane in dropped {
        for (a, b) in plane_overlay(camera, plane).edges {
            painter.line_segment([to_screen(a), to_screen(b)], Stroke::new(1.0, DROPPED));
        }
    }
}
