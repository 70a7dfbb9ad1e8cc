//! Which values of a glass mask are labels, and soft edges snapped to them (the rule is stated in
//! [`super::masks`]).
use crate::image::Image;

/// How many interior pixels (all four neighbours share the value) make a value a label: a 6x6 px
/// region has 16. An antialiased or blurred edge is a band one or two pixels wide for each grey
/// value, which has no interior pixel however long the edge, and the specks JPEG noise leaves are
/// smaller than this; a pane smaller than 6x6 px in the photo's own mask gives plane fitting
/// nothing to work with.
pub(crate) const MIN_INTERIOR_PIXELS: usize = 16;

/// Move every pixel of a soft-edge value (neither 0 nor a value with [`MIN_INTERIOR_PIXELS`]
/// interior pixels, and below the largest label) to the nearest label, the lower on a tie; the
/// number of pixels moved.
pub(crate) fn snap_soft_edges(mask: &mut Image<u8>) -> usize {
    let interior = interior_counts(mask);
    let is_label = |v: usize| v == 0 || interior[v] >= MIN_INTERIOR_PIXELS;
    let labels: Vec<usize> = (0..256).filter(|&v| is_label(v)).collect();
    let Some(&largest) = labels.last().filter(|&&l| l > 0) else {
        // No value but 0 fills a region: nothing tells a label from an edge.
        return 0;
    };
    let mut target: [u8; 256] = std::array::from_fn(|v| v as u8);
    for v in (1..largest).filter(|&v| !is_label(v)) {
        // `labels` is ascending, so the first of two equally near labels is the lower.
        let nearest = labels.iter().copied().min_by_key(|&l| l.abs_diff(v)).unwrap_or(0);
        target[v] = nearest as u8;
    }
    let mut moved = 0;
    for p in &mut mask.data {
        let t = target[usize::from(*p)];
        moved += usize::from(t != *p);
        *p = t;
    }
    moved
}

/// For each value, how many of its pixels have four neighbours of the same value (a neighbour
/// outside the image counts as the same, so that a pane cut off by the border fills a region).
fn interior_counts(mask: &Image<u8>) -> [usize; 256] {
    let (w, h) = (mask.width as usize, mask.height as usize);
    let at = |x: usize, y: usize| mask.data[y * w + x];
    let mut counts = [0usize; 256];
    for y in 0..h {
        for x in 0..w {
            let v = at(x, y);
            let same = (x == 0 || at(x - 1, y) == v)
                && (x + 1 == w || at(x + 1, y) == v)
                && (y == 0 || at(x, y - 1) == v)
                && (y + 1 == h || at(x, y + 1) == v);
            counts[usize::from(v)] += usize::from(same);
        }
    }
    counts
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(width: u32, height: u32, data: Vec<u8>) -> Image<u8> {
        Image { width, height, channels: 1, data }
    }

    #[test]
    fn interior_pixels_fill_regions_and_the_border_counts_as_inside() {
        // A 3x3 block of 4 in the corner of a 5x4 mask of 0, and a lone 9.
        let mut data = vec![0u8; 20];
        for y in 0..3 {
            for x in 0..3 {
                data[y * 5 + x] = 4;
            }
        }
        data[19] = 9;
        let counts = interior_counts(&image(5, 4, data));
        // The block's top-left 2x2 pixels touch only the border and the block.
        assert_eq!(counts[4], 4);
        assert_eq!(counts[9], 0);
        assert_eq!(counts[0], 2, "(4, 0) and (4, 1): the others touch the block or the 9");
    }

    #[test]
    fn soft_values_go_to_the_nearest_label_and_values_above_every_label_stay() {
        // Left half 10, right half 200 (both fill regions), a column of 100 between them
        // (nearer 10), one pixel of 110 (nearer 200), one of 105 (a tie: the lower) and one of
        // 230, above every label: a small region of its own.
        let (w, h) = (16usize, 8usize);
        let mut data: Vec<u8> = (0..w * h).map(|i| if i % w < 8 { 10 } else { 200 }).collect();
        (0..h).for_each(|y| data[y * w + 8] = 100);
        data[w + 9] = 110;
        data[2 * w + 9] = 105;
        data[3 * w + 12] = 230;
        let mut mask = image(w as u32, h as u32, data);
        assert_eq!(snap_soft_edges(&mut mask), h + 2);
        assert!((0..h).all(|y| mask.data[y * w + 8] == 10));
        assert_eq!(mask.data[w + 9], 200);
        assert_eq!(mask.data[2 * w + 9], 10);
        assert_eq!(mask.data[3 * w + 12], 230);
    }

    #[test]
    fn a_mask_where_only_zero_fills_a_region_keeps_its_values() {
        let mut mask =
            image(8, 8, (0..64).map(|i| if i % 9 == 0 { (i % 5) as u8 } else { 0 }).collect());
        let before = mask.clone();
        assert_eq!(snap_soft_edges(&mut mask), 0);
        assert_eq!(mask, before);
    }
}
