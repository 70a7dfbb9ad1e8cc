//! The frame's key totals (the depth order's entries, each view's tile keys), which size its key
//! list: read back before the keys are emitted ([`KeySizing::Exact`]), or after the frame
//! without waiting for it, the list sized from earlier frames ([`KeySizing::FromEarlierFrames`]).
use super::{Frame, ViewBuffers};
use crate::GpuContext;
use crate::gpu::{GpuError, PendingRead};

/// How a frame's key list is sized.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum KeySizing {
    /// Exactly: the render reads the key totals back between binning and emitting the keys,
    /// waiting for the GPU there.
    #[default]
    Exact,
    /// From the largest total this frame has held (times the growth expected of a changed set,
    /// [`Frame::expect_set_scaled`]), with a quarter of headroom, without waiting:
    /// the totals are read back after the frame ([`Frame::settle_keys`]), which then says
    /// whether the list held every key. A frame that did not is wrong: render it again (the
    /// next render is sized from its totals), or, not to wait for the totals, gate what learns
    /// from it on the GPU by [`Frame::key_overflow_flag`] (a training step's `step_guard`). The
    /// first render into a frame, and one that captures intermediates, are exact.
    FromEarlierFrames,
}

/// What a frame's key list held.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct KeyTotals {
    /// Keys of every view of the frame.
    pub keys: u64,
    /// Keys the list could hold.
    pub capacity: u64,
}

impl KeyTotals {
    /// Whether the list held every key (otherwise the frame dropped some).
    pub fn held(&self) -> bool {
        self.keys <= self.capacity
    }
}

/// Words of the totals' readback for `views` views: [entries, (low word, carries) of each
/// view's key total, the scan's total].
pub(crate) fn words(views: usize) -> usize {
    2 * views + 2
}

/// The totals as read back.
pub(crate) struct Totals {
    pub entries: u32,
    pub view_keys: Vec<u64>,
}

impl Totals {
    pub(crate) fn decode(words: &[u32]) -> Self {
        let view_keys = words[1..words.len() - 1]
            .chunks_exact(2)
            .map(|w| u64::from(w[0]) | u64::from(w[1]) << 32)
            .collect();
        Self { entries: words[0], view_keys }
    }

    /// Keys of every view.
    pub(crate) fn keys(&self) -> u64 {
        self.view_keys.iter().sum()
    }
}

/// Gives each view its share of the sorted key list: its keys follow the previous view's.
pub(crate) fn assign(views: &mut [ViewBuffers], view_keys: &[u64]) {
    let mut base = 0u64;
    for (v, &keys) in views.iter_mut().zip(view_keys) {
        v.key_base = u32::try_from(base).unwrap_or(u32::MAX);
        v.num_keys = u32::try_from(keys).unwrap_or(u32::MAX);
        base += keys;
    }
}

/// A readback of a render's key totals, submitted with its frame and not waited for: settled
/// by its frame ([`Frame::settle_keys`]), or taken out of it ([`Frame::take_pending_keys`]) and
/// settled later, after the frame has been rendered again ([`Frame::settle_pending_keys`]).
#[derive(Debug)]
pub struct PendingKeyTotals {
    read: PendingRead,
    words: usize,
    capacity: u64,
    /// Which render of its frame it belongs to.
    render: u64,
}

impl PendingKeyTotals {
    /// The totals' mapping `read`, for a key list of `capacity` keys, of render `render`.
    pub(crate) fn start(read: PendingRead, words: usize, capacity: u64, render: u64) -> Self {
        Self { read, words, capacity, render }
    }
}

impl Frame {
    /// The key totals of the last render, and whether its key list held them. A list sized
    /// from earlier frames gets them from their readback, waiting for the frame's GPU work only
    /// if they have not arrived (a training step asks after reading its loss back, by when they
    /// have). None before the first render.
    pub fn settle_keys(&mut self, ctx: &GpuContext) -> Result<Option<KeyTotals>, GpuError> {
        match self.pending_keys.take() {
            Some(p) => self.settle_pending_keys(ctx, p).map(Some),
            None => Ok(self.key_totals),
        }
    }

