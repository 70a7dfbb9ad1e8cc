//! Checkpoints: everything a run needs to continue exactly where it stopped (parameters, Adam
//! moments, planes and their moments, densification statistics, random state, and whatever the
//! caller keeps besides), in one file written atomically.
//!
//! Format: the line `trgs-checkpoint 1`, one line of JSON (the small state and the manifest of
//! the arrays that follow: name, element type, length), then the arrays, little-endian, in manifest
//! order. The manifest makes a truncated or mismatched file an error that says which array.
use crate::densify::DensifyStats;
use crate::exposure::ViewExposures;
use crate::gaussians::plan::TrainState;
use crate::planes::adam::OffsetLimit;
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::borrow::Cow;
use std::io::{BufRead, Read, Write};
use std::path::Path;
use trgs_core::io::{FormatError, write_atomic_with};
use trgs_core::scene::{
    Attribute, Gaussians, Material, PerAttribute, Population, ReflectionPlane, attribute_widths,
};

/// The checkpoint's file name in a run folder.
pub const CHECKPOINT_FILE: &str = "checkpoint.trgs";
const MAGIC: &str = "trgs-checkpoint 1";

/// Optimiser state of one plane. Adam's moments are in `plane_adam`'s slots: 0 the offset along
/// the normal, 3..6 the unnormalised normal, 6 the R0 logit; 1 and 2 are unused, left from the
/// per-coordinate centre of older versions (whose checkpoints still load: their centre-x moments
/// then start the offset's, which Adam's bias-corrected averages forget within a few hundred
/// steps).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PlaneMoments {
    pub m: [f64; 7],
    pub v: [f64; 7],
    /// Adam steps this plane has taken: its bias correction counts from the plane's creation,
    /// not from the run's start (0 in checkpoints that predate it; see `Trainer::step_planes`).
    #[serde(default)]
    pub steps: u32,
    /// Where the glass masks pin the plane's offset (None: free; also in older checkpoints).
    #[serde(default)]
    pub offset_limit: Option<OffsetLimit>,
}

/// A training run's state at the end of step `step`.
#[derive(Clone, Debug)]
pub struct Checkpoint {
    pub step: u32,
    pub state: TrainState,
    pub planes: Vec<ReflectionPlane>,
    pub plane_moments: Vec<PlaneMoments>,
    /// The training views' exposures and their Adam state (empty when compensation is off).
    pub exposures: ViewExposures,
    /// Classic densification's statistics since its last run (None when it is off).
    pub densify_stats: Option<DensifyStats>,
    /// The trainer's random state (densification draws).
    pub rng_state: u64,
    /// What the caller keeps besides the trainer (the `train` bin: its arguments, view order,
    /// evaluations so far).
    pub extra: serde_json::Value,
}

#[derive(Serialize, Deserialize)]
struct PlaneRecord {
    centre: [f64; 3],
    normal: [f64; 3],
    axis: [f64; 3],
    width: f64,
    height: f64,
    r0_logit: f64,
    material: Material,
}

#[derive(Serialize, Deserialize)]
struct Header {
    step: u32,
    gaussians: usize,
    sh_degree: u32,
    planes: Vec<PlaneRecord>,
    plane_moments: Vec<PlaneMoments>,
    /// Absent from checkpoints that predate exposure compensation.
    #[serde(default)]
    exposures: ViewExposures,
    densify: bool,
    rng_state: u64,
    extra: serde_json::Value,
    /// (name, "f32" | "f64" | "u32", element count) of each array, in file order.
    arrays: Vec<(String, String, usize)>,
}

/// One array of the payload: borrowed from the checkpoint when written, so that writing holds
/// no second copy of a state of millions of Gaussians; owned when read.
enum Array<'a> {
    F32(Cow<'a, [f32]>),
    F64(Cow<'a, [f64]>),
    U32(Cow<'a, [u32]>),
}

impl Array<'_> {
    fn kind(&self) -> &'static str {
        match self {
            Array::F32(_) => "f32",
            Array::F64(_) => "f64",
            Array::U32(_) => "u32",
        }
    }

    fn len(&self) -> usize {
        match self {
            Array::F32(v) => v.len(),
            Array::F64(v) => v.len(),
            Array::U32(v) => v.len(),
        }
    }

    fn write(&self, w: &mut dyn Write) -> std::io::Result<()> {
        match self {
            Array::F32(v) => write_le(w, v, f32::to_le_bytes),
            Array::F64(v) => write_le(w, v, f64::to_le_bytes),
            Array::U32(v) => write_le(w, v, u32::to_le_bytes),
        }
    }
}

