//! 3DGS models as INRIA-layout PLY, the format every 3DGS viewer reads, plus trgs's own
//! per-Gaussian attributes as extra float properties that other viewers ignore. The extras are
//! written only where a Gaussian holds something in them (glass Gaussians, a learned mask or
//! reflection): SIBR, INRIA's viewer, reads rows of a fixed size whatever the header says, so
//! a plain or baked model is written as exactly INRIA's rows.
//!
//! The stored values are the raw parameters, exactly as in [`Gaussians`] and INRIA's files:
//! opacity as a logit, scales as logs, rotations as unnormalised (w, x, y, z). The one layout
//! difference is SH: INRIA's `f_rest_*` are channel-major (`f_rest_{c (K-1) + j - 1}` is
//! coefficient j >= 1 of channel c) while [`Gaussians::sh`] is coefficient-major.
//!
//! The reader accepts any property order and type, ASCII and both binary byte orders, and skips
//! other elements, so files from INRIA's code, gsplat, Brush, SuperSplat's uncompressed export
//! and others load. It refuses data after the elements the header declares, and values a model
//! file cannot hold (not finite, or a log-scale whose exp is not: `io::model_values`), naming
//! the Gaussian and the property; the writer refuses the same values. What the renderer needs
//! beyond that (no zero quaternion, reflection intensities it can compose) is
//! [`crate::scene::validate_scene`]'s to refuse.
mod body;
mod end;
mod header;
mod pieces;
mod points;
#[cfg(test)]
mod tests;

pub use points::{ColouredPoint, read_point_cloud_ply};

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

use body::Body;
use end::check_end;
use header::{Element, Format, Header, parse_header};
use pieces::{ROWS_PER_PIECE, read_in_pieces};

use super::bytes::ByteReader;
use super::model_values::{Field, check_gaussian, check_gaussians};
use super::{FormatError, write_atomic_with};
use crate::scene::{Gaussians, Population, sh_coeff_count};

/// trgs's extra properties: mask logit, log reflection intensity, population (0 / 1).
const EXTRAS: [&str; 3] = ["trgs_mask", "trgs_reflection", "trgs_population"];

/// Read a 3DGS PLY file. A binary file's vertices are read a piece at a time, so that a model of
/// millions of Gaussians is not held twice, as the file's bytes and as Gaussians.
pub fn read_ply(path: &Path) -> Result<Gaussians<f32>, FormatError> {
    read_in_pieces(path, ROWS_PER_PIECE)
}

/// Write `g` as binary little-endian PLY (see the module docs for the layout).
pub fn write_ply(path: &Path, g: &Gaussians<f32>) -> Result<(), FormatError> {
    writable(g).map_err(|m| FormatError::new(path, m))?;
    // Streamed: a model of millions of Gaussians is not held again as bytes.
    write_atomic_with(path, |w| write_rows(g, w))
}

/// `g`'s lengths agree and every value is one a model file can hold.
fn writable(g: &Gaussians<f32>) -> Result<(), String> {
    g.check_lengths()?;
    check_gaussians(g).map_err(|u| u.message(&property_name(u.field, g.sh_coeffs())))
}

/// The PLY property of `field`, at `coeffs` SH coefficients a channel.
fn property_name(field: Field, coeffs: usize) -> String {
    match field {
        Field::Mean(a) => ["x", "y", "z"][a].to_string(),
        Field::Rotation(a) => format!("rot_{a}"),
        Field::LogScale(a) => format!("scale_{a}"),
        Field::OpacityLogit => "opacity".into(),
        Field::Sh { coeff: 0, channel } => format!("f_dc_{channel}"),
        Field::Sh { coeff, channel } => format!("f_rest_{}", channel * (coeffs - 1) + coeff - 1),
        Field::MaskLogit => EXTRAS[0].into(),
        Field::LogReflection => EXTRAS[1].into(),
    }
}

/// Whether `g` has anything to keep in trgs's extra properties (they read back as zeros and
/// primary Gaussians when absent).
fn needs_extras(g: &Gaussians<f32>) -> bool {
    g.populations.iter().any(|&p| p != Population::Primary)
        || g.mask_logits.iter().any(|&v| v.to_bits() != 0)
        || g.log_reflections.iter().any(|&v| v.to_bits() != 0)
}

/// Names of the float properties the writer emits, in order, for SH degree `degree`, with
/// trgs's extras or without.
fn property_names(degree: u32, extras: bool) -> Vec<String> {
    let rest = 3 * (sh_coeff_count(degree) - 1);
    let mut names: Vec<String> =
        ["x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"].map(String::from).into();
    names.extend((0..rest).map(|k| format!("f_rest_{k}")));
    names.extend(
        ["opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"]
            .map(String::from),
    );
    if extras {
        names.extend(EXTRAS.map(String::from));
    }
    names
}

/// The bytes of a binary little-endian PLY of `g`; an error when `g`'s arrays disagree in length
/// or it holds a value a model file cannot hold.
pub fn encode_ply(g: &Gaussians<f32>) -> Result<Vec<u8>, String> {
    writable(g)?;
    let mut out = Vec::new();
    write_rows(g, &mut out).map_err(|e| e.to_string())?;
    Ok(out)
}

