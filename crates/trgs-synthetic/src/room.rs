//! The fixed size of the scene's two rooms, which the layout builds and the camera paths stay
//! inside.

/// Room size in the local frame: x in [-HALF_WIDTH, HALF_WIDTH], y in [0, HEIGHT], the camera
/// room z in [0, FRONT_DEPTH], the room behind the glass z in [-depth, 0] with the depth of
/// [`Backdrop::depth`](super::Backdrop::depth).
pub(super) const HALF_WIDTH: f64 = 3.0;
pub(super) const HEIGHT: f64 = 2.8;
pub(super) const FRONT_DEPTH: f64 = 5.0;
