//! What a view's trained layers say of a kept plane's glass, pixel by pixel, for its refit
//! (`super::plane_refit`): whether the learned mask says glass and whether the view sees
//! through the plane, and which of the two ([`GlassEvidence`]) is read as glass.
use trgs_core::Image;
use trgs_core::plane_math::ray_rectangle_hit;
use trgs_core::scene::{Camera, ReflectionPlane};
use trgs_render::FrameImages;

/// What says where a kept plane's glass is in the views of [`glass_pixels`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum GlassEvidence {
    /// Glass one sees through: its pixels are those that see through the plane. A masked pixel
    /// that does not is a frame or a mullion in the plane: the learned mask is smooth and spills
    /// over the pane's edge onto them (on a pane turned in its opening, onto one side of its
    /// frame only, and the rectangle then grew that way).
    SeenThrough,
    /// A mirror, which nothing is seen through once trained: its pixels are its mask's.
    Mask,
}

impl GlassEvidence {
    /// Which evidence `list`'s views ([`glass_pixels`] labels) hold: glass one sees through
    /// where at least as many of the plane's pixels see through it as are masked without doing
    /// so.
    pub fn of(list: &[(usize, Image<u8>)]) -> Self {
        let count = |what: fn(u8) -> bool| -> usize {
            list.iter().map(|(_, m)| m.data.iter().filter(|&&v| what(v)).count()).sum()
        };
        let seen = count(|v| v & SEEN_THROUGH != 0);
        let masked_on_the_plane = count(|v| v & (MASKED | SEEN_THROUGH) == MASKED);
        if seen >= masked_on_the_plane { Self::SeenThrough } else { Self::Mask }
    }

    /// Whether a [`glass_pixels`] label is glass by this evidence.
    pub fn takes(self, label: u8) -> bool {
        let bit = match self {
            Self::SeenThrough => SEEN_THROUGH,
            Self::Mask => MASKED,
        };
        label & bit != 0
    }

    pub fn describe(self) -> &'static str {
        match self {
            Self::SeenThrough => "seen through it",
            Self::Mask => "its mask",
        }
    }
}

/// A pixel sees through a plane when its transmission depth is at least this many times the
/// plane's depth there: what it shows lies beyond the plane, not on it (a frame, a wall). Well
/// above 1: the trial's plane can stand centimetres in front of its wall and frame, and at a
/// ratio near 1 they count as seen through; the labels then fill the rectangle and pin neither
/// its edges nor its offset.
const SEEN_THROUGH_DEPTH: f32 = 1.1;

/// [`glass_pixels`]' labels, bits of what a pixel shows: neither, either or both.
pub(super) const NOT_GLASS: u8 = 0;
/// The learned mask says glass (M >= 1/2).
pub(super) const MASKED: u8 = 1;
/// The view sees through the plane there ([`SEEN_THROUGH_DEPTH`]).
pub(super) const SEEN_THROUGH: u8 = 2;

