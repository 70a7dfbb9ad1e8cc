//! Speed against error across runs: the PSNR each run reached after so many seconds of training
//! (its `metrics.json` `psnr_over_time`), as a Markdown table and a PNG line plot with a title,
//! axis names and a legend (plotters; text in egui's bundled font, so that no system font is
//! looked up).
use anyhow::{Result, anyhow};
use plotters::prelude::*;
use trgs_core::Image;
use trgs_core::io::RunMetrics;

/// One run's curve: (training seconds, test PSNR) in order.
#[derive(Clone, Debug)]
pub struct Curve {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

/// Line colours, in run order (the table names them); `report` takes at most this many runs,
/// so that no two curves share a colour.
pub const COLOURS: [([u8; 3], &str); 8] = [
    ([217, 51, 38], "red"),
    ([38, 89, 217], "blue"),
    ([26, 153, 51], "green"),
    ([153, 77, 179], "purple"),
    ([242, 153, 26], "orange"),
    ([26, 179, 191], "teal"),
    ([128, 128, 128], "grey"),
    ([140, 89, 38], "brown"),
];

/// The font family every label is drawn in.
const FONT: &str = "sans-serif";

/// The curve of a run's evaluations (its metrics.json's `psnr_over_time`); an exact render's
/// infinite PSNR has no place on an axis and is left out.
pub fn curve_of(name: &str, metrics: &RunMetrics) -> Curve {
    let finite = metrics.psnr_over_time.iter().filter(|e| e.psnr.is_finite());
    let points = finite.map(|e| (e.seconds, e.psnr)).collect();
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

/// Make the bundled font the family the plot's labels use (once per process).
fn register_font() -> Result<()> {
    static REGISTERED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(
            FONT,
            plotters::style::FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        )
        .is_ok()
    });
    if ok { Ok(()) } else { Err(anyhow!("the bundled font could not be loaded")) }
}

/// A `width x height` plot titled `title`: test PSNR (dB) against training time (s), each curve
/// a line with circle markers in its colour of [`COLOURS`], named in the legend.
pub fn plot(curves: &[Curve], title: &str, width: u32, height: u32) -> Result<Image<u8>> {
    register_font()?;
    let mut rgb = vec![255u8; (width * height * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (width, height)).into_drawing_area();
        draw(&root, curves, title).map_err(|e| anyhow!("drawing the plot: {e}"))?;
        root.present().map_err(|e| anyhow!("drawing the plot: {e}"))?;
    }
    let mut image = Image::<u8>::new(width, height, 3);
    image.data = rgb;
    Ok(image)
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    curves: &[Curve],
    title: &str,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let all: Vec<(f64, f64)> = curves.iter().flat_map(|c| c.points.iter().copied()).collect();
    let t_max = all.iter().map(|p| p.0).fold(1.0, f64::max);
    let p_min = all.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    let p_max = all.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
    let (p_lo, p_hi) =
        if p_min.is_finite() { ((p_min - 1.0).floor(), (p_max + 1.0).ceil()) } else { (0.0, 1.0) };
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FONT, 22))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(56)
        .build_cartesian_2d(0.0..t_max * 1.05, p_lo..p_hi)?;
    chart
        .configure_mesh()
        .x_desc("training time (s)")
        .y_desc("test PSNR (dB)")
        .axis_desc_style((FONT, 16))
        .label_style((FONT, 13))
        .x_label_formatter(&|t| format!("{t:.0}"))
        .y_label_formatter(&|p| format!("{p:.0}"))
        .light_line_style(RGBColor(238, 238, 238))
        .draw()?;
    for (k, c) in curves.iter().enumerate() {
        let [r, g, b] = COLOURS[k % COLOURS.len()].0;
        let colour = RGBColor(r, g, b);
        chart
            .draw_series(LineSeries::new(c.points.iter().copied(), colour.stroke_width(2)))?
            .label(c.name.as_str())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
        chart.draw_series(c.points.iter().map(|&p| Circle::new(p, 4, colour.filled())))?;
    }
    if !curves.is_empty() {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font((FONT, 14))
            .draw()?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn curves() -> Vec<Curve> {
        let m = RunMetrics::parse(
            r#"{"psnr_over_time": [
                {"step": 100, "seconds": 30.0, "psnr": 22.0, "ssim": 0.8},
                {"step": 200, "seconds": 70.0, "psnr": 25.5, "ssim": 0.9}]}"#,
        )
        .expect("metrics");
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
    fn plot_draws_each_curve_in_its_colour_with_text() {
        let im = plot(&curves(), "two runs", 480, 320).expect("plot");
        let count = |c: [u8; 3]| im.data.chunks_exact(3).filter(|px| **px == c).count();
        assert!(count(COLOURS[0].0) > 50 && count(COLOURS[1].0) > 50);
        // Text (title, axis names, labels, legend) is drawn in grey levels: dark pixels that
        // are neither a curve nor the white background.
        let dark = im.data.chunks_exact(3).filter(|px| px.iter().all(|&v| v < 100)).count();
        assert!(dark > 500, "{dark} dark pixels: no text?");
        // No curves: axes and title only.
        let empty = plot(&[], "nothing", 200, 120).expect("plot");
        assert!(empty.data.chunks_exact(3).all(|px| px[0] == px[1] && px[1] == px[2]));
    }
}
