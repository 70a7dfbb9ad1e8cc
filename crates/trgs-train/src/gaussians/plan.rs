//! The rebuild of the Gaussian set as a plan on the CPU (the deciding stages' twins make one, and
//! so do sets too large for those stages' bindings), which the GPU carries out (`gather_rows`),
//! and what such a plan is decided from.
use trgs_core::scene::{Attribute, Gaussians, PerAttribute, Population, attribute_widths};

/// Parameters and Adam moments of a set of Gaussians, edited together.
#[derive(Clone, Debug)]
pub struct TrainState {
    pub gaussians: Gaussians<f32>,
    /// First and second moments of every attribute, flat.
    pub m: PerAttribute<Vec<f32>>,
    pub v: PerAttribute<Vec<f32>>,
}

/// The state made of `sources` (an index into `state` each, in order); moments are copied for
/// `keep_moments` entries and zero for the others.
pub(crate) fn gather(state: &TrainState, sources: &[(usize, bool)]) -> TrainState {
    let g = &state.gaussians;
    let out = g.gather(sources.iter().map(|&(i, _)| i));
    let w = attribute_widths(g.sh_coeffs());
    let moments = |src: &PerAttribute<Vec<f32>>| -> PerAttribute<Vec<f32>> {
        PerAttribute::from_fn(|a| {
            let (w, src) = (w[a], &src[a]);
            let mut v = Vec::with_capacity(sources.len() * w);
            for &(i, keep) in sources {
                if keep {
                    v.extend_from_slice(&src[i * w..(i + 1) * w]);
                } else {
                    v.extend(std::iter::repeat_n(0.0, w));
                }
            }
            v
        })
    };
    TrainState { m: moments(&state.m), v: moments(&state.v), gaussians: out }
}

pub(crate) fn sigmoid(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}

/// The attributes densification decides from (classic and MCMC), read back on their own when
/// it decides on the CPU: 15 words per Gaussian, where the parameters and their Adam moments
/// are about 180 at SH degree 3.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Geometry {
    pub means: Vec<[f32; 3]>,
    pub rotations: Vec<[f32; 4]>,
    pub log_scales: Vec<[f32; 3]>,
    pub opacity_logits: Vec<f32>,
    pub populations: Vec<Population>,
}

impl Geometry {
    pub fn of(g: &Gaussians<f32>) -> Self {
        Self {
            means: g.means.clone(),
            rotations: g.rotations.clone(),
            log_scales: g.log_scales.clone(),
            opacity_logits: g.opacity_logits.clone(),
            populations: g.populations.clone(),
        }
    }

    pub fn len(&self) -> usize {
        self.opacity_logits.len()
    }

    pub fn is_empty(&self) -> bool {
        self.opacity_logits.is_empty()
    }
}

/// A rebuild of the Gaussian set: output row j is a copy of input row `sources[j].0`, with its
/// Adam moments when `sources[j].1` and zero moments otherwise; the attributes given here are
/// the values of the rows with zero moments, the rows the plan makes anew (e.g. the split
/// children's means and scales; a kept row's given value is its source's). The twins of the
/// deciding stages make one from a [`Geometry`]; it runs on the GPU (`gather_rows`), or on the
/// CPU with [`RowPlan::apply`], its twin.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RowPlan {
    pub sources: Vec<(usize, bool)>,
    pub means: Option<Vec<[f32; 3]>>,
    pub log_scales: Option<Vec<[f32; 3]>>,
    pub opacity_logits: Option<Vec<f32>>,
}

impl RowPlan {
    /// The state this plan makes of `state`, on the CPU. The attributes the plan gives are the
    /// values of the rows it makes anew (those whose moments restart); a kept row is its source
    /// as it is in `state`, so that a plan applied a step after it was decided keeps that
    /// step's update of the rows it does not change.
    pub fn apply(&self, state: &TrainState) -> TrainState {
        fn anew<T: Copy>(rows: &mut [T], given: Option<&Vec<T>>, sources: &[(usize, bool)]) {
            let Some(given) = given else { return };
            for ((row, &value), &(_, keep)) in rows.iter_mut().zip(given).zip(sources) {
                if !keep {
                    *row = value;
                }
            }
        }
        let mut out = gather(state, &self.sources);
        let g = &mut out.gaussians;
        anew(&mut g.means, self.means.as_ref(), &self.sources);
        anew(&mut g.log_scales, self.log_scales.as_ref(), &self.sources);
        anew(&mut g.opacity_logits, self.opacity_logits.as_ref(), &self.sources);
        out
    }

    /// The attributes the plan gives (whole, read for the rows made anew), as GPU words.
    pub fn given_words(&self) -> Vec<(Attribute, Vec<u32>)> {
        let words = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<u32>>();
        let mut out = Vec::new();
        if let Some(v) = &self.means {
            out.push((Attribute::Means, words(v.as_flattened())));
        }
        if let Some(v) = &self.log_scales {
            out.push((Attribute::LogScales, words(v.as_flattened())));
        }
        if let Some(v) = &self.opacity_logits {
            out.push((Attribute::OpacityLogits, words(v)));
        }
        out
    }

    /// Whether every attribute the plan gives is finite (an upload's check; the gathered rows
    /// come from a checked set).
    pub fn given_are_finite(&self) -> bool {
        self.given_words().iter().all(|(_, w)| w.iter().all(|&b| f32::from_bits(b).is_finite()))
    }
}