/// Values per chunk of a payload array written or read.
const CHUNK: usize = 1 << 16;

/// `values` little-endian, a chunk at a time.
fn write_le<T: Copy, const N: usize>(
    w: &mut dyn Write,
    values: &[T],
    bytes: impl Fn(T) -> [u8; N],
) -> std::io::Result<()> {
    let mut chunk = Vec::with_capacity(CHUNK.min(values.len()) * N);
    for part in values.chunks(CHUNK) {
        chunk.clear();
        part.iter().for_each(|&v| chunk.extend_from_slice(&bytes(v)));
        w.write_all(&chunk)?;
    }
    Ok(())
}

/// `len` little-endian values from `r`, a chunk at a time.
fn read_le<T, const N: usize>(
    r: &mut impl Read,
    len: usize,
    value: impl Fn([u8; N]) -> T,
) -> std::io::Result<Vec<T>> {
    let mut out = Vec::with_capacity(len);
    let mut chunk = vec![0u8; CHUNK.min(len) * N];
    while out.len() < len {
        let bytes = &mut chunk[..(len - out.len()).min(CHUNK) * N];
        r.read_exact(bytes)?;
        out.extend(bytes.chunks_exact(N).map(|c| value(std::array::from_fn(|i| c[i]))));
    }
    Ok(out)
}

fn chunks<const N: usize>(v: &[f32]) -> Vec<[f32; N]> {
    v.chunks_exact(N).map(|c| std::array::from_fn(|i| c[i])).collect()
}

/// Why `state` could not be resumed from: a parameter an upload refuses (not finite, a zero
/// quaternion, an out-of-range reflection) or an Adam moment that is not finite.
pub fn check_state(state: &TrainState) -> Result<(), String> {
    trgs_core::scene::validate_gaussians(&state.gaussians).map_err(|e| e.to_string())?;
    let n = state.gaussians.len().max(1);
    for a in Attribute::ALL {
        for (which, moments) in [("first", &state.m[a]), ("second", &state.v[a])] {
            if let Some(k) = moments.iter().position(|x| !x.is_finite()) {
                let name = a.name();
                let gaussian = k / (moments.len() / n).max(1);
                return Err(format!(
                    "Gaussian {gaussian}: the {which} Adam moment of {name} is not finite ({})",
                    moments[k]
                ));
            }
        }
    }
    Ok(())
}

