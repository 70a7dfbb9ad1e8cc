//! Speed against error across runs: the PSNR each run reached after so many seconds of training
//! (its `metrics.json` `psnr_over_time`), as a Markdown table and a PNG line plot. The plot's
//! tick labels (seconds, dB) are drawn with a built-in 3x5 pixel font, so that no font
//! dependency is needed; the table beside it carries the exact numbers and the colour key.
use trgs_core::Image;

/// One run's curve: (training seconds, test PSNR) in order.
#[derive(Clone, Debug)]
pub struct Curve {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

/// Line colours, in run order (the table names them); `report` takes at most this many runs,
/// so that no two curves share a colour.
pub const COLOURS: [([f32; 3], &str); 8] = [
    ([0.85, 0.2, 0.15], "red"),
    ([0.15, 0.35, 0.85], "blue"),
    ([0.1, 0.6, 0.2], "green"),
    ([0.6, 0.3, 0.7], "purple"),
    ([0.95, 0.6, 0.1], "orange"),
    ([0.1, 0.7, 0.75], "teal"),
    ([0.5, 0.5, 0.5], "grey"),
    ([0.55, 0.35, 0.15], "brown"),
];

/// Read `psnr_over_time` of a run's metrics.json text.
pub fn curve_of(name: &str, metrics: &serde_json::Value) -> Curve {
    let points = metrics["psnr_over_time"]
        .as_array()
        .map(|rows| {
            rows.iter()
                .filter_map(|r| Some((r["seconds"].as_f64()?, r["psnr"].as_f64()?)))
                .collect()
        })
        .unwrap_or_default();
    Curve { name: name.to_string(), points }
}

/// Markdown table: one row per run, one column per evaluation (its PSNR and training time).
pub fn markdown_table(curves: &[Curve]) -> String {
    let mut s = String::from("| run | colour |");
    let n = curves.iter().map(|c| c.points.len()).max().unwrap_or(0);
    for i in 0..n {
        s.push_str(&format!(" eval {} |", i + 1));
    }
    s.push_str("\n|---|---|");
    s.push_str(&"---:|".repeat(n));
    s.push('\n');
    for (k, c) in curves.iter().enumerate() {
        // A `|` in a name would end its cell.
        let name = c.name.replace('|', "\\|");
        s.push_str(&format!("| {name} | {} |", COLOURS[k % COLOURS.len()].1));
        for &(t, p) in &c.points {
            s.push_str(&format!(" {p:.2} dB at {t:.0} s |"));
        }
        s.push('\n');
    }
    s
}

/// A `width x height` plot: PSNR (y) against seconds (x), both axes from the data's range, with a
/// labelled grid (a round number of seconds that gives at most 8 intervals, and 1, 2, 5 or 10 dB
/// or more that gives at most 10),
/// each curve as a polyline with square markers.
pub fn plot(curves: &[Curve], width: u32, height: u32) -> Image<f32> {
    let mut im = Image::<f32>::new(width, height, 3);
    im.data.iter_mut().for_each(|v| *v = 1.0);
    let all: Vec<(f64, f64)> = curves.iter().flat_map(|c| c.points.iter().copied()).collect();
    if all.is_empty() || width < 16 || height < 16 {
        return im;
    }
    let t_max = all.iter().map(|p| p.0).fold(1.0, f64::max);
    let p_min = all.iter().map(|p| p.1).fold(f64::INFINITY, f64::min).floor();
    let p_max = all.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max).ceil().max(p_min + 1.0);
    let t_step = [10.0, 30.0, 60.0, 120.0, 300.0, 600.0, 1200.0, 1800.0, 3600.0]
        .into_iter()
        .find(|&s| t_max / s <= 8.0)
        .unwrap_or((t_max / 8.0 / 3600.0).ceil() * 3600.0);
    let p_step = [1.0, 2.0, 5.0, 10.0].into_iter().find(|&s| (p_max - p_min) / s <= 10.0);
    let p_step = p_step.unwrap_or(((p_max - p_min) / 100.0).ceil() * 10.0);
    // Room for the labels left of and below the axes; the plot area keeps 8 pixels at the top
    // and on the right.
    let label = |p: f64| format!("{p:.0}dB");
    let widest = [p_min, p_max].iter().map(|&p| text_width(&label(p))).fold(0.0, f64::max);
    let (left, bottom, margin) = (widest + 12.0, GLYPH_H + 12.0, 8.0);
    let w = (f64::from(width) - left - margin).max(1.0);
    let h = (f64::from(height) - bottom - margin).max(1.0);
    let to_px =
        |t: f64, p: f64| (left + w * t / t_max, margin + h * (1.0 - (p - p_min) / (p_max - p_min)));
    let (grey, black) = ([0.85, 0.85, 0.85], [0.0, 0.0, 0.0]);
    let mut t = 0.0;
    while t <= t_max {
        let (x, y) = to_px(t, p_min);
        line(&mut im, (x, margin), (x, y), grey);
        let text = format!("{t:.0}s");
        // Centred under its grid line, but kept inside the image at the right edge.
        let tx = (x - 0.5 * text_width(&text)).min(f64::from(width) - text_width(&text) - 1.0);
        draw_text(&mut im, tx, y + 6.0, &text, black);
        t += t_step;
    }
    let mut p = p_min;
    while p <= p_max {
        let (x, y) = to_px(0.0, p);
        line(&mut im, (x, y), (left + w, y), grey);
        let text = label(p);
        let ty = (y - 0.5 * GLYPH_H).max(1.0);
        draw_text(&mut im, x - 6.0 - text_width(&text), ty, &text, black);
        p += p_step;
    }
    line(&mut im, (left, margin + h), (left + w, margin + h), black);
    line(&mut im, (left, margin), (left, margin + h), black);
    for (k, c) in curves.iter().enumerate() {
        let colour = COLOURS[k % COLOURS.len()].0;
        let px: Vec<(f64, f64)> = c.points.iter().map(|&(t, p)| to_px(t, p)).collect();
        for pair in px.windows(2) {
            line(&mut im, pair[0], pair[1], colour);
        }
        for &(x, y) in &px {
            for dy in -2..=2 {
                for dx in -2..=2 {
                    set(&mut im, x + f64::from(dx), y + f64::from(dy), colour);
                }
            }
        }
    }
    im
}

