//! Speed against error across runs: the PSNR each run reached after so many seconds of training
//! (its `metrics.json` `psnr_over_time`), as a Markdown table and a PNG line plot. The plot has no
//! text (no font dependency): the table beside it carries the numbers and the colour key.
use trgs_core::Image;

/// One run's curve: (training seconds, test PSNR) in order.
#[derive(Clone, Debug)]
pub struct Curve {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

/// Line colours, in run order (the table names them).
pub const COLOURS: [([f32; 3], &str); 4] = [
    ([0.85, 0.2, 0.15], "red"),
    ([0.15, 0.35, 0.85], "blue"),
    ([0.1, 0.6, 0.2], "green"),
    ([0.6, 0.3, 0.7], "purple"),
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

/// Markdown table: one row per evaluation time of the first curve's steps, one column per run.
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
        s.push_str(&format!("| {} | {} |", c.name, COLOURS[k % COLOURS.len()].1));
        for &(t, p) in &c.points {
            s.push_str(&format!(" {p:.2} dB at {t:.0} s |"));
        }
        s.push('\n');
    }
    s
}

/// A `width x height` plot: PSNR (y) against seconds (x), both axes from the data's range with a
/// grid every 60 s and every 1 dB, each curve as a polyline with square markers.
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
    let margin = 8.0;
    let (w, h) = (f64::from(width) - 2.0 * margin, f64::from(height) - 2.0 * margin);
    let to_px = |t: f64, p: f64| {
        (margin + w * t / t_max, margin + h * (1.0 - (p - p_min) / (p_max - p_min)))
    };
    let grey = [0.85, 0.85, 0.85];
    let mut t = 0.0;
    while t <= t_max {
        let (x, _) = to_px(t, p_min);
        line(&mut im, (x, margin), (x, margin + h), grey);
        t += 60.0;
    }
    let mut p = p_min;
    while p <= p_max {
        let (_, y) = to_px(0.0, p);
        line(&mut im, (margin, y), (margin + w, y), grey);
        p += 1.0;
    }
    let black = [0.0, 0.0, 0.0];
    line(&mut im, (margin, margin + h), (margin + w, margin + h), black);
    line(&mut im, (margin, margin), (margin, margin + h), black);
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
}
