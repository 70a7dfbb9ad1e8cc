//! The planes' gradients of a backward pass, read back when the caller asks: the plane sums and
//! mirrored views' gradients come back in one small readback, which is chained into each plane
//! on the CPU (a dozen numbers per plane, the twin's own `mirrored_view_bwd` and `plane_grad`).
//! The backward does not wait for them, so a training step can read them after it has submitted
//! the next step.
use crate::GpuContext;
use crate::gpu::{GpuError, PendingRead};
use crate::layout::VIEW_GRAD_FLOATS;
use glam::{DMat3, DVec3};
use trgs_core::plane_grad::{PlaneGrad, ViewGrads, mirrored_view_bwd, plane_grad};
use trgs_core::scene::{ReflectionPlane, ViewTransform};

/// dL/d(each plane's centre, unnormalised normal, R0 logit) of one backward pass, on its way
/// back from the GPU.
#[derive(Debug, Default)]
pub struct PlaneGradsRead {
    pending: Option<Pending>,
}

#[derive(Debug)]
struct Pending {
    read: PendingRead,
    /// The planes and the real view the frame was rendered with (the chain's linearisation
    /// point, whatever the planes are when the values arrive).
    planes: Vec<ReflectionPlane>,
    real: ViewTransform,
    /// Per plane, the index of its mirrored view (None: it had no pass).
    mirrored: Vec<Option<usize>>,
    /// Bytes of the plane sums, then of each view's gradient slot.
    plane_bytes: u64,
    view_stride: u64,
    bytes: u64,
}

impl PlaneGradsRead {
    /// The gradients of `planes` from a readback of `read` (the plane sums, `plane_bytes`, then a
    /// slot of `view_stride` bytes per view): `mirrored[k]` is plane k's view.
    pub(crate) fn pending(
        read: PendingRead,
        planes: Vec<ReflectionPlane>,
        real: ViewTransform,
        mirrored: Vec<Option<usize>>,
        (plane_bytes, view_stride, bytes): (u64, u64, u64),
    ) -> Self {
        let p = Pending { read, planes, real, mirrored, plane_bytes, view_stride, bytes };
        Self { pending: Some(p) }
    }

    /// The planes' gradients, in the scene's order (empty without planes), waiting for the
    /// backward pass only if they have not arrived.
    pub fn read(self, ctx: &GpuContext) -> Result<Vec<PlaneGrad>, GpuError> {
        let Some(p) = self.pending else { return Ok(Vec::new()) };
        let flat: Vec<f32> = p.read.read(ctx, p.bytes as usize)?;
        let stride = (p.view_stride / 4) as usize;
        let view_of = |vi: usize| {
            let o = (p.plane_bytes / 4) as usize + vi * stride;
            view_grads(&flat[o..o + VIEW_GRAD_FLOATS as usize])
        };
        let grads = p
            .planes
            .iter()
            .zip(&p.mirrored)
            .enumerate()
            .map(|(k, (plane, mirrored))| {
                let c = &flat[4 * k..4 * k + 4];
                let mut g_n = DVec3::new(f64::from(c[1]), f64::from(c[2]), f64::from(c[3]));
                let mut g_u = DVec3::ZERO;
                if let Some(vi) = *mirrored {
                    let (du, dn) = mirrored_view_bwd(plane, &p.real, &view_of(vi));
                    g_u += du;
                    g_n += dn;
                }
                plane_grad(plane, g_u, g_n, f64::from(c[0]))
            })
            .collect();
        Ok(grads)
    }
}

/// A mirrored view's gradient from its VIEW_GRAD_FLOATS (linear map by columns, translation,
/// centre).
fn view_grads(v: &[f32]) -> ViewGrads {
    let d = |i: usize| f64::from(v[i]);
    let col = |i: usize| DVec3::new(d(i), d(i + 1), d(i + 2));
    ViewGrads {
        linear: DMat3::from_cols(col(0), col(3), col(6)),
        translation: col(9),
        centre: col(12),
    }
}