/// The header and a row of floats per Gaussian (`g`'s lengths checked), into `w`.
fn write_rows(g: &Gaussians<f32>, w: &mut dyn std::io::Write) -> std::io::Result<()> {
    let extras = needs_extras(g);
    let names = property_names(g.sh_degree, extras);
    let mut header = format!("ply\nformat binary_little_endian 1.0\nelement vertex {}\n", g.len());
    for name in &names {
        let _ = writeln!(header, "property float {name}");
    }
    header.push_str("end_header\n");
    w.write_all(header.as_bytes())?;
    let k = g.sh_coeffs();
    let mut row = Vec::with_capacity(names.len());
    let mut bytes = Vec::with_capacity(names.len() * 4);
    for i in 0..g.len() {
        row.clear();
        row.extend(g.means[i]);
        row.extend([0.0; 3]); // normals: INRIA writes zeros; nobody reads them
        let sh = g.sh_of(i);
        row.extend(sh[0]);
        for c in 0..3 {
            row.extend(sh[1..].iter().map(|coeff| coeff[c]));
        }
        row.push(g.opacity_logits[i]);
        row.extend(g.log_scales[i]);
        row.extend(g.rotations[i]);
        if extras {
            row.push(g.mask_logits[i]);
            row.push(g.log_reflections[i]);
            row.push(f32::from(g.populations[i] as u8));
        }
        debug_assert_eq!(row.len(), names.len(), "SH count {k}");
        bytes.clear();
        row.iter().for_each(|v| bytes.extend(v.to_le_bytes()));
        w.write_all(&bytes)?;
    }
    Ok(())
}

/// Parse a PLY held in memory; `path` is only used to name the file in errors.
pub fn parse_ply(bytes: &[u8], path: &Path) -> Result<Gaussians<f32>, FormatError> {
    let fail = |m: String| FormatError::new(path, m);
    let (mut body, header, index) =
        vertex_section(bytes, "one Gaussian per vertex").map_err(fail)?;
    let vertex = &header.elements[index];
    let layout = Layout::of(vertex).map_err(fail)?;
    let mut rows = VertexRows::new(vertex, &layout, body.remaining());
    for i in 0..vertex.count {
        rows.read(&mut body, i).map_err(fail)?;
    }
    check_end(&mut body, &header.elements[index + 1..], &header.elements).map_err(fail)?;
    Ok(rows.g)
}

/// The body read up to the first vertex (every element before it skipped), the header and the
/// vertex element's index in it; `expected` says what a vertex is, for the error when there is
/// none.
fn vertex_section<'a>(
    bytes: &'a [u8],
    expected: &str,
) -> Result<(Body<'a>, Header, usize), String> {
    let header = parse_header(bytes)?;
    let body = &bytes[header.body_offset..];
    let mut body = match header.format {
        Format::Ascii => Body::ascii(body),
        // Offsets in messages count from the file's start, not the body's.
        Format::Binary(e) => Body::Binary(ByteReader::at(body, header.body_offset), e),
    };
    let vertex_index = header
        .elements
        .iter()
        .position(|e| e.name == "vertex")
        .ok_or_else(|| format!("the file has no `vertex` element (expected {expected})"))?;
    for element in &header.elements[..vertex_index] {
        body.skip(element)?;
    }
    Ok((body, header, vertex_index))
}

/// Where each vertex property goes in a per-vertex row of values:
/// `x y z | f_dc 0..3 | f_rest 0..R | opacity | scale 0..3 | rot 0..4 | mask reflection population`.
struct Layout {
    /// For each vertex property, its slot in the row, or None for properties we skip.
    slots: Vec<Option<usize>>,
    rest: usize,
    degree: u32,
}

