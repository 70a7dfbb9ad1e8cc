//! Ray tracing every view of a layout: the composite, the true transmission and the glass
//! labels of each pixel from its 2x2 subsamples, spread over the available cores.
use glam::DVec3;

use super::generate::{Layout, SUPERSAMPLE, local_ray};
use trgs_core::image::Image;
use trgs_core::scene::Camera;

/// One rendered view: composite, transmission, and labels for every pixel.
pub(crate) struct View {
    pub image: Image<f32>,
    pub transmission: Image<f32>,
    pub labels: Image<u8>,
}

pub(crate) fn render_view(layout: &Layout, camera: &Camera) -> View {
    let (w, h) = (camera.width(), camera.height());
    let mut image = Image::new(w, h, 3);
    let mut transmission = Image::new(w, h, 3);
    let mut labels = Image::new(w, h, 1);
    let n_sub = f64::from(SUPERSAMPLE * SUPERSAMPLE);
    let mut counts = vec![0u32; layout.world.panes.len()];
    for y in 0..h {
        for x in 0..w {
            let (mut c, mut t) = (DVec3::ZERO, DVec3::ZERO);
            counts.iter_mut().for_each(|k| *k = 0);
            for sy in 0..SUPERSAMPLE {
                for sx in 0..SUPERSAMPLE {
                    let px = f64::from(x) + (f64::from(sx) + 0.5) / f64::from(SUPERSAMPLE);
                    let py = f64::from(y) + (f64::from(sy) + 0.5) / f64::from(SUPERSAMPLE);
                    let s = layout.world.sample(&local_ray(layout, camera, px, py));
                    c += s.colour;
                    t += s.transmission;
                    if let Some(k) = s.pane {
                        counts[k] += 1;
                    }
                }
            }
            // Any subsample on a pane marks the pixel (the pane with most subsamples, lowest
            // index on ties), so that outside the masks the composite equals the transmission.
            let mut label = 0u8;
            let mut most = 0;
            for (k, &n) in counts.iter().enumerate() {
                if n > most {
                    most = n;
                    label = (k + 1).min(255) as u8;
                }
            }
            labels.set(x, y, 0, label);
            for ch in 0..3 {
                image.set(x, y, ch as u32, (c[ch] / n_sub) as f32);
                transmission.set(x, y, ch as u32, (t[ch] / n_sub) as f32);
            }
        }
    }
    View { image, transmission, labels }
}

/// Render every view, spread over the available cores; each view is a pure function of the
/// layout, so the result does not depend on the number of threads.
pub(crate) fn render_all(layout: &Layout) -> Vec<View> {
    let slots: Vec<std::sync::Mutex<Option<View>>> =
        layout.cameras.iter().map(|_| std::sync::Mutex::new(None)).collect();
    for_each_view(layout, |i, view| {
        if let Ok(mut slot) = slots[i].lock() {
            *slot = Some(view);
        }
    });
    slots.into_iter().filter_map(|s| s.into_inner().ok().flatten()).collect()
}

/// Render every view on the available cores and hand each to `f` as soon as it is traced (in
/// no particular order), so that a caller that writes them holds a few views at a time only.
pub(crate) fn for_each_view(layout: &Layout, f: impl Fn(usize, View) + Sync) {
    trgs_core::parallel::for_each_index(layout.cameras.len(), 16, |i| {
        f(i, render_view(layout, &layout.cameras[i]));
        true
    });
}
