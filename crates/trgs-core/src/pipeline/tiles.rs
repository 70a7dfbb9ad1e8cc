//! The screen's tiles: every stage from `tile_counts` to `compose` works on tiles of
//! [`TILE_SIZE`] pixels, and a plane's mirrored pass on a [`TileRect`] of them.

/// Side of a square screen tile in pixels. 8 rather than 3DGS's 16: a tile's list holds the
/// Gaussians that overlap it, so smaller tiles about halve the evaluations per pixel (and the
/// rasterize time of `bench`) for about 1.5x the keys, and a plane's footprint follows its
/// outline more closely.
pub const TILE_SIZE: u32 = 8;
/// Pixels per tile: the rasterizers' workgroup size and batch length.
pub const TILE_PIXELS: u32 = TILE_SIZE * TILE_SIZE;

/// The tile grid of an image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileGrid {
    pub width: u32,
    pub height: u32,
    pub tiles_x: u32,
    pub tiles_y: u32,
}

impl TileGrid {
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            tiles_x: width.div_ceil(TILE_SIZE),
            tiles_y: height.div_ceil(TILE_SIZE),
        }
    }

    pub fn tile_count(&self) -> u32 {
        self.tiles_x * self.tiles_y
    }

    /// Every tile.
    pub fn full(&self) -> TileRect {
        TileRect { x0: 0, y0: 0, x1: self.tiles_x, y1: self.tiles_y }
    }
}

/// A half-open rectangle of tiles `[x0, x1) x [y0, y1)`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct TileRect {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

impl TileRect {
    pub fn is_empty(&self) -> bool {
        self.x0 >= self.x1 || self.y0 >= self.y1
    }

    pub fn count(&self) -> u32 {
        if self.is_empty() { 0 } else { (self.x1 - self.x0) * (self.y1 - self.y0) }
    }

    pub fn intersect(&self, o: &TileRect) -> TileRect {
        let r = TileRect {
            x0: self.x0.max(o.x0),
            y0: self.y0.max(o.y0),
            x1: self.x1.min(o.x1),
            y1: self.y1.min(o.y1),
        };
        if r.is_empty() { TileRect::default() } else { r }
    }

    pub fn contains(&self, tx: u32, ty: u32) -> bool {
        tx >= self.x0 && tx < self.x1 && ty >= self.y0 && ty < self.y1
    }
}
