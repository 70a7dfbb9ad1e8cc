//! The values a model file may hold, the same for every format trgs reads and writes (PLY and
//! glb): every value finite, a rotation whose squared length f32 can hold, and every log-encoded
//! value (the scales, the reflection intensity) small enough that its exp is finite in f32, as
//! the glb's linear scales and the renderer compute it. The logits (opacity, mask) need only be
//! finite: the sigmoid of any finite value is. Readers refuse other values as they read them,
//! naming the Gaussian and the field in the format's own terms; writers refuse them before they
//! write, so that whatever a trgs writer writes, every trgs reader reads.
use crate::scene::Gaussians;

const NOT_FINITE: &str = "is not finite";

/// A field of a Gaussian, for each format to name in its own terms.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Field {
    Mean(usize),
    Rotation(usize),
    LogScale(usize),
    OpacityLogit,
    /// SH coefficient `coeff` (trgs's order: l^2 + m + l) of colour channel `channel`.
    Sh {
        coeff: usize,
        channel: usize,
    },
    MaskLogit,
    LogReflection,
}

/// A value a model file cannot hold: where it is, what it is and why not.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Unusable {
    pub(crate) index: usize,
    pub(crate) field: Field,
    pub(crate) value: f32,
    why: &'static str,
}

impl Unusable {
    /// The problem, with `name` the format's name for the field: "Gaussian 17: scale_0 = 1e30 is
    /// a log-scale whose exp is not finite in f32".
    pub(crate) fn message(&self, name: &str) -> String {
        format!("Gaussian {}: {name} = {:?} {}", self.index, self.value, self.why)
    }
}

/// The first value of Gaussian `i` that a model file cannot hold.
pub(crate) fn check_gaussian(g: &Gaussians<f32>, i: usize) -> Result<(), Unusable> {
    let bad = |field, value, why| Err(Unusable { index: i, field, value, why });
    for (a, &v) in g.means[i].iter().enumerate() {
        if !v.is_finite() {
            return bad(Field::Mean(a), v, NOT_FINITE);
        }
    }
    let q = g.rotations[i];
    for (a, &v) in q.iter().enumerate() {
        if !v.is_finite() {
            return bad(Field::Rotation(a), v, NOT_FINITE);
        }
    }
    if !q.iter().map(|v| v * v).sum::<f32>().is_finite() {
        // Normalising it (the renderer, a glb's unit quaternion) would divide by infinity.
        let a = (0..4).max_by(|&x, &y| q[x].abs().total_cmp(&q[y].abs())).unwrap_or(0);
        return bad(Field::Rotation(a), q[a], "makes the rotation's squared length overflow f32");
    }
    for (a, &v) in g.log_scales[i].iter().enumerate() {
        if let Some(why) = log_problem(v, "is a log-scale whose exp is not finite in f32") {
            return bad(Field::LogScale(a), v, why);
        }
    }
    if !g.opacity_logits[i].is_finite() {
        return bad(Field::OpacityLogit, g.opacity_logits[i], NOT_FINITE);
    }
    for (coeff, c) in g.sh_of(i).iter().enumerate() {
        for (channel, &v) in c.iter().enumerate() {
            if !v.is_finite() {
                return bad(Field::Sh { coeff, channel }, v, NOT_FINITE);
            }
        }
    }
    if !g.mask_logits[i].is_finite() {
        return bad(Field::MaskLogit, g.mask_logits[i], NOT_FINITE);
    }
    let r = g.log_reflections[i];
    if let Some(why) =
        log_problem(r, "is a log reflection intensity whose exp is not finite in f32")
    {
        return bad(Field::LogReflection, r, why);
    }
    Ok(())
}

/// Why the log-encoded value `v` cannot be held, if it cannot: not finite, or `overflow` (its
/// exp is not finite).
fn log_problem(v: f32, overflow: &'static str) -> Option<&'static str> {
    if !v.is_finite() {
        Some(NOT_FINITE)
    } else if !v.exp().is_finite() {
        Some(overflow)
    } else {
        None
    }
}

/// The first value of `g` (its lengths checked) that a model file cannot hold.
pub(crate) fn check_gaussians(g: &Gaussians<f32>) -> Result<(), Unusable> {
    (0..g.len()).try_for_each(|i| check_gaussian(g, i))
}
