//! The output layers of one render and their gradients, and the geometry pass ([`ViewPass`]) of
//! each view they are rasterised from.
use super::project::Projected;
use super::rasterize::PixelState;
use super::rasterize_reflection::ReflectionPixelState;
use crate::image::Image;
use crate::pipeline::{TileGrid, TileRect};
use crate::scene::ViewTransform;

/// The geometry stages of one view: projection and the sorted per-tile lists.
#[derive(Clone, Debug)]
pub struct ViewPass {
    pub view: ViewTransform,
    pub projected: Projected,
    /// Sorted tile indices, one per key.
    pub keys: Vec<u32>,
    pub values: Vec<u32>,
    pub ranges: Vec<(u32, u32)>,
}

/// Every layer of one view (docs/ARCHITECTURE.md, "Data flow"), plus what the backward replays.
#[derive(Clone, Debug)]
pub struct Frame {
    /// C, RGB.
    pub color: Image<f64>,
    /// C_t, RGB.
    pub transmission: Image<f64>,
    /// D_t.
    pub depth: Image<f64>,
    /// V = sum_i w_i |z_i - D_t| (the depth-variance loss before H and the mean).
    pub depth_variance: Image<f64>,
    /// M.
    pub mask: Image<f64>,
    /// 1 - T_t.
    pub alpha: Image<f64>,
    /// H: 0 for no hit, k + 1 for plane k.
    pub hit: Image<u32>,
    /// R_raw (Schlick, zero without a hit).
    pub strength_raw: Image<f64>,
    /// R = H R_raw M.
    pub strength: Image<f64>,
    /// C_r = sum_k H_k C_raw^k A^k, RGB.
    pub reflection: Image<f64>,
    /// Per plane: the mirrored pass (None when the camera is not in front of the plane or the
    /// rectangle is off screen).
    pub planes: Vec<Option<PlaneLayers>>,
    /// The real camera's pass (what its adjoint replays).
    pub primary: ViewPass,
    /// Pass 1's per-pixel states.
    pub pixels: Vec<PixelState>,
}

/// One plane's mirrored pass.
#[derive(Clone, Debug)]
pub struct PlaneLayers {
    /// C_raw^k, RGB, over the whole image (zero outside the footprint, not masked by H).
    pub raw_color: Image<f64>,
    /// A^k.
    pub intensity: Image<f64>,
    pub footprint: TileRect,
    /// The mirrored view's pass.
    pub pass: ViewPass,
    /// Pass 2's per-pixel states.
    pub pixels: Vec<ReflectionPixelState>,
}

impl Frame {
    pub fn width(&self) -> u32 {
        self.color.width
    }

    pub fn height(&self) -> u32 {
        self.color.height
    }

    /// C_r^k = C_raw^k A^k of plane k over its whole footprint (for the gradient-conflict loss,
    /// whose Sobel reads beyond H).
    pub fn plane_reflection(&self, k: usize) -> Option<Image<f64>> {
        let p = self.planes.get(k)?.as_ref()?;
        let mut out = p.raw_color.clone();
        for (i, v) in out.data.iter_mut().enumerate() {
            *v *= p.intensity.data[i / 3];
        }
        Some(out)
    }
}

/// dL/d(each layer of a [`Frame`]); zero layers contribute nothing. The hit mask is discrete and
/// has no gradient.
#[derive(Clone, Debug)]
pub struct FrameGrads {
    pub color: Image<f64>,
    pub transmission: Image<f64>,
    pub depth: Image<f64>,
    pub depth_variance: Image<f64>,
    pub mask: Image<f64>,
    pub alpha: Image<f64>,
    pub strength_raw: Image<f64>,
    pub strength: Image<f64>,
    pub reflection: Image<f64>,
    pub planes: Vec<PlaneLayerGrads>,
}

#[derive(Clone, Debug)]
pub struct PlaneLayerGrads {
    pub raw_color: Image<f64>,
    pub intensity: Image<f64>,
}