/// Write `ck` to `path` atomically (a temporary file renamed into place). A state that could
/// not be resumed from ([`check_state`]) is refused and the file keeps what it held: a diverged
/// run never overwrites its last good checkpoint.
pub fn write_checkpoint(path: &Path, ck: &Checkpoint) -> Result<(), FormatError> {
    let exposures = if ck.exposures.is_finite() {
        Ok(())
    } else {
        Err("a view's exposure is not finite".to_string())
    };
    exposures.and_then(|()| check_state(&ck.state)).map_err(|problem| {
        FormatError::new(
            path,
            format!(
                "the training state after step {} is not valid, so it was not written (the file \
                 keeps the checkpoint written before): {problem}",
                ck.step
            ),
        )
    })?;
    let g = &ck.state.gaussians;
    let populations: Vec<u32> = g.populations.iter().map(|&p| p as u32).collect();
    let mut arrays: Vec<(String, Array<'_>)> = vec![
        ("means".into(), Array::F32(Cow::Borrowed(g.means.as_flattened()))),
        ("rotations".into(), Array::F32(Cow::Borrowed(g.rotations.as_flattened()))),
        ("log_scales".into(), Array::F32(Cow::Borrowed(g.log_scales.as_flattened()))),
        ("opacity_logits".into(), Array::F32(Cow::Borrowed(&g.opacity_logits))),
        ("sh".into(), Array::F32(Cow::Borrowed(g.sh.as_flattened()))),
        ("mask_logits".into(), Array::F32(Cow::Borrowed(&g.mask_logits))),
        ("log_reflections".into(), Array::F32(Cow::Borrowed(&g.log_reflections))),
        ("populations".into(), Array::U32(Cow::Borrowed(&populations))),
    ];
    // Moments by the attribute's position in `Attribute::ALL` (the file format's names).
    for a in Attribute::ALL {
        let k = a.index();
        arrays.push((format!("adam_m_{k}"), Array::F32(Cow::Borrowed(&ck.state.m[a]))));
        arrays.push((format!("adam_v_{k}"), Array::F32(Cow::Borrowed(&ck.state.v[a]))));
    }
    if let Some(s) = &ck.densify_stats {
        arrays.push(("densify_grad_sum".into(), Array::F64(Cow::Borrowed(&s.grad_sum))));
        arrays.push(("densify_count".into(), Array::U32(Cow::Borrowed(&s.count))));
        arrays.push(("densify_max_radius".into(), Array::F64(Cow::Borrowed(&s.max_radius))));
    }
    let header = Header {
        step: ck.step,
        gaussians: g.len(),
        sh_degree: g.sh_degree,
        planes: ck
            .planes
            .iter()
            .map(|p| PlaneRecord {
                centre: p.centre.to_array(),
                normal: p.normal.to_array(),
                axis: p.axis.to_array(),
                width: p.width,
                height: p.height,
                r0_logit: p.r0_logit,
                material: p.material,
            })
            .collect(),
        plane_moments: ck.plane_moments.clone(),
        exposures: ck.exposures.clone(),
        densify: ck.densify_stats.is_some(),
        rng_state: ck.rng_state,
        extra: ck.extra.clone(),
        arrays: arrays.iter().map(|(n, a)| (n.clone(), a.kind().to_string(), a.len())).collect(),
    };
    let json = serde_json::to_string(&header)
        .map_err(|e| FormatError::new(path, format!("encoding the header: {e}")))?;
    write_atomic_with(path, |w| {
        w.write_all(format!("{MAGIC}\n{json}\n").as_bytes())?;
        arrays.iter().try_for_each(|(_, a)| a.write(w))
    })
}

/// Read a checkpoint written by [`write_checkpoint`], an array at a time (the file is not held
/// in memory whole).
pub fn read_checkpoint(path: &Path) -> Result<Checkpoint, FormatError> {
    let io = |e: std::io::Error| FormatError::io(path, &e);
    let file = std::fs::File::open(path).map_err(io)?;
    let size = file.metadata().map_err(io)?.len();
    let mut r = std::io::BufReader::with_capacity(1 << 20, file);
    let (header, read) = read_header(&mut r, path)?;
    let mut arrays = read_arrays(&mut r, path, &header, size.saturating_sub(read))?;
    let (gaussians, m, v) = gaussians_of(&header, &mut arrays)?;
    let densify_stats = if header.densify {
        let count = arrays.take_u32("densify_count", header.gaussians)?;
        Some(DensifyStats {
            grad_sum: arrays.take_f64("densify_grad_sum", header.gaussians)?,
            count,
            max_radius: arrays.take_f64("densify_max_radius", header.gaussians)?,
        })
    } else {
        None
    };
    let planes = planes_of(&header, path)?;
    Ok(Checkpoint {
        step: header.step,
        state: TrainState { gaussians, m, v },
        planes,
        plane_moments: header.plane_moments,
        exposures: header.exposures,
        densify_stats,
        rng_state: header.rng_state,
        extra: header.extra,
    })
}

/// The most bytes of a first line read to tell a checkpoint of another format version from
/// another file.
const MAGIC_LINE_MAX: u64 = 64;

