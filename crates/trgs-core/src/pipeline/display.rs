//! How stage `display` maps a layer to colours; the GPU stage gets it as `DisplayParams`.

/// How a layer's values map to display colours (`DisplayParams::mode` on the GPU).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DisplayMapping {
    /// `xyz` as RGB.
    Rgb,
    /// One channel as gray.
    Gray { channel: u32 },
    /// One channel holding a depth, as gray `(1/d - 1/far) / (1/near - 1/far)`; `d <= 0` (no
    /// surface) is black.
    InverseDepth { channel: u32, near: f32, far: f32 },
    /// Black (a layer the frame does not have, e.g. the reflection of a frame without planes).
    Black,
}

impl DisplayMapping {
    /// The GPU's (mode, channel, near, far).
    pub fn gpu_fields(self) -> (u32, u32, f32, f32) {
        match self {
            DisplayMapping::Rgb => (0, 0, 0.0, 0.0),
            DisplayMapping::Gray { channel } => (1, channel, 0.0, 0.0),
            DisplayMapping::InverseDepth { channel, near, far } => (2, channel, near, far),
            DisplayMapping::Black => (3, 0, 0.0, 0.0),
        }
    }
}
