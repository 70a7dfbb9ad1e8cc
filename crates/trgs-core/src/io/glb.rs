//! Binary glTF (`.glb`) with the Khronos `KHR_gaussian_splatting` extension: a model's Gaussians
//! as one POINTS primitive, its reflection planes as nodes.
//!
//! Written per the extension (release candidate of 2026-04): `POSITION` (with min/max),
//! `KHR_gaussian_splatting:ROTATION` (unit quaternion, x y z w), `:SCALE` (linear), `:OPACITY`
//! (after the sigmoid), `:SH_DEGREE_l_COEF_n` (3DGS's raw coefficients, `n` from the lowest order
//! m; trgs's coefficient `l^2 + n`), and a `COLOR_0` fallback for point-cloud viewers (the
//! DC colour, which 3DGS trains as sRGB, decoded to the linear values glTF expects), all f32.
//! What the standard attributes cannot carry exactly goes into application attributes (the
//! leading underscore of glTF): `_TRGS_OPACITY_LOGIT` (a logit does not survive a round trip
//! through an f32 sigmoid near 0 or 1), `_TRGS_MASK_LOGIT`, `_TRGS_LOG_REFLECTION` and
//! `_TRGS_POPULATION` (0 primary, 1 glass). A reader that finds them uses them; a file from
//! another tool without them reads as primary Gaussians with logit(opacity) and ln(scale).
//!
//! trgs's world is a COLMAP-style frame (y down, z forward); the Gaussians and plane nodes hang
//! under a root node turned 180 degrees about x, so that glTF viewers (y up) show the scene
//! upright, while the mesh and plane data stay in trgs's coordinates. Each plane node has the
//! plane's centre and orientation (x: width axis, y: height axis, z: normal) as its transform, and
//! every parameter exactly in `extras.trgs_plane`.
//!
//! Reading accepts 8- and 16-bit integer attributes too (normalised or not, as quantising
//! exporters write rotations, scales and opacities). The splat mesh's node transform (with its
//! parents') and the glTF-to-trgs flip are applied to the Gaussians (identity for trgs's own
//! files): a y-up file from another tool comes out upright. Rotations move SH of degree 1 and up
//! only when they map each axis onto itself up to sign (as the flip does); other rotations with
//! view-dependent colour, non-uniform scales, sparse accessors and required extensions trgs does
//! not know are refused by name.
//!
//! Written by hand rather than on the `gltf` crate, which cannot hold these files: gltf-json
//! 1.4.1 (the newest release) parses a vertex attribute name that is neither a glTF semantic nor
//! `_`-prefixed, as every `KHR_gaussian_splatting:*` name is, into one `Checked::Invalid` key, so
//! a file's extension attributes collapse into one map entry (four of seven left in a probe);
//! `Gltf::from_slice` then refuses the file (`invalid glTF: meshes[0].primitives[0].attributes
//! ["<invalid semantic name>"]: Invalid value`), iterating the attributes without validation
//! panics, and no `Semantic` writes such a name back. The container framing is 12 bytes.
use std::path::Path;

use glam::{DMat3, DQuat};
use serde_json::{Value, json};

use super::error::{FormatError, write_atomic};
use super::model_values::{Field, check_gaussians};
use crate::scene::{Gaussians, Material, ReflectionPlane, sh_coeff_count};
use crate::sh::C0;

/// glTF's bufferView target for vertex attributes.
const ARRAY_BUFFER: u32 = 34962;
const MAGIC: u32 = 0x4654_6C67;
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;
const FLOAT: u64 = 5126;
const MODE_POINTS: u64 = 0;
const EXTENSION: &str = "KHR_gaussian_splatting";

/// One attribute: its semantic, accessor type and components per element.
struct Column {
    semantic: String,
    kind: &'static str,
    values: Vec<f32>,
}

