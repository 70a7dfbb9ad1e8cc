//! What a render is asked for ([`RenderOptions`]) and how it can fail ([`RenderError`]).
use crate::frame::KeySizing;
use crate::gpu::GpuError;
use trgs_core::pipeline::ReflectionModel;
use trgs_core::scene::{CameraError, InvalidInput};

/// How to render.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Colour behind the last transmittance of C_t.
    pub background: [f32; 3],
    /// Gaussians with a camera-space depth below this are culled (0.2 as in 3DGS).
    pub near: f64,
    /// Compute the depth-variance layer V (a second walk over each pixel's Gaussians; only the
    /// depth-variance loss needs it).
    pub depth_variance: bool,
    /// Per-plane switch (missing entries are on): a disabled plane gets no mirrored pass and no
    /// hit, as if it were not in the scene.
    pub enabled_planes: Vec<bool>,
    /// Time every stage with timestamp queries when the adapter has them
    /// ([`Frame::stage_times`](crate::Frame::stage_times)).
    pub profile: bool,
    /// Evaluate SH only up to this degree (training's degree schedule); None or a larger value
    /// uses the scene's. The backward of the frame follows the same degree.
    pub sh_degree: Option<u32>,
    /// Keep copies of the tile counts and the unsorted keys (stage-by-stage tests).
    pub capture_intermediates: bool,
    /// Parts of the reflection model (Schlick, the intensity map A) switched off for ablations;
    /// the backward of the frame follows the same model.
    pub reflection: ReflectionModel,
    /// How the frame's key list is sized: exactly, waiting for the binning's totals halfway
    /// through the render, or from earlier frames without waiting ([`KeySizing`]).
    pub key_sizing: KeySizing,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            background: [0.0; 3],
            near: 0.2,
            depth_variance: false,
            enabled_planes: Vec::new(),
            profile: false,
            sh_degree: None,
            capture_intermediates: false,
            reflection: ReflectionModel::default(),
            key_sizing: KeySizing::Exact,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error(transparent)]
    Input(#[from] InvalidInput),
    #[error("camera {name:?}: {source}")]
    Camera { name: String, source: CameraError },
    #[error("camera {name:?}: image size {width}x{height} must be at least 1x1")]
    EmptyImage { name: String, width: u32, height: u32 },
    /// One of the frame's buffers would exceed what the adapter can bind at once.
    #[error(
        "camera {name:?}: the frame's {what} need {bytes} bytes in one binding, over the \
         adapter's limit of {limit} bytes; render at a lower resolution or with fewer Gaussians"
    )]
    FrameTooLarge { name: String, what: &'static str, bytes: u64, limit: u64 },
    /// The image needs more tiles along one axis than a dispatch can have workgroups.
    #[error(
        "camera {name:?}: {tiles} tiles along one image axis, over the adapter's limit of {limit} \
         workgroups per dispatch dimension; render at a lower resolution"
    )]
    TooManyTiles { name: String, tiles: u32, limit: u32 },
    #[error(transparent)]
    Gpu(#[from] GpuError),
}
