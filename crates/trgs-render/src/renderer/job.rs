//! What the phases of a render share: its inputs ([`RenderJob`]) and the views it projects and
//! bins ([`ViewSpec`]): the camera's own, then the camera mirrored about each plane it sees.
use super::options::RenderOptions;
use crate::scene::GpuScene;
use crate::stages::Stage;
use trgs_core::pipeline::{TileGrid, TileRect};
use trgs_core::plane_math::mirrored_view;
use trgs_core::reference::footprint;
use trgs_core::scene::{Camera, ViewTransform};

/// One render's inputs, as the phases after the checks read them.
#[derive(Clone, Copy, Debug)]
pub(super) struct RenderJob<'a> {
    pub s: Stage<'a>,
    pub scene: &'a GpuScene,
    pub camera: &'a Camera,
    pub options: &'a RenderOptions,
    /// The image's tile grid (checked against the adapter's dispatch limits).
    pub grid: TileGrid,
    /// Keys in a page of the frame's key list ([`super::Renderer::set_key_page_len`]).
    pub key_page_len: u32,
}

impl RenderJob<'_> {
    /// Pixels of the image.
    pub fn pixels(&self) -> u64 {
        u64::from(self.grid.width) * u64::from(self.grid.height)
    }
}

/// One view to project and bin: the real camera, or the camera mirrored about plane `plane`.
#[derive(Debug)]
pub(super) struct ViewSpec {
    pub view: ViewTransform,
    pub plane: Option<usize>,
    pub limit: TileRect,
}

/// The views of the render: the camera over the whole grid, then, for each enabled plane whose
/// rectangle the camera sees from its front side, the mirrored camera over that footprint.
pub(super) fn plan_views(job: &RenderJob<'_>) -> Vec<ViewSpec> {
    let (camera, grid) = (job.camera, &job.grid);
    let view = ViewTransform::from(&camera.pose);
    let mut specs = vec![ViewSpec { view, plane: None, limit: grid.full() }];
    for (i, plane) in job.scene.planes().iter().enumerate() {
        if !job.options.enabled_planes.get(i).copied().unwrap_or(true) {
            continue;
        }
        if let Some(fp) = footprint(plane, &camera.pose, &camera.intrinsics, grid) {
            specs.push(ViewSpec { view: mirrored_view(plane, &view), plane: Some(i), limit: fp });
        }
    }
    specs
}
