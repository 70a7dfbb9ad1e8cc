//! Argument types and parsers that several commands share.
use trgs_core::io::Split;
pub use trgs_train::run::parse_non_negative;

/// Which views of a scene folder a command works on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SplitArg {
    /// The test views (test_views.txt, or every 8th image)
    Test,
    /// The views training uses
    Train,
    /// Every view
    All,
}

impl From<SplitArg> for Split {
    fn from(s: SplitArg) -> Split {
        match s {
            SplitArg::Test => Split::Test,
            SplitArg::Train => Split::Train,
            SplitArg::All => Split::All,
        }
    }
}

/// A colour `R,G,B` with each component in [0, 1].
pub fn parse_colour(v: &str) -> Result<[f32; 3], String> {
    let parts: Vec<Option<f32>> = v
        .split(',')
        .map(|p| p.trim().parse().ok().filter(|x: &f32| (0.0..=1.0).contains(x)))
        .collect();
    match parts[..] {
        [Some(r), Some(g), Some(b)] => Ok([r, g, b]),
        _ => Err("expected three numbers in [0, 1], e.g. 1,1,1".into()),
    }
}

/// A share in [0, 1].
pub fn parse_share(v: &str) -> Result<f64, String> {
    v.parse::<f64>()
        .ok()
        .filter(|x| (0.0..=1.0).contains(x))
        .ok_or_else(|| "expected a number in [0, 1]".into())
}

/// A size `WxH` in points, each at least 1.
pub fn parse_window_size(v: &str) -> Result<[f32; 2], String> {
    let (w, h) = v.split_once('x').ok_or("expected WxH, e.g. 800x600")?;
    let size: [f32; 2] = [
        w.parse().map_err(|_| format!("width {w:?}: expected a number (WxH)"))?,
        h.parse().map_err(|_| format!("height {h:?}: expected a number (WxH)"))?,
    ];
    if !size.iter().all(|&d| d.is_finite() && d >= 1.0) {
        return Err("width and height must be at least 1".into());
    }
    Ok(size)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colours_and_sizes_are_checked() {
        assert_eq!(parse_colour("1, 0.5,0"), Ok([1.0, 0.5, 0.0]));
        for bad in ["1,x,0", "1,1", "2,0,0", "NaN,0,0"] {
            assert!(parse_colour(bad).is_err(), "{bad}");
        }
        assert_eq!(parse_window_size("800x600"), Ok([800.0, 600.0]));
        assert!(parse_window_size("big").is_err_and(|e| e.contains("WxH")));
        assert!(parse_window_size("0x600").is_err_and(|e| e.contains("at least 1")));
        assert_eq!(parse_non_negative("0.5"), Ok(0.5));
        assert!(parse_non_negative("-1").is_err() && parse_non_negative("inf").is_err());
        assert_eq!(parse_share("1"), Ok(1.0));
        assert!(parse_share("1.5").is_err() && parse_share("x").is_err());
    }
}
