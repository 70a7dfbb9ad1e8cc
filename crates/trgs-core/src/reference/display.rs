//! Stage `display` (shaders/render/display.wgsl): a layer's per-pixel `vec4` values to 8-bit RGBA
//! for a screen or a PNG. Colour layers are clamped to [0, 1] as they are (trgs's colours are
//! display-referred, as in 3DGS); scalar layers become gray; depth becomes gray inverse depth
//! between a near and a far distance, so that near things are bright and the range that matters
//! indoors gets most of the levels. Packing follows WGSL's `pack4x8unorm`: red in the low byte,
//! each channel `floor(0.5 + 255 clamp(v, 0, 1))`.
use crate::pipeline::DisplayMapping;

/// WGSL's `pack4x8unorm`.
pub fn pack4x8unorm(v: [f32; 4]) -> u32 {
    v.iter().enumerate().fold(0u32, |acc, (i, &c)| {
        let q = (0.5 + 255.0 * c.clamp(0.0, 1.0)).floor() as u32;
        acc | (q << (8 * i))
    })
}

/// One pixel.
pub fn display_pixel(p: [f32; 4], mapping: DisplayMapping) -> u32 {
    let rgb = match mapping {
        DisplayMapping::Rgb => [p[0], p[1], p[2]],
        DisplayMapping::Gray { channel } => [p[channel as usize]; 3],
        DisplayMapping::InverseDepth { channel, near, far } => {
            let d = p[channel as usize];
            let t = if d > 0.0 {
                let (inv_near, inv_far) = (1.0 / near, 1.0 / far);
                (1.0 / d - inv_far) / (inv_near - inv_far)
            } else {
                0.0
            };
            [t; 3]
        }
        DisplayMapping::Black => [0.0; 3],
    };
    pack4x8unorm([rgb[0], rgb[1], rgb[2], 1.0])
}

/// Every pixel, row-major without padding.
pub fn display(pixels: &[[f32; 4]], mapping: DisplayMapping) -> Vec<u32> {
    pixels.iter().map(|&p| display_pixel(p, mapping)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packing_matches_wgsl_rounding_and_clamping() {
        assert_eq!(pack4x8unorm([0.0, 1.0, 0.5, 2.0]), 0xff_80_ff_00);
        assert_eq!(pack4x8unorm([-1.0, 0.5 / 255.0, 0.0, 0.0]) & 0xffff, 0x0100);
    }

    #[test]
    fn inverse_depth_spans_near_to_far_and_blacks_out_empty_pixels() {
        let m = DisplayMapping::InverseDepth { channel: 0, near: 1.0, far: 4.0 };
        let gray = |d: f32| display_pixel([d, 0.0, 0.0, 0.0], m) & 0xff;
        assert_eq!(gray(1.0), 255);
        assert_eq!(gray(0.5), 255);
        assert_eq!(gray(4.0), 0);
        assert_eq!(gray(100.0), 0);
        assert_eq!(gray(0.0), 0);
        assert_eq!(gray(2.0), 85); // (1/2 - 1/4) / (1 - 1/4) = 1/3
    }

    #[test]
    fn alpha_is_opaque_and_black_is_black() {
        assert_eq!(display_pixel([0.3, 0.4, 0.5, 0.0], DisplayMapping::Black), 0xff_00_00_00);
        let g = display_pixel([0.0, 0.0, 0.25, 0.0], DisplayMapping::Gray { channel: 2 });
        assert_eq!(g, 0xff_40_40_40);
    }
}
