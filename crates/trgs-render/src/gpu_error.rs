//! GPU failures after setup as values, not panics: an embedding app that renders on a device it
//! shares (a viewer, an editor) must be able to report a lost device or an out-of-memory frame
//! and go on, where a panic inside the library would take the whole process down.
//!
//! Two sources feed [`GpuError`]:
//! - waits and readbacks: a device that is lost, or that does not finish in
//!   [`crate::gpu::GPU_WAIT_LIMIT`], fails the wait or the mapping;
//! - [`ErrorScopes`]: wgpu reports an operation's out-of-memory, validation and internal errors
//!   to the innermost error scope, and only when there is none to the device's uncaptured-error
//!   handler, whose default panics. Every public entry point that records GPU work runs inside
//!   scopes of its own, so its errors come back from it and the app's handler (if it set one)
//!   sees none of them.
use crate::GpuContext;

/// A GPU failure during rendering, training or a readback.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum GpuError {
    #[error(
        "the GPU ran out of memory while {what} ({detail}); render or train at a lower \
         resolution or with fewer Gaussians"
    )]
    OutOfMemory { what: String, detail: String },
    #[error("the GPU device was lost while {what} ({detail}); create a new GpuContext to go on")]
    Lost { what: String, detail: String },
    #[error(
        "the GPU did not finish {what} within {seconds} s (a hung kernel or a device that stopped \
         answering)"
    )]
    Timeout { what: String, seconds: u64 },
    /// wgpu refused an operation (a validation or internal error): a defect in trgs or in the
    /// resources an app passed in, never a condition of the scene.
    #[error("wgpu refused an operation while {what}: {detail}")]
    Rejected { what: String, detail: String },
}

impl GpuError {
    fn from_wgpu(what: &str, error: &wgpu::Error) -> Self {
        let what = what.to_string();
        match error {
            wgpu::Error::OutOfMemory { source } => {
                Self::OutOfMemory { what, detail: source.to_string() }
            }
            wgpu::Error::Validation { description, .. }
            | wgpu::Error::Internal { description, .. } => {
                Self::Rejected { what, detail: description.trim().to_string() }
            }
        }
    }
}

/// Error scopes around one public operation: `open` before its first GPU call, `close` after its
/// last. Scopes are per thread, so an operation must close on the thread that opened it (the
/// guards are not `Send`). Dropped unclosed (an early return), the scopes are popped and what they
/// caught is dropped: the early return already carries its own error.
#[derive(Debug)]
#[must_use = "close the scopes to learn whether the operation failed"]
pub struct ErrorScopes {
    what: &'static str,
    ctx: GpuContext,
    // Innermost last: popped in reverse order, as wgpu requires.
    guards: Vec<wgpu::ErrorScopeGuard>,
}

impl ErrorScopes {
    /// Catch the out-of-memory, validation and internal errors of what follows; `what` names the
    /// operation in the error ("rendering a frame").
    pub fn open(ctx: &GpuContext, what: &'static str) -> Self {
        let guards = [
            wgpu::ErrorFilter::Internal,
            wgpu::ErrorFilter::Validation,
            wgpu::ErrorFilter::OutOfMemory,
        ]
        .into_iter()
        .map(|f| ctx.device.push_error_scope(f))
        .collect();
        Self { what, ctx: ctx.clone(), guards }
    }

    /// Pop the scopes; the first error any of them caught (out of memory before the others). On a
    /// lost device every resource is invalid and wgpu refuses to use it: that is reported as
    /// the loss, not as the refusal it causes.
    pub fn close(mut self) -> Result<(), GpuError> {
        let mut first = None;
        while let Some(guard) = self.guards.pop() {
            // wgpu-core reports errors when the call is made, so the future is ready.
            if let Some(e) = pollster::block_on(guard.pop()) {
                first.get_or_insert(GpuError::from_wgpu(self.what, &e));
            }
        }
        let Some(first) = first else {
            return Ok(());
        };
        match loss_after_poll(&self.ctx) {
            Some(reason) => Err(lost(self.what, reason)),
            None => Err(first),
        }
    }

    /// Close the scopes after `result`. When both failed, a caught loss or lack of memory is the
    /// cause and wins (the operation's own error is then one of its consequences, such as a
    /// mapping refused on a buffer that could not be made); otherwise the operation's error does.
    pub fn close_after<T, E: From<GpuError>>(self, result: Result<T, E>) -> Result<T, E> {
        match (result, self.close()) {
            (Ok(value), Ok(())) => Ok(value),
            (Ok(_), Err(caught)) => Err(caught.into()),
            (Err(e), Ok(())) => Err(e),
            (Err(e), Err(caught)) => match caught {
                GpuError::OutOfMemory { .. } | GpuError::Lost { .. } => Err(caught.into()),
                GpuError::Timeout { .. } | GpuError::Rejected { .. } => Err(e),
            },
        }
    }
}

impl Drop for ErrorScopes {
    /// Unclosed (an early return), the scopes are popped innermost first, as wgpu requires (a
    /// `Vec` would drop its guards outermost first, which wgpu refuses with a panic).
    fn drop(&mut self) {
        while let Some(guard) = self.guards.pop() {
            drop(guard);
        }
    }
}

/// The loss of the device while doing `what`.
pub(crate) fn lost(what: &str, detail: String) -> GpuError {
    GpuError::Lost { what: what.to_string(), detail }
}

/// Why the device was lost, if it was: the loss is learnt in a poll of the device, and an
/// operation that did not wait for the GPU has not polled since, so it polls first (without
/// waiting; a poll that panics on the lost device counts as one).
fn loss_after_poll(ctx: &GpuContext) -> Option<String> {
    if let Some(reason) = ctx.lost() {
        return Some(reason);
    }
    let polled = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        ctx.device.poll(wgpu::PollType::Poll)
    }));
    match polled {
        Ok(_) => ctx.lost(),
        Err(_) => Some(ctx.lost().unwrap_or_else(|| "wgpu stopped while polling".to_string())),
    }
}

/// Run `f` inside [`ErrorScopes`] named `what`.
pub fn scoped<T, E: From<GpuError>>(
    ctx: &GpuContext,
    what: &'static str,
    f: impl FnOnce() -> Result<T, E>,
) -> Result<T, E> {
    let scopes = ErrorScopes::open(ctx, what);
    scopes.close_after(f())
}
