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

impl<F: Copy + Default> Image<F> {
    /// Every sample of a pixel that `covered` (one channel, this size) marks 0 set to zero: what
    /// the losses and metrics see of an undistorted photo's border, which has no source.
    pub fn zero_uncovered(mut self, covered: &Image<u8>) -> Self {
        let ch = self.channels.max(1) as usize;
        for (i, v) in self.data.iter_mut().enumerate() {
            if covered.data.get(i / ch).is_some_and(|&c| c == 0) {
                *v = F::default();
            }
        }
        self
    }

    /// The columns `x0..x1` (clamped to the image) as an image of their own.
    pub fn columns(&self, x0: u32, x1: u32) -> Self {
        let (x0, x1) = (x0.min(self.width), x1.min(self.width).max(x0.min(self.width)));
        let ch = self.channels as usize;
        let row = self.width as usize * ch;
        let data = self
            .data
            .chunks(row.max(1))
            .flat_map(|r| &r[x0 as usize * ch..x1 as usize * ch])
            .copied()
            .collect();
        Image { width: x1 - x0, height: self.height, channels: self.channels, data }
    }

    /// Resampled to `w x h` by nearest sample (labels stay labels); a copy at the same size.
    pub fn resized_nearest(&self, w: u32, h: u32) -> Self {
        if (self.width, self.height) == (w, h) {
            return self.clone();
        }
        let mut out = Image::<F>::new(w, h, self.channels);
        let ch = self.channels as usize;
        for y in 0..h {
            let sy = ((f64::from(y) + 0.5) * f64::from(self.height) / f64::from(h)) as u32;
            for x in 0..w {
                let sx = ((f64::from(x) + 0.5) * f64::from(self.width) / f64::from(w)) as u32;
                let src = (sy.min(self.height - 1) as usize * self.width as usize
                    + sx.min(self.width - 1) as usize)
                    * ch;
                let dst = (y as usize * w as usize + x as usize) * ch;
                out.data[dst..dst + ch].copy_from_slice(&self.data[src..src + ch]);
            }
        }
        out
    }
}

impl Image<f32> {
    /// Resampled to `w x h` bilinearly (pixel centres aligned, edges clamped): for enlarging.
    pub fn resized_bilinear(&self, w: u32, h: u32) -> Self {
        let mut out = Image::<f32>::new(w, h, self.channels);
        let ch = self.channels as usize;
        let at = |x: i64, y: i64, c: usize| {
            let x = x.clamp(0, i64::from(self.width) - 1) as usize;
            let y = y.clamp(0, i64::from(self.height) - 1) as usize;
            self.data[(y * self.width as usize + x) * ch + c]
        };
        for y in 0..h {
            let fy = (f64::from(y) + 0.5) * f64::from(self.height) / f64::from(h) - 0.5;
            let (y0, ty) = (fy.floor() as i64, (fy - fy.floor()) as f32);
            for x in 0..w {
                let fx = (f64::from(x) + 0.5) * f64::from(self.width) / f64::from(w) - 0.5;
                let (x0, tx) = (fx.floor() as i64, (fx - fx.floor()) as f32);
                let o = (y as usize * w as usize + x as usize) * ch;
                for c in 0..ch {
                    let top = at(x0, y0, c) * (1.0 - tx) + at(x0 + 1, y0, c) * tx;
                    let bottom = at(x0, y0 + 1, c) * (1.0 - tx) + at(x0 + 1, y0 + 1, c) * tx;
                    out.data[o + c] = top * (1.0 - ty) + bottom * ty;
                }
            }
        }
        out
    }
}

impl Image<u8> {
    /// The samples as [0, 1] (k / 255).
    pub fn to_f32(&self) -> Image<f32> {
        Image::<f32>::from_u8(self.width, self.height, self.channels, &self.data)
    }

    /// A one-channel mask with its 4-connected pieces of non-zero pixels smaller than
    /// `fraction` of the largest piece's pixel count set to zero.
    pub fn without_small_pieces(&self, fraction: f64) -> Self {
        debug_assert_eq!(self.channels, 1, "a mask has one channel");
        let (w, h) = (self.width as usize, self.height as usize);
        let mut piece = vec![usize::MAX; w * h];
        let mut sizes: Vec<usize> = Vec::new();
        let mut stack = Vec::new();
        for start in 0..w * h {
            if self.data[start] == 0 || piece[start] != usize::MAX {
                continue;
            }
            let id = sizes.len();
            piece[start] = id;
            stack.push(start);
            let mut size = 0;
            while let Some(p) = stack.pop() {
                size += 1;
                let (x, y) = (p % w, p / w);
                let neighbours = [
                    (x > 0).then(|| p - 1),
                    (x + 1 < w).then(|| p + 1),
                    (y > 0).then(|| p - w),
                    (y + 1 < h).then(|| p + w),
                ];
                for q in neighbours.into_iter().flatten() {
                    if self.data[q] != 0 && piece[q] == usize::MAX {
                        piece[q] = id;
                        stack.push(q);
                    }
                }
            }
            sizes.push(size);
        }
        let least = fraction * sizes.iter().copied().max().unwrap_or(0) as f64;
        let mut out = self.clone();
        for (v, &id) in out.data.iter_mut().zip(&piece) {
            if id != usize::MAX && (sizes[id] as f64) < least {
                *v = 0;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::Image;

    /// Rows of a mask drawn with '#' for set pixels.
    fn mask(rows: &[&str]) -> Image<u8> {
        let data = rows.iter().flat_map(|r| r.bytes().map(|b| u8::from(b == b'#'))).collect();
        Image { width: rows[0].len() as u32, height: rows.len() as u32, channels: 1, data }
    }

    #[test]
    fn small_pieces_go_and_pieces_near_the_largest_stay() {
        // A pane (12 pixels), a pane of the same size beyond a mullion, a sliver (2 pixels) and
        // a diagonal neighbour of the panes, which 4-connectivity keeps apart (1 pixel).
        let m = mask(&[
            "####.####..#", //
            "####.####..#",
            "####.####...",
            "....#.......",
        ]);
        let kept = m.without_small_pieces(0.25);
        let expected = mask(&[
            "####.####...", //
            "####.####...",
            "####.####...",
            "............",
        ]);
        assert_eq!(kept, expected);
        // Nothing goes at fraction 0, and an empty mask stays empty.
        assert_eq!(m.without_small_pieces(0.0), m);
        let empty = mask(&["...."]);
        assert_eq!(empty.without_small_pieces(0.5), empty);
    }
}