fn columns(g: &Gaussians<f32>) -> Vec<Column> {
    let n = g.len();
    let col = |semantic: &str, kind: &'static str, values: Vec<f32>| Column {
        semantic: semantic.to_string(),
        kind,
        values,
    };
    let mut cols = vec![
        col("POSITION", "VEC3", g.means.iter().flatten().copied().collect()),
        col(
            "KHR_gaussian_splatting:ROTATION",
            "VEC4",
            g.rotations
                .iter()
                .flat_map(|q| {
                    // Finite and non-zero: `writable` has checked.
                    let norm = q.iter().map(|v| v * v).sum::<f32>().sqrt();
                    [q[1] / norm, q[2] / norm, q[3] / norm, q[0] / norm]
                })
                .collect(),
        ),
        col(
            "KHR_gaussian_splatting:SCALE",
            "VEC3",
            g.log_scales.iter().flatten().map(|v| v.exp()).collect(),
        ),
        col(
            "KHR_gaussian_splatting:OPACITY",
            "SCALAR",
            g.opacity_logits.iter().map(|v| 1.0 / (1.0 + (-v).exp())).collect(),
        ),
    ];
    let coeffs = sh_coeff_count(g.sh_degree);
    for degree in 0..=g.sh_degree {
        for order in 0..2 * degree + 1 {
            let k = (degree * degree + order) as usize;
            cols.push(col(
                &format!("KHR_gaussian_splatting:SH_DEGREE_{degree}_COEF_{order}"),
                "VEC3",
                (0..n).flat_map(|i| g.sh[i * coeffs + k]).collect(),
            ));
        }
    }
    let fallback = (0..n)
        .flat_map(|i| {
            g.sh[i * coeffs].map(|v| srgb_to_linear((0.5 + C0 as f32 * v).clamp(0.0, 1.0)))
        })
        .collect();
    cols.push(col("COLOR_0", "VEC3", fallback));
    cols.push(col("_TRGS_OPACITY_LOGIT", "SCALAR", g.opacity_logits.clone()));
    cols.push(col("_TRGS_MASK_LOGIT", "SCALAR", g.mask_logits.clone()));
    cols.push(col("_TRGS_LOG_REFLECTION", "SCALAR", g.log_reflections.clone()));
    cols.push(col(
        "_TRGS_POPULATION",
        "SCALAR",
        g.populations.iter().map(|&p| p as u8 as f32).collect(),
    ));
    cols
}

/// The linear value of an sRGB-encoded one in [0, 1] (IEC 61966-2-1), as glTF's `COLOR_0`
/// holds linear colour.
fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

/// What the file stores `field` as, for messages (scales are stored as their exp, and read back
/// as its log).
fn attribute_name(field: Field) -> String {
    match field {
        Field::Mean(a) => format!("POSITION[{a}]"),
        Field::Rotation(a) => format!("rotation[{a}] (w x y z; KHR_gaussian_splatting:ROTATION)"),
        Field::LogScale(a) => format!("log-scale[{a}] (ln of KHR_gaussian_splatting:SCALE)"),
        Field::OpacityLogit => "_TRGS_OPACITY_LOGIT".into(),
        Field::Sh { coeff, channel } => {
            let degree = coeff.isqrt();
            let order = coeff - degree * degree;
            format!("KHR_gaussian_splatting:SH_DEGREE_{degree}_COEF_{order}[{channel}]")
        }
        Field::MaskLogit => "_TRGS_MASK_LOGIT".into(),
        Field::LogReflection => "_TRGS_LOG_REFLECTION".into(),
    }
}

/// Every value of `g` one a model file can hold, and a rotation with a direction (the file
/// stores a unit quaternion).
fn writable(g: &Gaussians<f32>) -> Result<(), String> {
    check_gaussians(g).map_err(|u| u.message(&attribute_name(u.field)))?;
    match g.rotations.iter().position(|q| q.iter().all(|&v| v * v == 0.0)) {
        Some(i) => Err(format!(
            "Gaussian {i}: rotation {:?} has no direction, and a glTF rotation is a unit \
             quaternion",
            g.rotations[i]
        )),
        None => Ok(()),
    }
}

fn components(kind: &str) -> Option<usize> {
    match kind {
        "SCALAR" => Some(1),
        "VEC3" => Some(3),
        "VEC4" => Some(4),
        _ => None,
    }
}

fn material_name(m: Material) -> &'static str {
    match m {
        Material::Glass => "glass",
        Material::Mirror => "mirror",
    }
}