/// Pixels per font cell side: the 3x5 glyphs are drawn at 6x10 pixels.
const GLYPH_SCALE: f64 = 2.0;
const GLYPH_H: f64 = 5.0 * GLYPH_SCALE;
const GLYPH_ADVANCE: f64 = 4.0 * GLYPH_SCALE;

/// The 3x5 glyph of `c` (rows top to bottom, 3 bits each, the high bit on the left), for the
/// characters the tick labels use; anything else is a blank.
fn glyph(c: char) -> [u8; 5] {
    match c {
        '0' => [0b111, 0b101, 0b101, 0b101, 0b111],
        '1' => [0b010, 0b110, 0b010, 0b010, 0b111],
        '2' => [0b111, 0b001, 0b111, 0b100, 0b111],
        '3' => [0b111, 0b001, 0b111, 0b001, 0b111],
        '4' => [0b101, 0b101, 0b111, 0b001, 0b001],
        '5' => [0b111, 0b100, 0b111, 0b001, 0b111],
        '6' => [0b111, 0b100, 0b111, 0b101, 0b111],
        '7' => [0b111, 0b001, 0b001, 0b001, 0b001],
        '8' => [0b111, 0b101, 0b111, 0b101, 0b111],
        '9' => [0b111, 0b101, 0b111, 0b001, 0b111],
        '-' => [0b000, 0b000, 0b111, 0b000, 0b000],
        's' => [0b011, 0b100, 0b010, 0b001, 0b110],
        'd' => [0b001, 0b001, 0b111, 0b101, 0b111],
        'B' => [0b110, 0b101, 0b110, 0b101, 0b110],
        _ => [0; 5],
    }
}

fn text_width(text: &str) -> f64 {
    GLYPH_ADVANCE * text.chars().count() as f64 - GLYPH_SCALE
}

/// Draw `text` with its top-left corner at (x, y).
fn draw_text(im: &mut Image<f32>, x: f64, y: f64, text: &str, c: [f32; 3]) {
    for (i, ch) in text.chars().enumerate() {
        let x0 = x + GLYPH_ADVANCE * i as f64;
        for (row, bits) in glyph(ch).iter().enumerate() {
            for col in 0..3 {
                if bits >> (2 - col) & 1 == 0 {
                    continue;
                }
                for sy in 0..GLYPH_SCALE as i32 {
                    for sx in 0..GLYPH_SCALE as i32 {
                        let px = x0 + GLYPH_SCALE * f64::from(col) + f64::from(sx);
                        let py = y + GLYPH_SCALE * row as f64 + f64::from(sy);
                        set(im, px, py, c);
                    }
                }
            }
        }
    }
}

