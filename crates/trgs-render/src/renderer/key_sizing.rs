//! How long the frame's key list is: sized from earlier frames before anything is recorded, or
//! exactly from the totals phase 1 copied, read back halfway through the render; and how those
//! totals reach the frame once it is submitted.
use super::binning::TotalsCopy;
use super::options::{RenderError, RenderOptions};
use crate::GpuContext;
use crate::frame::key_totals::{self, PendingKeyTotals, Totals};
use crate::frame::{Frame, KeySizing, KeyTotals, ViewBuffers};
use crate::gpu::{self, PendingRead, Recorder};
use crate::toolkit::paged::MAX_PAGES;
use trgs_core::scene::Camera;

/// What is known of the key list before the render records anything.
#[derive(Debug)]
pub(super) struct KeyBudget {
    /// The most keys a frame can have.
    pub most: u64,
    /// The list's length sized from earlier frames; None: sized exactly, halfway through.
    pub estimate: Option<u32>,
}

/// The key list's length, and the totals it was sized from when they were read back halfway.
pub(super) struct KeyListSize {
    pub capacity: u32,
    pub exact: Option<Totals>,
}

/// The budget of a render into `frame` (reset for it) with pages of `key_page_len` keys.
pub(super) fn key_budget(frame: &Frame, options: &RenderOptions, key_page_len: u32) -> KeyBudget {
    // Over two bindings, or a u32 total that would have wrapped.
    let most = (u64::from(MAX_PAGES) * u64::from(key_page_len)).min(u32::MAX.into());
    let estimate = match options.key_sizing {
        KeySizing::FromEarlierFrames if !options.capture_intermediates => frame.key_capacity(most),
        _ => None,
    };
    KeyBudget { most, estimate }
}

/// The key list's length: the estimate, with the counts left on the GPU (emit_keys drops what
/// the list cannot hold), or the totals copied in phase 1, read back now (the one wait of an
/// exact render), which also give each view its share of the list.
pub(super) fn size_key_list(
    rec: &mut Recorder,
    ctx: &GpuContext,
    camera: &Camera,
    budget: &KeyBudget,
    totals: &TotalsCopy,
    views: &mut [ViewBuffers],
) -> Result<KeyListSize, RenderError> {
    if let Some(capacity) = budget.estimate {
        return Ok(KeyListSize { capacity, exact: None });
    }
    rec.submit_and_wait(ctx)?;
    let words: Vec<u32> = gpu::map_and_read(ctx, &totals.staging, 4 * totals.words)?;
    let read = Totals::decode(&words);
    let all_keys = read.keys();
    let most_keys = budget.most;
    debug_assert!(
        all_keys > most_keys || all_keys == u64::from(words[words.len() - 1]),
        "the views' key totals add up to the scan's"
    );
    // Checked before the u32 scan's total is trusted: a frame of 2^32 keys or more is over two
    // bindings of any adapter's, and its total would have wrapped.
    if all_keys > most_keys {
        return Err(RenderError::FrameTooLarge {
            name: camera.name.clone(),
            what: "tile keys (all views together, in two bindings)",
            bytes: all_keys * 4,
            limit: most_keys * 4,
        });
    }
    key_totals::assign(views, &read.view_keys);
    // Below 2^32: checked above against a binding limit of at most 4 GiB.
    Ok(KeyListSize { capacity: all_keys as u32, exact: Some(read) })
}

/// Submits the render: an exact one waits for the GPU (None), one sized from earlier frames
/// does not (its submission, which its totals' readback follows).
pub(super) fn submit_render(
    rec: &mut Recorder,
    ctx: &GpuContext,
    size: &KeyListSize,
) -> Result<Option<wgpu::SubmissionIndex>, RenderError> {
    if size.exact.is_some() {
        rec.submit_and_wait(ctx)?;
        Ok(None)
    } else {
        Ok(Some(rec.submit(ctx)?))
    }
}

/// Gives the finished `frame` its key totals: known now for an exact list, or their readback
/// after `submission`, settled later ([`Frame::settle_keys`]).
pub(super) fn deliver_totals(
    frame: &mut Frame,
    submission: Option<wgpu::SubmissionIndex>,
    size: &KeyListSize,
    totals: TotalsCopy,
) {
    match submission {
        None => {
            let keys = u64::from(size.capacity);
            frame.record_key_totals(KeyTotals { keys, capacity: keys });
        }
        Some(submission) => frame.expect_key_totals(PendingKeyTotals::start(
            PendingRead::after(totals.staging, submission),
            totals.words,
            u64::from(size.capacity),
            frame.renders(),
        )),
    }
}
