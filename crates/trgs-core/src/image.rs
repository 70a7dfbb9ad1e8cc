//! A plain interleaved image buffer, the currency of layers, metrics and file formats.

/// Interleaved `height x width x channels` samples, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Image<F = f32> {
    pub width: u32,
    pub height: u32,
    pub channels: u32,
    pub data: Vec<F>,
}

impl<F: Copy + Default> Image<F> {
    /// An image filled with `F::default()` (zero for numbers).
    pub fn new(width: u32, height: u32, channels: u32) -> Self {
        Self::filled(width, height, channels, F::default())
    }

    pub fn filled(width: u32, height: u32, channels: u32, value: F) -> Self {
        let n = width as usize * height as usize * channels as usize;
        Self { width, height, channels, data: vec![value; n] }
    }

    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Index of channel `c` of pixel `(x, y)` in `data`.
    #[inline]
    pub fn index(&self, x: u32, y: u32, c: u32) -> usize {
        (y as usize * self.width as usize + x as usize) * self.channels as usize + c as usize
    }

    #[inline]
    pub fn get(&self, x: u32, y: u32, c: u32) -> F {
        self.data[self.index(x, y, c)]
    }

    #[inline]
    pub fn set(&mut self, x: u32, y: u32, c: u32, v: F) {
        let i = self.index(x, y, c);
        self.data[i] = v;
    }

    /// The same image with every sample converted by `f`.
    pub fn map<G: Copy + Default>(&self, f: impl Fn(F) -> G) -> Image<G> {
        Image {
            width: self.width,
            height: self.height,
            channels: self.channels,
            data: self.data.iter().map(|&v| f(v)).collect(),
        }
    }
}

impl Image<f32> {
    /// 8-bit samples (sRGB-encoded as stored; no transfer function is applied) to [0, 1].
    pub fn from_u8(width: u32, height: u32, channels: u32, bytes: &[u8]) -> Self {
        Self {
            width,
            height,
            channels,
            data: bytes.iter().map(|&b| f32::from(b) / 255.0).collect(),
        }
    }

    /// Quantise [0, 1] samples to 8 bits with rounding; out-of-range values are clamped.
    pub fn to_u8(&self) -> Vec<u8> {
        self.data.iter().map(|&v| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8).collect()
    }

    /// [`Self::to_u8`] as an image.
    pub fn quantised(&self) -> Image<u8> {
        Image {
            width: self.width,
            height: self.height,
            channels: self.channels,
            data: self.to_u8(),
        }
    }
}

impl Image<u8> {
    /// The samples as [0, 1] (k / 255).
    pub fn to_f32(&self) -> Image<f32> {
        Image::<f32>::from_u8(self.width, self.height, self.channels, &self.data)
    }
}