fn set(im: &mut Image<f32>, x: f64, y: f64, c: [f32; 3]) {
    let (xi, yi) = (x.round(), y.round());
    if xi < 0.0 || yi < 0.0 || xi >= f64::from(im.width) || yi >= f64::from(im.height) {
        return;
    }
    for (ch, v) in c.iter().enumerate() {
        im.set(xi as u32, yi as u32, ch as u32, *v);
    }
}

/// A two-pixel-wide line, sampled every half pixel.
fn line(im: &mut Image<f32>, a: (f64, f64), b: (f64, f64), c: [f32; 3]) {
    let steps = (2.0 * (b.0 - a.0).abs().max((b.1 - a.1).abs())).ceil().max(1.0) as usize;
    for i in 0..=steps {
        let s = i as f64 / steps as f64;
        let (x, y) = (a.0 + s * (b.0 - a.0), a.1 + s * (b.1 - a.1));
        set(im, x, y, c);
        set(im, x + 0.5, y + 0.5, c);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn curves() -> Vec<Curve> {
        let m = serde_json::json!({"psnr_over_time": [
            {"step": 100, "seconds": 30.0, "psnr": 22.0},
            {"step": 200, "seconds": 70.0, "psnr": 25.5}]});
        let mut b = curve_of("b", &m);
        b.points.iter_mut().for_each(|p| p.1 -= 1.0);
        vec![curve_of("a", &m), b]
    }

    #[test]
    fn table_lists_every_evaluation() {
        let t = markdown_table(&curves());
        assert!(t.contains("| a | red | 22.00 dB at 30 s | 25.50 dB at 70 s |"), "{t}");
        assert!(t.contains("| b | blue | 21.00 dB at 30 s | 24.50 dB at 70 s |"), "{t}");
    }

    #[test]
    fn plot_draws_each_curve_in_its_colour() {
        let im = plot(&curves(), 200, 120);
        let count = |c: [f32; 3]| {
            im.data.chunks_exact(3).filter(|px| px.iter().zip(&c).all(|(a, b)| a == b)).count()
        };
        assert!(count(COLOURS[0].0) > 50 && count(COLOURS[1].0) > 50);
        // The last point of curve a (the highest PSNR) is at the top right.
        let (x, y) = (200 - 8 - 1, 8);
        assert_eq!(im.get(x, y, 0), COLOURS[0].0[0]);
        assert!(plot(&[], 50, 50).data.iter().all(|&v| v == 1.0));
    }

    /// The tick labels are drawn left of the y axis and below the x axis, and nowhere they
    /// would be clipped.
    #[test]
    fn plot_labels_both_axes() {
        let (w, h) = (200u32, 120u32);
        let im = plot(&curves(), w, h);
        let black = |x: u32, y: u32| (0..3).all(|c| im.get(x, y, c) == 0.0);
        // The y axis is the leftmost all-black column of the plot area.
        let axis_x = (0..w).find(|&x| (20..h - 30).all(|y| black(x, y))).expect("y axis");
        let left_ink = (0..axis_x - 2).flat_map(|x| (0..h).map(move |y| (x, y)));
        assert!(left_ink.filter(|&(x, y)| black(x, y)).count() > 20, "no y labels");
        // The x axis: the lowest row that is mostly black (markers may cover parts of it).
        let ink = |y: u32| (axis_x..w).filter(|&x| black(x, y)).count();
        let axis_y = (0..h).rev().find(|&y| ink(y) > 8 * (w - axis_x) as usize / 10);
        let axis_y = axis_y.expect("x axis");
        let below = (axis_y + 3..h).flat_map(|y| (0..w).map(move |x| (x, y)));
        assert!(below.filter(|&(x, y)| black(x, y)).count() > 20, "no x labels");
        assert_eq!(text_width("22dB"), 30.0);
        assert!(glyph('?').iter().all(|&r| r == 0));
    }
}