impl Layout {
    fn of(vertex: &Element) -> Result<Self, String> {
        let rest_indices: Vec<usize> = vertex
            .properties
            .iter()
            .filter_map(|p| p.name.strip_prefix("f_rest_")?.parse().ok())
            .collect();
        let rest = rest_indices.len();
        let degree = match rest {
            0 => 0,
            9 => 1,
            24 => 2,
            45 => 3,
            n => {
                return Err(format!(
                    "found {n} f_rest_* properties; expected 0, 9, 24 or 45 (SH degree 0 to 3)"
                ));
            }
        };
        let mut slot_of: HashMap<String, usize> = HashMap::new();
        let fixed = ["x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2"];
        for (s, name) in fixed.iter().enumerate() {
            slot_of.insert(name.to_string(), s);
        }
        for k in 0..rest {
            slot_of.insert(format!("f_rest_{k}"), 6 + k);
        }
        let tail = ["opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"];
        for (s, name) in tail.iter().chain(&EXTRAS).enumerate() {
            slot_of.insert(name.to_string(), 6 + rest + s);
        }
        let mut seen = vec![false; 6 + rest + tail.len() + EXTRAS.len()];
        let mut slots = Vec::with_capacity(vertex.properties.len());
        for p in &vertex.properties {
            let slot = slot_of.get(&p.name).copied();
            if let Some(s) = slot {
                if p.list_count.is_some() {
                    return Err(format!(
                        "vertex property `{}` is a list; expected a scalar",
                        p.name
                    ));
                }
                if std::mem::replace(&mut seen[s], true) {
                    return Err(format!("vertex property `{}` appears twice", p.name));
                }
            }
            slots.push(slot);
        }
        // Everything but the extras is required; a missing f_rest_k shows up here by name.
        let required =
            fixed.iter().map(|s| s.to_string()).chain((0..rest).map(|k| format!("f_rest_{k}")));
        for name in required.chain(tail.iter().map(|s| s.to_string())) {
            if !seen[slot_of[&name]] {
                let hint = if vertex.properties.iter().any(|p| p.name == "packed_position") {
                    " (this looks like a compressed PLY from SuperSplat or gsplat, which trgs does not read: \
                     export an uncompressed PLY)"
                } else {
                    ""
                };
                return Err(format!("the vertex element has no property `{name}`{hint}"));
            }
        }
        Ok(Self { slots, rest, degree })
    }
}

/// Gaussians built a vertex at a time, whether the body is held whole or read in pieces.
struct VertexRows<'a> {
    vertex: &'a Element,
    layout: &'a Layout,
    /// One vertex's values in [`Layout`]'s slots.
    row: Vec<f32>,
    sh: Vec<[f32; 3]>,
    g: Gaussians<f32>,
}

impl<'a> VertexRows<'a> {
    /// `remaining`: the bytes of the body from the first vertex on, which bound how many
    /// vertices the file can hold.
    fn new(vertex: &'a Element, layout: &'a Layout, remaining: usize) -> Self {
        let g = Gaussians::empty(layout.degree);
        let k = g.sh_coeffs();
        let mut rows = Self {
            vertex,
            layout,
            row: vec![0.0; 6 + layout.rest + 8 + EXTRAS.len()],
            sh: vec![[0.0; 3]; k],
            g,
        };
        // A corrupt count must not make us allocate more than the body could hold (every
        // property takes at least one byte, binary or ASCII).
        let bound = remaining / vertex.properties.len().max(1);
        let cap = usize::try_from(vertex.count).map_or(bound, |n| n.min(bound));
        let g = &mut rows.g;
        g.means.reserve(cap);
        g.rotations.reserve(cap);
        g.log_scales.reserve(cap);
        g.opacity_logits.reserve(cap);
        g.sh.reserve(cap.saturating_mul(k));
        g.mask_logits.reserve(cap);
        g.log_reflections.reserve(cap);
        g.populations.reserve(cap);
        rows
    }

    /// Read vertex `i` from `body` and add its Gaussian.
    fn read(&mut self, body: &mut Body<'_>, i: u64) -> Result<(), String> {
        let n = self.vertex.count;
        let r = self.layout.rest;
        let row = &mut self.row;
        // Defaults for the optional extras: mask logit 0, log reflection 0, primary.
        row[6 + r + 8..].fill(0.0);
        for (p, slot) in self.vertex.properties.iter().zip(&self.layout.slots) {
            let what = || format!("property {}", p.name);
            match (p.list_count, slot) {
                (Some(ty), _) => {
                    let count =
                        body.count(ty, &what).map_err(|m| format!("vertex {i} of {n}: {m}"))?;
                    for _ in 0..count {
                        body.scalar(p.ty, &what).map_err(|m| format!("vertex {i} of {n}: {m}"))?;
                    }
                }
                (None, slot) => {
                    let v =
                        body.scalar(p.ty, &what).map_err(|m| format!("vertex {i} of {n}: {m}"))?;
                    if let Some(s) = slot {
                        row[*s] = v as f32;
                    }
                }
            }
        }
        let t = 6 + r; // start of opacity, scales, rotation, extras
        let population = match row[t + 10] {
            0.0 => Population::Primary,
            1.0 => Population::Glass,
            v => {
                return Err(format!(
                    "vertex {i}: trgs_population is {v}; expected 0 (primary) or 1 (glass)"
                ));
            }
        };
        let k = self.sh.len();
        let sh = &mut self.sh;
        sh[0] = [row[3], row[4], row[5]];
        for c in 0..3 {
            for j in 1..k {
                sh[j][c] = row[6 + c * (k - 1) + (j - 1)];
            }
        }
        let g = &mut self.g;
        g.push(
            [row[0], row[1], row[2]],
            [row[t + 4], row[t + 5], row[t + 6], row[t + 7]],
            [row[t + 1], row[t + 2], row[t + 3]],
            row[t],
            sh,
            population,
        );
        if let (Some(m), Some(a)) = (g.mask_logits.last_mut(), g.log_reflections.last_mut()) {
            *m = row[t + 8];
            *a = row[t + 9];
        }
        check_gaussian(g, g.len() - 1).map_err(|u| u.message(&property_name(u.field, k)))
    }
}