/// What a view's trained layers say of plane `k`'s glass where plane `k` is hit: whether the
/// learned mask says glass ([`MASKED`]) and whether the view sees through the plane
/// ([`SEEN_THROUGH`]); [`GlassEvidence`] picks which of the two says glass. The mask alone
/// leaves out glass whose reflection is faint (a dark floor seen through clear glass), where
/// nothing in the loss holds M up, and a rectangle fitted to it shrinks off the pane; the depth
/// alone leaves out a mirror, which nothing is seen through once trained. A frame or a wall
/// inside the first rectangle is neither, where the mask does not spill onto it.
pub(super) fn glass_pixels(
    k: usize,
    plane: &ReflectionPlane,
    camera: &Camera,
    images: &FrameImages,
) -> Image<u8> {
    let (w, h) = (images.hit.width, images.hit.height);
    let origin = camera.pose.centre();
    let mut out = Image::<u8>::new(w, h, 1);
    for y in 0..h {
        for x in 0..w {
            let p = (y * w + x) as usize;
            if images.hit.data[p] as usize != k + 1 {
                continue;
            }
            // The rendered depth is camera-space z, not the distance along the (unit) ray:
            // compared with the distance, a pixel off the view's axis needed more depth to see
            // through, and the rectangle shrank from the side of the glass nearer the border.
            let ray = camera.pixel_ray(x, y);
            let seen_through = ray_rectangle_hit(plane, origin, ray).is_some_and(|s| {
                let z = camera.pose.transform_point(origin + s * ray).z;
                images.depth.data[p] >= SEEN_THROUGH_DEPTH * z as f32
            });
            let masked = images.mask.data[p] >= 0.5;
            out.data[p] = (u8::from(masked) * MASKED) | (u8::from(seen_through) * SEEN_THROUGH);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// A camera 2 in front of a 1 x 1 pane that fills the middle of its 8 x 8 view.
    fn pane_in_view() -> (ReflectionPlane, Camera, FrameImages) {
        use trgs_core::scene::{Intrinsics, Material, Pose};
        let plane =
            ReflectionPlane::new(DVec3::ZERO, DVec3::Z, DVec3::X, 1.0, 1.0, Material::Glass);
        let eye = DVec3::new(0.0, 0.0, 2.0);
        let k = Intrinsics::from_fov_x(60f64.to_radians(), 8, 8);
        let camera = Camera::new("c".to_string(), k, Pose::look_at(eye, DVec3::ZERO, DVec3::Y));
        let f = |v: f32| Image::<f32>::filled(8, 8, 1, v);
        let mut hit = Image::<u32>::new(8, 8, 1);
        for y in 0..8 {
            for x in 0..8 {
                let ray = camera.pixel_ray(x, y);
                let p = (y * 8 + x) as usize;
                hit.data[p] = u32::from(ray_rectangle_hit(&plane, eye, ray).is_some());
            }
        }
        let images = FrameImages {
            color: Image::filled(8, 8, 3, 0.0),
            transmission: Image::filled(8, 8, 3, 0.0),
            depth: f(2.0),
            depth_variance: f(0.0),
            mask: f(0.0),
            alpha: f(1.0),
            hit,
            strength_raw: f(0.0),
            strength: f(0.0),
            reflection: Image::filled(8, 8, 3, 0.0),
            planes: Vec::new(),
        };
        (plane, camera, images)
    }

    #[test]
    fn a_pixel_of_the_plane_says_whether_it_is_masked_and_whether_it_sees_through() {
        let (plane, camera, mut images) = pane_in_view();
        let inside: Vec<usize> = (0..64).filter(|&p| images.hit.data[p] == 1).collect();
        assert!(inside.len() >= 4 && inside.len() < 64, "{} pixels hit", inside.len());
        let labelled = |images: &FrameImages, k: usize, label: u8| -> Vec<usize> {
            let m = glass_pixels(k, &plane, &camera, images);
            (0..64).filter(|&p| m.data[p] == label).collect()
        };
        // On the plane (a frame, a wall) with a low mask: neither.
        assert_eq!(labelled(&images, 0, NOT_GLASS).len(), 64);
        // Seen through with a low mask (faint reflection), where the plane is hit only.
        images.depth = Image::filled(8, 8, 1, 3.0);
        assert_eq!(labelled(&images, 0, SEEN_THROUGH), inside);
        // At the pane's corners, off the view's axis, as at its centre: the depth is
        // camera-space z (the plane's is 2 at every pixel), not the distance along the ray.
        images.depth = Image::filled(8, 8, 1, 2.0 * SEEN_THROUGH_DEPTH + 0.01);
        assert_eq!(labelled(&images, 0, SEEN_THROUGH), inside);
        images.depth = Image::filled(8, 8, 1, 2.0 * SEEN_THROUGH_DEPTH - 0.01);
        assert_eq!(labelled(&images, 0, NOT_GLASS).len(), 64);
        images.depth = Image::filled(8, 8, 1, 3.0);
        // Both.
        images.mask = Image::filled(8, 8, 1, 0.9);
        assert_eq!(labelled(&images, 0, MASKED | SEEN_THROUGH), inside);
        // On the plane with a high mask (a mirror, or a frame the mask spills onto).
        images.depth = Image::filled(8, 8, 1, 2.0);
        assert_eq!(labelled(&images, 0, MASKED), inside);
        // Another plane's pixels are not this one's.
        assert_eq!(labelled(&images, 1, NOT_GLASS).len(), 64);
    }

    #[test]
    fn glass_seen_through_is_told_from_a_mirror_by_its_pixels() {
        let view = |labels: &[u8]| {
            let data = labels.to_vec();
            (0, Image { width: data.len() as u32, height: 1, channels: 1, data })
        };
        // A pane: mostly seen through, its mask spilt onto a frame (masked, not seen through).
        let both = MASKED | SEEN_THROUGH;
        let pane = [view(&[both, both, SEEN_THROUGH, SEEN_THROUGH, MASKED, MASKED, NOT_GLASS])];
        assert_eq!(GlassEvidence::of(&pane), GlassEvidence::SeenThrough);
        // A mirror: nothing seen through it, its mask over it.
        let mirror = [view(&[MASKED, MASKED, MASKED, NOT_GLASS, SEEN_THROUGH])];
        assert_eq!(GlassEvidence::of(&mirror), GlassEvidence::Mask);
        let takes = |e: GlassEvidence| (0..4u8).filter(|&l| e.takes(l)).collect::<Vec<_>>();
        assert_eq!(takes(GlassEvidence::SeenThrough), [SEEN_THROUGH, MASKED | SEEN_THROUGH]);
        assert_eq!(takes(GlassEvidence::Mask), [MASKED, MASKED | SEEN_THROUGH]);
    }
}
