//! What loading did to the photos (scaled down, undistorted) and the glass masks (soft edges
//! moved to the nearest label), gathered over the views into the lines of the run's log.
use super::{Resolution, View};

/// A width and height.
pub(super) type Size = (u32, u32);

/// A loaded view and what loading did to it.
pub(super) type Loaded = (View, ViewReport);

/// What loading did to one view.
pub(super) struct ViewReport {
    /// Its training size.
    pub(super) size: Size,
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
    /// The views made larger than their photos (only `--resolution` does that).
    enlarged: Option<Scaled>,
    /// The first portrait and the first landscape training size, and how many of each.
    portrait: Option<(usize, Size)>,
    landscape: Option<(usize, Size)>,
    /// How many masks had soft edges, and the first.
    soft: Option<(usize, SoftMask)>,
}

impl LoadNotes {
    pub(super) fn add(&mut self, report: ViewReport) {
        let (w, h) = report.size;
        let side = if h > w { &mut self.portrait } else { &mut self.landscape };
        side.get_or_insert((0, report.size)).0 += 1;
        if let Some((from, to)) = report.scaled {
            self.scaled.get_or_insert(Scaled { views: 0, from, to }).views += 1;
            if to.0 > from.0 || to.1 > from.1 {
                self.enlarged.get_or_insert(Scaled { views: 0, from, to }).views += 1;
            }
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
        // `--resolution` sets every photo's width: with portrait photos beside landscape ones
        // (a phone's) the portrait ones train at a longer side than asked for, or are enlarged
        // (more pixels to train on, no more detail); a user asking for "1600 px" means neither.
        if let Resolution::Width(width) = resolution {
            if let (Some((p, (pw, ph))), Some((l, (lw, lh)))) = (self.portrait, self.landscape) {
                lines.push(format!(
                    "--resolution {width} sets the width of every photo: {p} portrait photos \
                     train at {pw}x{ph} and {l} landscape ones at {lw}x{lh}; for photos of both \
                     orientations --downscale, or the default (1600 px on the longer side), \
                     treat them alike"
                ));
            }
            if let Some(e) = self.enlarged {
                let (n, (fw, fh), (w, h)) = (e.views, e.from, e.to);
                lines.push(format!(
                    "{n} photos narrower than --resolution {width} are enlarged to it ({fw}x{fh} \
                     -> {w}x{h}): more pixels to train on, no more detail"
                ));
            }
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

#[cfg(test)]
mod tests {
    use super::*;

    fn scaled(from: Size, to: Size) -> ViewReport {
        ViewReport { size: to, scaled: Some((from, to)), lens: None, soft: None }
    }

    #[test]
    fn a_width_over_photos_of_both_orientations_is_named() {
        // A phone's photos at full size: a width shrinks both, the portrait ones to a longer
        // side than the landscape ones.
        let mut notes = LoadNotes::default();
        notes.add(scaled((4032, 3024), (1600, 1200)));
        notes.add(scaled((3024, 4032), (1600, 2133)));
        notes.add(scaled((3024, 4032), (1600, 2133)));
        let lines = notes.lines(Resolution::Width(1600));
        assert_eq!(lines.len(), 1, "{lines:?}");
        assert!(lines[0].contains("2 portrait photos train at 1600x2133"), "{lines:?}");
        assert!(lines[0].contains("1 landscape ones at 1600x1200"), "{lines:?}");
        // The same photos by the default rule: one size on the longer side, nothing to say
        // of orientations.
        assert!(notes.lines(Resolution::LongSide(1600)).iter().all(|l| !l.contains("portrait")));
        // One orientation: nothing either.
        let mut notes = LoadNotes::default();
        notes.add(scaled((4032, 3024), (1600, 1200)));
        assert!(notes.lines(Resolution::Width(1600)).is_empty());
    }

    #[test]
    fn photos_enlarged_by_a_width_are_named() {
        // Photos already cut to 1600 px on the longer side, then --resolution 1600.
        let mut notes = LoadNotes::default();
        notes.add(scaled((1200, 1600), (1600, 2133)));
        notes.add(ViewReport { size: (1600, 1200), scaled: None, lens: None, soft: None });
        let lines = notes.lines(Resolution::Width(1600));
        let enlarged: Vec<_> = lines.iter().filter(|l| l.contains("enlarged")).collect();
        assert_eq!(enlarged.len(), 1, "{lines:?}");
        assert!(enlarged[0].starts_with("1 photos narrower than --resolution 1600"), "{lines:?}");
        assert!(enlarged[0].contains("1200x1600 -> 1600x2133"), "{lines:?}");
    }
}