impl FrameGrads {
    /// All-zero gradients for a `width` x `height` frame of a scene with `planes` planes.
    pub fn zeros(width: u32, height: u32, planes: usize) -> Self {
        let (w, h) = (width, height);
        Self {
            color: Image::new(w, h, 3),
            transmission: Image::new(w, h, 3),
            depth: Image::new(w, h, 1),
            depth_variance: Image::new(w, h, 1),
            mask: Image::new(w, h, 1),
            alpha: Image::new(w, h, 1),
            strength_raw: Image::new(w, h, 1),
            strength: Image::new(w, h, 1),
            reflection: Image::new(w, h, 3),
            planes: (0..planes)
                .map(|_| PlaneLayerGrads {
                    raw_color: Image::new(w, h, 3),
                    intensity: Image::new(w, h, 1),
                })
                .collect(),
        }
    }

    /// Gradients for a `width` x `height` frame with `planes` planes, each layer filled by `fill`
    /// in the order of the fields, the planes' layers last (C_raw, then A, plane by plane):
    /// random or synthetic upstream gradients for tests and benchmarks.
    pub fn filled(
        width: u32,
        height: u32,
        planes: usize,
        mut fill: impl FnMut(&mut Image<f64>),
    ) -> Self {
        let mut g = Self::zeros(width, height, planes);
        for layer in [
            &mut g.color,
            &mut g.transmission,
            &mut g.depth,
            &mut g.depth_variance,
            &mut g.mask,
            &mut g.alpha,
            &mut g.strength_raw,
            &mut g.strength,
            &mut g.reflection,
        ] {
            fill(layer);
        }
        for p in &mut g.planes {
            fill(&mut p.raw_color);
            fill(&mut p.intensity);
        }
        g
    }

    /// All-zero gradients shaped like `frame`.
    pub fn zeros_like(frame: &Frame) -> Self {
        Self::zeros(frame.width(), frame.height(), frame.planes.len())
    }
}

impl Frame {
    /// A fingerprint of every discrete decision of the forward pass: culling, binning and order,
    /// each pixel's stop points, which Gaussians pass the 1/255 threshold or sit at the 0.99 cap,
    /// colour clamps and the hit mask. Two renders with the same fingerprint differ only
    /// smoothly; finite-difference checks use it to tell a real gradient error from a step across
    /// a discontinuity of the renderer.
    pub fn fingerprint(&self) -> u64 {
        use std::hash::{Hash, Hasher};
        let mut h = std::collections::hash_map::DefaultHasher::new();
        let grid = TileGrid::new(self.width(), self.height());
        let hash_pass = |h: &mut std::collections::hash_map::DefaultHasher,
                         pass: &ViewPass,
                         lasts: &[u32],
                         tiles: TileRect| {
            let p = &pass.projected;
            p.visible.hash(h);
            p.color_clamped.hash(h);
            pass.values.hash(h);
            pass.ranges.hash(h);
            lasts.hash(h);
            for ty in tiles.y0..tiles.y1 {
                for tx in tiles.x0..tiles.x1 {
                    let (s, e) = pass.ranges[(ty * grid.tiles_x + tx) as usize];
                    let list = &pass.values[s as usize..e as usize];
                    for (x, y) in super::rasterize::tile_pixels(&grid, tx, ty) {
                        let last = lasts[(y * grid.width + x) as usize] as usize;
                        for &gi in &list[..last.min(list.len())] {
                            let d = super::rasterize::alpha_at(
                                p,
                                gi as usize,
                                f64::from(x) + 0.5,
                                f64::from(y) + 0.5,
                            );
                            d.map(|v| v.4).hash(h);
                        }
                    }
                }
            }
        };
        let lasts: Vec<u32> = self.pixels.iter().flat_map(|s| [s.last_t, s.last_m]).collect();
        let lt: Vec<u32> = self.pixels.iter().map(|s| s.last_t).collect();
        lasts.hash(&mut h);
        hash_pass(&mut h, &self.primary, &lt, grid.full());
        self.hit.data.hash(&mut h);
        for p in &self.planes {
            match p {
                None => 0u8.hash(&mut h),
                Some(p) => {
                    p.footprint.hash(&mut h);
                    let l: Vec<u32> = p.pixels.iter().map(|s| s.last).collect();
                    hash_pass(&mut h, &p.pass, &l, p.footprint);
                }
            }
        }
        h.finish()
    }
}