    /// The readback of the last render's key totals, when the render did not wait for them:
    /// taken out of the frame, so that the frame can be rendered again before they arrive
    /// (a training step finished after the next one was recorded). None when they are known.
    pub fn take_pending_keys(&mut self) -> Option<PendingKeyTotals> {
        self.pending_keys.take()
    }

    /// The key totals of `pending` (taken from this frame), waiting for its render only if they
    /// have not arrived; they size this frame's later key lists. When the frame still holds the
    /// render they belong to, they also describe it ([`Frame::key_count`]).
    pub fn settle_pending_keys(
        &mut self,
        ctx: &GpuContext,
        pending: PendingKeyTotals,
    ) -> Result<KeyTotals, GpuError> {
        let p = pending;
        let words: Vec<u32> = p.read.read(ctx, 4 * p.words)?;
        let totals = Totals::decode(&words);
        let settled = KeyTotals { keys: totals.keys(), capacity: p.capacity };
        self.observe_keys(settled.keys, p.render);
        if p.render == self.renders {
            assign(&mut self.views, &totals.view_keys);
            if let Some(b) = self.binning.as_mut() {
                b.entries = totals.entries;
                b.total = u32::try_from(settled.keys.min(settled.capacity)).unwrap_or(u32::MAX);
            }
            self.key_totals = Some(settled);
        }
        Ok(settled)
    }

    /// A buffer whose second u32 (byte offset 4) the last render set to 1 on the GPU if its key
    /// list dropped keys and to 0 if it held them (written by `emit_keys`, under either
    /// sizing): what a training step gates its updates on before the totals come back. None
    /// before the first render.
    pub fn key_overflow_flag(&self) -> Option<&wgpu::Buffer> {
        self.binning.as_ref().map(|b| &b.kept)
    }

    /// Records a render's totals, known now.
    pub(crate) fn record_key_totals(&mut self, totals: KeyTotals) {
        self.observe_keys(totals.keys, self.renders);
        self.key_totals = Some(totals);
    }

    /// Render `render` had `keys` keys: the largest total grows, and an expectation said before
    /// that render ([`Frame::expect_set_scaled`]) gives way to what it measured.
    fn observe_keys(&mut self, keys: u64, render: u64) {
        self.largest_keys = self.largest_keys.max(keys);
        if self.expected_keys.is_some_and(|(_, after)| render > after) {
            self.expected_keys = None;
        }
    }

    /// The set this frame renders changed so that its keys may grow `ratio` times (a
    /// densification or relocation, which estimates it): until a render of the new set reports
    /// its totals, lists sized from earlier frames expect `ratio` times the largest total (when
    /// over 1), so that the next render need not wait for its totals to size its list exactly.
    /// A list that turns out too small is caught as any other is
    /// ([`KeySizing::FromEarlierFrames`]).
    pub fn expect_set_scaled(&mut self, ratio: f64) {
        // Two changes before a render of the new set reports: the second scales the first's.
        let base = self.largest_keys.max(self.expected_keys.map_or(0, |(k, _)| k));
        if !(ratio > 1.0) || base == 0 {
            return;
        }
        self.expected_keys = Some(((base as f64 * ratio).ceil() as u64, self.renders));
    }

    /// The key list for a render that sizes it from earlier frames: the largest total this frame
    /// has held (or the total expected of a changed set) with a quarter of headroom, at most
    /// `most`; None before any.
    pub(crate) fn key_capacity(&self, most: u64) -> Option<u32> {
        let k = self.largest_keys.max(self.expected_keys.map_or(0, |(k, _)| k));
        (k > 0).then(|| u32::try_from((k + k / 4).min(most)).unwrap_or(u32::MAX))
    }

    /// Leaves the totals of a render that sized its list from earlier frames to arrive later.
    pub(crate) fn expect_key_totals(&mut self, pending: PendingKeyTotals) {
        debug_assert_eq!(pending.render, self.renders, "the totals of this render");
        self.key_totals = None;
        self.pending_keys = Some(pending);
    }
}