/// Why a file whose first line is `first` is not read as a checkpoint: a checkpoint of another
/// format version (a newer trgs, or an old one this trgs no longer reads), or not one at all.
fn not_this_format(first: &[u8]) -> String {
    let (name, ours) = MAGIC.rsplit_once(' ').unwrap_or((MAGIC, "1"));
    let ours: u32 = ours.parse().unwrap_or(1);
    let version = std::str::from_utf8(first)
        .ok()
        .and_then(|l| l.strip_prefix(name)?.strip_prefix(' ')?.trim().parse::<u32>().ok());
    match version {
        Some(v) if v > ours => format!(
            "a checkpoint of format version {v}, written by a newer trgs (this one reads version \
             {ours}): continue it with that trgs"
        ),
        Some(v) => format!(
            "a checkpoint of format version {v}, which this trgs (version {ours}) no longer \
             reads: continue it with the trgs that wrote it"
        ),
        None => format!("not a trgs checkpoint (expected a first line {MAGIC:?})"),
    }
}

/// The magic line and the header line; with the bytes they took.
fn read_header(r: &mut impl BufRead, path: &Path) -> Result<(Header, u64), FormatError> {
    let io = |e: std::io::Error| FormatError::io(path, &e);
    let bad = |what: String| FormatError::new(path, what);
    // The first line, read no further than the magic's length (any file may be passed here).
    let mut magic = Vec::new();
    r.by_ref().take(MAGIC_LINE_MAX).read_until(b'\n', &mut magic).map_err(io)?;
    let first = magic.strip_suffix(b"\n").unwrap_or(&magic);
    if first != MAGIC.as_bytes() {
        return Err(bad(not_this_format(first)));
    }
    if !magic.ends_with(b"\n") {
        return Err(bad("no header line".into()));
    }
    let mut header_line = Vec::new();
    r.read_until(b'\n', &mut header_line).map_err(io)?;
    let read = (magic.len() + header_line.len()) as u64;
    let header: Header =
        serde_json::from_slice(header_line.strip_suffix(b"\n").unwrap_or(&header_line))
            .map_err(|e| bad(format!("malformed header: {e}")))?;
    Ok((header, read))
}

/// The arrays the header's manifest promises, from the `left` bytes after it: each must be
/// there whole, and nothing may follow the last.
fn read_arrays<'a>(
    r: &mut impl Read,
    path: &'a Path,
    header: &Header,
    mut left: u64,
) -> Result<Arrays<'a>, FormatError> {
    let io = |e: std::io::Error| FormatError::io(path, &e);
    let bad = |what: String| FormatError::new(path, what);
    let mut arrays = std::collections::HashMap::new();
    for (name, kind, len) in &header.arrays {
        let size = match kind.as_str() {
            "f32" | "u32" => 4,
            "f64" => 8,
            other => return Err(bad(format!("array {name}: unknown element type {other:?}"))),
        };
        let n = (*len as u64).saturating_mul(size);
        if left < n {
            return Err(bad(format!(
                "array {name}: expected {len} {kind} values, the file ends after {left} bytes of \
                 it (truncated?)"
            )));
        }
        left -= n;
        let array = match kind.as_str() {
            "f32" => Array::F32(read_le(r, *len, f32::from_le_bytes).map_err(io)?.into()),
            "u32" => Array::U32(read_le(r, *len, u32::from_le_bytes).map_err(io)?.into()),
            _ => Array::F64(read_le(r, *len, f64::from_le_bytes).map_err(io)?.into()),
        };
        arrays.insert(name.clone(), array);
    }
    if left > 0 {
        return Err(bad(format!("{left} bytes after the last array")));
    }
    Ok(Arrays { path, arrays })
}

/// The arrays read, taken by name and checked for their type and length.
struct Arrays<'a> {
    path: &'a Path,
    arrays: std::collections::HashMap<String, Array<'static>>,
}

