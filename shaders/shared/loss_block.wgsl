// The pixel blocks of the training losses: a 16x16 workgroup owns a 16x16 block of pixels and
// stages its neighbourhood, with a halo of SSIM_RADIUS pixels, in workgroup memory, so that the
// 11-tap SSIM window runs as two separable passes (rows, then columns) out of shared memory.
// Samples outside the image read as zero: 3DGS's conv2d with zero padding.

const LOSS_BLOCK: u32 = 16u;
// Side of a block with its halo, and its sample count.
const LOSS_SPAN: u32 = 26u;
const LOSS_SPAN_SAMPLES: u32 = 676u;
// Row-blurred samples: LOSS_SPAN rows of LOSS_BLOCK columns.
const LOSS_ROW_SAMPLES: u32 = 416u;

// The pixel of halo-block sample k of the block at `block_origin`, and whether it is inside.
fn loss_span_pixel(block_origin: vec2<u32>, k: u32, width: u32, height: u32) -> vec3<u32> {
    let q = vec2<i32>(block_origin) + vec2<i32>(i32(k % LOSS_SPAN), i32(k / LOSS_SPAN))
        - vec2<i32>(i32(SSIM_RADIUS));
    let inside = q.x >= 0 && q.y >= 0 && u32(q.x) < width && u32(q.y) < height;
    return vec3<u32>(u32(max(q.x, 0)), u32(max(q.y, 0)), select(0u, 1u, inside));
}
