//! What loading did to the photos (scaled down, undistorted) and the glass masks (soft edges
//! moved to the nearest label), gathered over the views into the lines of the run's log.
use super::{Resolution, View};

/// A width and height.
pub(super) type Size = (u32, u32);

/// A loaded view and what loading did to it.
pub(super) type Loaded = (View, ViewReport);

/// What loading did to one view.
pub(super) struct ViewReport {
    /// Its pinhole size and its training size, when they differ.
    pub(super) scaled: Option<(Size, Size)>,
    pub(super) lens: Option<LensNote>,
    pub(super) soft: Option<SoftMask>,
}

/// A glass mask with soft edges: its path (as the scene folder names it) and how many of its
/// pixels were moved to the nearest label.
pub(super) struct SoftMask {
    pub(super) path: String,
    pub(super) pixels: usize,
}

/// How many views were scaled, and the first one's sizes.
#[derive(Clone, Copy)]
struct Scaled {
    views: usize,
    from: Size,
    to: Size,
}

/// What loading did to the photos, gathered over the views for the run's log.
#[derive(Default)]
pub(super) struct LoadNotes {
    lenses: Vec<LensNote>,
    scaled: Option<Scaled>,
    /// How many masks had soft edges, and the first.
    soft: Option<(usize, SoftMask)>,
}

impl LoadNotes {
    pub(super) fn add(&mut self, report: ViewReport) {
        if let Some((from, to)) = report.scaled {
            self.scaled.get_or_insert(Scaled { views: 0, from, to }).views += 1;
        }
        if let Some(mask) = report.soft {
            self.soft.get_or_insert((0, mask)).0 += 1;
        }
        if let Some(lens) = report.lens {
            match self
                .lenses
                .iter_mut()
                .find(|n| n.lens == lens.lens && n.describe == lens.describe)
            {
                Some(n) => n.views += 1,
                None => self.lenses.push(lens),
            }
        }
    }

    pub(super) fn lines(&self, resolution: Resolution) -> Vec<String> {
        let mut lines: Vec<String> = self.lenses.iter().map(LensNote::line).collect();
        if let (Some(s), Resolution::LongSide(side)) = (self.scaled, resolution) {
            let (n, (fw, fh), (w, h)) = (s.views, s.from, s.to);
            lines.push(format!(
                "{n} photos longer than {side} px are trained at {side} on their longer side \
                 ({fw}x{fh} -> {w}x{h}); --full-size keeps their size, --resolution or \
                 --downscale choose another"
            ));
        }
        if let Some((n, first)) = &self.soft {
            let masks =
                if *n == 1 { "1 glass mask has".into() } else { format!("{n} glass masks have") };
            lines.push(format!(
                "{masks} soft edges (first: {}, {} pixels between labels): assigned to the \
                 nearest label; paint each pane with one value",
                first.path, first.pixels
            ));
        }
        lines
    }
}

/// What the loader did to the photos of one lens, for the run's log.
pub(super) struct LensNote {
    pub(super) lens: String,
    pub(super) describe: String,
    pub(super) photo: (u32, u32),
    pub(super) pinhole: (u32, u32),
    pub(super) views: usize,
    /// Pixels without a source in the first view (at the training resolution), of `pixels`.
    pub(super) blank: usize,
    pub(super) pixels: usize,
}

impl LensNote {
    fn line(&self) -> String {
        let blank = if self.blank == 0 {
            "every pixel has a source".to_string()
        } else {
            format!(
                "{} of {} pixels have no source and are left out of the loss",
                self.blank, self.pixels
            )
        };
        format!(
            "camera model {} ({}) on {} views: undistorted from {}x{} photos into {}x{} pinhole \
             views, as colmap image_undistorter would; {blank}",
            self.lens,
            self.describe,
            self.views,
            self.photo.0,
            self.photo.1,
            self.pinhole.0,
            self.pinhole.1
        )
    }
}