fn plane_node(k: usize, p: &ReflectionPlane) -> Value {
    let n = p.unit_normal();
    let basis = DMat3::from_cols(p.axis, p.bitangent(), n);
    let q = DQuat::from_mat3(&basis).normalize();
    json!({
        "name": format!("plane {} ({})", k + 1, material_name(p.material)),
        "translation": p.centre.to_array(),
        "rotation": [q.x, q.y, q.z, q.w],
        "extras": { "trgs_plane": {
            "label": k + 1,
            "material": material_name(p.material),
            "centre": p.centre.to_array(),
            "normal": p.normal.to_array(),
            "axis": p.axis.to_array(),
            "width": p.width,
            "height": p.height,
            "r0_logit": p.r0_logit,
            "r0": p.r0(),
        }},
    })
}

/// `g` and `planes` as a GLB file.
pub fn encode_glb(g: &Gaussians<f32>, planes: &[ReflectionPlane]) -> Result<Vec<u8>, String> {
    g.check_lengths()?;
    if g.is_empty() {
        return Err("a glTF point primitive needs at least one Gaussian".into());
    }
    writable(g)?;
    let mut bin: Vec<u8> = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    let mut attributes = serde_json::Map::new();
    for (i, c) in columns(g).into_iter().enumerate() {
        let offset = bin.len();
        bin.extend(c.values.iter().flat_map(|v| v.to_le_bytes()));
        // Every view holds one vertex attribute: ARRAY_BUFFER (the validator hints otherwise).
        views.push(json!({
            "buffer": 0, "byteOffset": offset, "byteLength": c.values.len() * 4,
            "target": ARRAY_BUFFER,
        }));
        let mut accessor = json!({
            "bufferView": i, "componentType": FLOAT, "count": g.len(), "type": c.kind,
        });
        if c.semantic == "POSITION" {
            let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
            for m in &g.means {
                for a in 0..3 {
                    lo[a] = lo[a].min(m[a]);
                    hi[a] = hi[a].max(m[a]);
                }
            }
            accessor["min"] = json!(lo);
            accessor["max"] = json!(hi);
        }
        accessors.push(accessor);
        attributes.insert(c.semantic, json!(i));
    }
    let mut children = vec![1];
    let mut nodes = vec![
        // COLMAP-style (y down, z forward) to glTF (y up, z backward).
        json!({"name": "trgs", "rotation": [1.0, 0.0, 0.0, 0.0], "children": []}),
        json!({"name": "gaussians", "mesh": 0}),
    ];
    for (k, p) in planes.iter().enumerate() {
        children.push(nodes.len());
        nodes.push(plane_node(k, p));
    }
    nodes[0]["children"] = json!(children);
    let doc = json!({
        "asset": {"version": "2.0", "generator": concat!("trgs ", env!("CARGO_PKG_VERSION"))},
        "extensionsUsed": [EXTENSION],
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": nodes,
        "meshes": [{"name": "gaussians", "primitives": [{
            "mode": MODE_POINTS,
            "attributes": attributes,
            "extensions": {EXTENSION: {"kernel": "ellipse", "colorSpace": "srgb_rec709_display"}},
        }]}],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": views,
        "accessors": accessors,
    });
    let mut text = serde_json::to_vec(&doc).map_err(|e| e.to_string())?;
    text.resize(text.len().next_multiple_of(4), b' ');
    bin.resize(bin.len().next_multiple_of(4), 0);
    let total = 12 + 8 + text.len() + 8 + bin.len();
    let total = u32::try_from(total).map_err(|_| format!("{total} bytes: over GLB's 4 GiB"))?;
    let mut out = Vec::with_capacity(total as usize);
    for word in [MAGIC, 2, total, text.len() as u32, CHUNK_JSON] {
        out.extend(word.to_le_bytes());
    }
    out.extend(&text);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(CHUNK_BIN.to_le_bytes());
    out.extend(&bin);
    Ok(out)
}

/// Write `g` and `planes` to `path` (atomically).
pub fn write_glb(
    path: &Path,
    g: &Gaussians<f32>,
    planes: &[ReflectionPlane],
) -> Result<(), FormatError> {
    let bytes = encode_glb(g, planes).map_err(|m| FormatError::new(path, m))?;
    write_atomic(path, &bytes)
}

mod placement;
mod read;

pub use read::{parse_glb, read_glb};

#[cfg(test)]
mod tests;