impl Arrays<'_> {
    fn take_f32(&mut self, name: &str, len: usize) -> Result<Vec<f32>, FormatError> {
        match self.arrays.remove(name) {
            Some(Array::F32(v)) if v.len() == len => Ok(v.into_owned()),
            Some(a) => Err(FormatError::new(
                self.path,
                format!("array {name}: expected {len} f32 values, found {} {}", a.len(), a.kind()),
            )),
            None => Err(FormatError::new(self.path, format!("array {name} is missing"))),
        }
    }

    fn take_u32(&mut self, name: &str, len: usize) -> Result<Vec<u32>, FormatError> {
        match self.arrays.remove(name) {
            Some(Array::U32(v)) if v.len() == len => Ok(v.into_owned()),
            _ => {
                Err(FormatError::new(self.path, format!("array {name}: expected {len} u32 values")))
            }
        }
    }

    fn take_f64(&mut self, name: &str, len: usize) -> Result<Vec<f64>, FormatError> {
        match self.arrays.remove(name) {
            Some(Array::F64(v)) if v.len() == len => Ok(v.into_owned()),
            _ => {
                Err(FormatError::new(self.path, format!("array {name}: expected {len} f64 values")))
            }
        }
    }
}

/// The Gaussians and their Adam moments (m, v) of the header's count and SH degree.
#[allow(clippy::type_complexity)]
fn gaussians_of(
    header: &Header,
    arrays: &mut Arrays<'_>,
) -> Result<(Gaussians<f32>, PerAttribute<Vec<f32>>, PerAttribute<Vec<f32>>), FormatError> {
    let n = header.gaussians;
    let coeffs = trgs_core::scene::sh_coeff_count(header.sh_degree);
    let means = chunks::<3>(&arrays.take_f32("means", 3 * n)?);
    let rotations = chunks::<4>(&arrays.take_f32("rotations", 4 * n)?);
    let log_scales = chunks::<3>(&arrays.take_f32("log_scales", 3 * n)?);
    let opacity_logits = arrays.take_f32("opacity_logits", n)?;
    let sh = chunks::<3>(&arrays.take_f32("sh", 3 * coeffs * n)?);
    let mask_logits = arrays.take_f32("mask_logits", n)?;
    let log_reflections = arrays.take_f32("log_reflections", n)?;
    let widths = attribute_widths(coeffs);
    let mut m = PerAttribute::<Vec<f32>>::default();
    let mut v = PerAttribute::<Vec<f32>>::default();
    for a in Attribute::ALL {
        let k = a.index();
        m[a] = arrays.take_f32(&format!("adam_m_{k}"), n * widths[a])?;
        v[a] = arrays.take_f32(&format!("adam_v_{k}"), n * widths[a])?;
    }
    let populations = arrays
        .take_u32("populations", n)?
        .into_iter()
        .map(|p| {
            u8::try_from(p).ok().and_then(Population::from_u8).ok_or_else(|| {
                FormatError::new(arrays.path, format!("population code {p} (expected 0 or 1)"))
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let gaussians = Gaussians {
        means,
        rotations,
        log_scales,
        opacity_logits,
        sh_degree: header.sh_degree,
        sh,
        mask_logits,
        log_reflections,
        populations,
    };
    Ok((gaussians, m, v))
}

/// The header's planes, checked against their moments (one each, offset limits valid).
fn planes_of(header: &Header, path: &Path) -> Result<Vec<ReflectionPlane>, FormatError> {
    let bad = |what: String| FormatError::new(path, what);
    if header.plane_moments.len() != header.planes.len() {
        return Err(bad(format!(
            "{} plane moments for {} planes",
            header.plane_moments.len(),
            header.planes.len()
        )));
    }
    for (k, mom) in header.plane_moments.iter().enumerate() {
        if let Some(l) = &mom.offset_limit
            && !l.is_valid()
        {
            return Err(bad(format!(
                "plane {k}: offset limit {l:?} (expected a finite anchor and a finite tolerance \
                 of at least 0)"
            )));
        }
    }
    Ok(header
        .planes
        .iter()
        .map(|p| ReflectionPlane {
            centre: DVec3::from_array(p.centre),
            normal: DVec3::from_array(p.normal),
            axis: DVec3::from_array(p.axis),
            width: p.width,
            height: p.height,
            r0_logit: p.r0_logit,
            material: p.material,
        })
        .collect())
}

#[cfg(test)]
#[path = "checkpoint_tests.rs"]
mod tests;
