//! Reading a `.glb`: the container's chunks, the accessors (f32 and 8- and 16-bit integers), the
//! splat mesh's attributes and trgs's own, and the plane nodes (see the module docs of `glb`).
use std::path::Path;

use glam::DVec3;
use serde_json::Value;

use super::placement;
use super::{
    CHUNK_BIN, CHUNK_JSON, EXTENSION, FLOAT, MAGIC, MODE_POINTS, attribute_name, components,
};
use crate::io::error::{FormatError, read_bytes};
use crate::io::model_values::check_gaussians;
use crate::scene::{Gaussians, Material, Population, ReflectionPlane, sh_coeff_count};

/// Read the Gaussians and planes of the GLB at `path`.
pub fn read_glb(path: &Path) -> Result<(Gaussians<f32>, Vec<ReflectionPlane>), FormatError> {
    parse_glb(&read_bytes(path)?, path)
}

pub(super) fn word(bytes: &[u8], at: usize) -> Option<u32> {
    bytes.get(at..at + 4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// The JSON document and the BIN chunk of a GLB.
pub(super) fn chunks(bytes: &[u8]) -> Result<(Value, &[u8]), String> {
    if word(bytes, 0) != Some(MAGIC) {
        return Err("not a binary glTF file (no 'glTF' magic at the start)".into());
    }
    if word(bytes, 4) != Some(2) {
        return Err(format!("glTF container version {:?}, expected 2", word(bytes, 4)));
    }
    let mut at = 12;
    let (mut json, mut bin) = (None, None);
    while at + 8 <= bytes.len() {
        let (Some(len), Some(kind)) = (word(bytes, at), word(bytes, at + 4)) else { break };
        let data = bytes.get(at + 8..at + 8 + len as usize).ok_or_else(|| {
            format!("chunk at byte {at} claims {len} bytes; the file ends at {}", bytes.len())
        })?;
        match kind {
            CHUNK_JSON if json.is_none() => {
                json = Some(
                    serde_json::from_slice::<Value>(data)
                        .map_err(|e| format!("JSON chunk: {e}"))?,
                )
            }
            CHUNK_BIN if bin.is_none() => bin = Some(data),
            _ => {} // unknown chunks are ignored, as the spec says
        }
        at += 8 + (len as usize).next_multiple_of(4);
    }
    let json = json.ok_or("no JSON chunk")?;
    Ok((json, bin.unwrap_or(&[])))
}

/// The f32 values of accessor `index` with `kind`, `count` elements.
pub(super) fn read_accessor(
    doc: &Value,
    bin: &[u8],
    index: &Value,
    semantic: &str,
    kinds: &[&str],
    count: Option<usize>,
) -> Result<(Vec<f32>, usize), String> {
    let what = |m: String| format!("attribute {semantic}: {m}");
    let i = index.as_u64().ok_or_else(|| what("accessor index is not a number".into()))?;
    let acc = &doc["accessors"][i as usize];
    if acc.is_null() {
        return Err(what(format!("accessor {i} does not exist")));
    }
    let kind = acc["type"].as_str().unwrap_or("");
    if !kinds.contains(&kind) {
        return Err(what(format!("accessor type {kind:?}, expected {}", kinds.join(" or "))));
    }
    // Float, or the integer types quantising exporters use (KHR_gaussian_splatting allows
    // normalised rotations, scales and opacities), decoded with glTF's normalisation rules.
    let normalized = acc["normalized"].as_bool().unwrap_or(false);
    let (bytes, decode): (u64, Decode) = match acc["componentType"].as_u64() {
        Some(FLOAT) => (4, |b, _| f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        Some(5120) => (1, |b, n| {
            let v = f32::from(b[0] as i8);
            if n { (v / 127.0).max(-1.0) } else { v }
        }),
        Some(5121) => (1, |b, n| f32::from(b[0]) / if n { 255.0 } else { 1.0 }),
        Some(5122) => (2, |b, n| {
            let v = f32::from(i16::from_le_bytes([b[0], b[1]]));
            if n { (v / 32767.0).max(-1.0) } else { v }
        }),
        Some(5123) => {
            (2, |b, n| f32::from(u16::from_le_bytes([b[0], b[1]])) / if n { 65535.0 } else { 1.0 })
        }
        _ => {
            return Err(what(format!(
                "componentType {}: expected float (5126) or 8/16-bit integers (5120-5123)",
                acc["componentType"]
            )));
        }
    };
    let n = acc["count"].as_u64().ok_or_else(|| what("no count".into()))? as usize;
    if let Some(c) = count
        && n != c
    {
        return Err(what(format!("{n} elements, POSITION has {c}")));
    }
    #[allow(clippy::expect_used)]
    let width = components(kind).expect("checked above");
    if !acc["sparse"].is_null() {
        return Err(what("a sparse accessor, which trgs does not read".into()));
    }
    let view = &doc["bufferViews"][acc["bufferView"].as_u64().unwrap_or(u64::MAX) as usize];
    if view.is_null() {
        return Err(what("no bufferView".into()));
    }
    if view["buffer"].as_u64() != Some(0) {
        return Err(what("data outside the GLB's own buffer".into()));
    }
    let elem = width as u64 * bytes;
    let stride = view["byteStride"].as_u64().unwrap_or(elem);
    if stride < elem {
        return Err(what(format!("byteStride {stride} is below the element's {elem} bytes")));
    }
    // The whole range is checked before anything is allocated, so that a corrupt count or
    // offset gives this error instead of a huge allocation or an overflow.
    let start = view["byteOffset"]
        .as_u64()
        .unwrap_or(0)
        .checked_add(acc["byteOffset"].as_u64().unwrap_or(0));
    let span = (n as u64)
        .checked_sub(1)
        .map_or(Some(0), |last| last.checked_mul(stride)?.checked_add(elem));
    let in_bin = start
        .zip(span)
        .and_then(|(s, l)| s.checked_add(l))
        .is_some_and(|end| end <= bin.len() as u64);
    let (Some(start), true) = (start, in_bin) else {
        return Err(what(format!("{n} elements lie past the BIN chunk ({} bytes)", bin.len())));
    };
    let (start, stride, elem) = (start as usize, stride as usize, elem as usize);
    let mut out = Vec::with_capacity(n * width);
    for e in 0..n {
        let at = start + e * stride;
        for b in bin[at..at + elem].chunks_exact(bytes as usize) {
            out.push(decode(b, normalized));
        }
    }
    Ok((out, n))
}

fn vec3(v: &Value, field: &str) -> Result<DVec3, String> {
    let a: Vec<f64> =
        v[field].as_array().map_or(Vec::new(), |a| a.iter().filter_map(Value::as_f64).collect());
    match a[..] {
        [x, y, z] => Ok(DVec3::new(x, y, z)),
        _ => Err(format!("field {field:?} is not three numbers")),
    }
}

/// Plane number `plane` of the file, from the extras of node `node`.
fn plane_of(node: usize, plane: usize, extras: &Value) -> Result<ReflectionPlane, String> {
    let what = |m: String| format!("node {node} extras.trgs_plane: {m}");
    let number = |f: &str| extras[f].as_f64().ok_or_else(|| what(format!("no number {f:?}")));
    let material = match extras["material"].as_str() {
        Some("mirror") => Material::Mirror,
        Some("glass") | None => Material::Glass,
        Some(other) => return Err(what(format!("material {other:?}, expected glass or mirror"))),
    };
    let normal = vec3(extras, "normal").map_err(what)?;
    // Checked before the axis is orthogonalised against it, which a zero normal makes NaN.
    if !(normal.length() > 0.0 && normal.is_finite()) {
        return Err(what(format!("normal {normal} is zero or not finite")));
    }
    let mut p = ReflectionPlane::new(
        vec3(extras, "centre").map_err(what)?,
        normal,
        vec3(extras, "axis").map_err(what)?,
        number("width")?,
        number("height")?,
        material,
    );
    p.r0_logit = number("r0_logit")?;
    // The same checks as planes.json's reader: finite, a usable normal and axis, a positive size.
    p.validate(plane).map_err(|e| what(e.to_string()))?;
    Ok(p)
}

/// Parse a GLB; `path` names the file in errors.
pub fn parse_glb(
    bytes: &[u8],
    path: &Path,
) -> Result<(Gaussians<f32>, Vec<ReflectionPlane>), FormatError> {
    parse(bytes).map_err(|m| FormatError::new(path, m))
}

fn parse(bytes: &[u8]) -> Result<(Gaussians<f32>, Vec<ReflectionPlane>), String> {
    let (doc, bin) = chunks(bytes)?;
    for required in doc["extensionsRequired"].as_array().into_iter().flatten() {
        // KHR_mesh_quantization only allows the integer attributes read_accessor decodes.
        if !matches!(required.as_str(), Some(EXTENSION | "KHR_mesh_quantization")) {
            return Err(format!(
                "the file requires the extension {required}, which trgs does not read"
            ));
        }
    }
    let (mesh, primitive) = doc["meshes"]
        .as_array()
        .into_iter()
        .flatten()
        .enumerate()
        .flat_map(|(k, m)| m["primitives"].as_array().into_iter().flatten().map(move |p| (k, p)))
        .find(|(_, p)| !p["extensions"][EXTENSION].is_null())
        .ok_or_else(|| format!("no mesh primitive with the {EXTENSION} extension"))?;
    let to_trgs = placement::mesh_to_trgs(&doc, mesh)?;
    let ext = &primitive["extensions"][EXTENSION];
    if primitive["mode"].as_u64() != Some(MODE_POINTS) {
        return Err(format!("the {EXTENSION} primitive's mode must be 0 (POINTS)"));
    }
    for field in ["kernel", "colorSpace"] {
        if !ext[field].is_string() {
            return Err(format!("the {EXTENSION} object lacks its required {field:?}"));
        }
    }
    let attrs = Attributes { doc: &doc, bin, attrs: &primitive["attributes"] };
    let mut g = read_gaussians(&attrs)?;
    read_trgs_attributes(&attrs, &mut g)?;
    if let Some(m) = to_trgs {
        placement::place(&mut g, &m)?;
    }
    // After the placement, which moves, turns and scales what the file holds.
    check_gaussians(&g).map_err(|u| u.message(&attribute_name(u.field)))?;
    let mut planes = Vec::new();
    for (index, node) in doc["nodes"].as_array().into_iter().flatten().enumerate() {
        let extras = &node["extras"]["trgs_plane"];
        if !extras.is_null() {
            planes.push(plane_of(index, planes.len(), extras)?);
        }
    }
    Ok((g, planes))
}

/// The attributes of the splat primitive, read through its accessors.
struct Attributes<'a> {
    doc: &'a Value,
    bin: &'a [u8],
    attrs: &'a Value,
}

impl Attributes<'_> {
    /// The values of attribute `semantic` (one of `kinds`, `count` elements), None when the
    /// primitive lacks it.
    fn get(
        &self,
        semantic: &str,
        kinds: &[&str],
        count: Option<usize>,
    ) -> Result<Option<Vec<f32>>, String> {
        let index = &self.attrs[semantic];
        if index.is_null() {
            return Ok(None);
        }
        read_accessor(self.doc, self.bin, index, semantic, kinds, count).map(|(v, _)| Some(v))
    }

    /// As [`Attributes::get`], for an attribute the file must have.
    fn required(
        &self,
        semantic: &str,
        kinds: &[&str],
        count: Option<usize>,
    ) -> Result<Vec<f32>, String> {
        self.get(semantic, kinds, count)?.ok_or_else(|| format!("no {semantic} attribute"))
    }
}

/// The Gaussians of the standard attributes: positions, rotations, scales, opacities and SH.
fn read_gaussians(attrs: &Attributes<'_>) -> Result<Gaussians<f32>, String> {
    let (positions, n) = match &attrs.attrs["POSITION"] {
        Value::Null => return Err("no POSITION attribute".into()),
        index => read_accessor(attrs.doc, attrs.bin, index, "POSITION", &["VEC3"], None)?,
    };
    if n == 0 {
        return Err("POSITION has no elements".into());
    }
    let rot = attrs.required("KHR_gaussian_splatting:ROTATION", &["VEC4"], Some(n))?;
    let scale = attrs.required("KHR_gaussian_splatting:SCALE", &["VEC3"], Some(n))?;
    let opacity = attrs.required("KHR_gaussian_splatting:OPACITY", &["SCALAR"], Some(n))?;
    let bands = sh_bands(attrs, n)?;
    let degree = bands.len() as u32 - 1;
    let mut g = Gaussians::<f32>::zeros(n, degree);
    let coeffs = sh_coeff_count(degree);
    for (l, band) in bands.iter().enumerate() {
        for (order, values) in band.iter().enumerate() {
            for i in 0..n {
                let v = &values[3 * i..3 * i + 3];
                g.sh[i * coeffs + l * l + order] = [v[0], v[1], v[2]];
            }
        }
    }
    for i in 0..n {
        g.means[i] = [positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]];
        let q = &rot[4 * i..4 * i + 4];
        let norm2: f32 = q.iter().map(|v| v * v).sum();
        if !(norm2.is_finite() && norm2 > 0.0) {
            return Err(format!(
                "Gaussian {i}: rotation {q:?} (expected a finite, non-zero quaternion)"
            ));
        }
        g.rotations[i] = [q[3], q[0], q[1], q[2]];
        for a in 0..3 {
            let s = scale[3 * i + a];
            if !(s >= 0.0 && s.is_finite()) {
                return Err(format!("Gaussian {i}: scale {s} (expected finite and not negative)"));
            }
            // A zero scale (a flat splat, or one below f32's range written out as 0) becomes the
            // smallest normal f32: ln(0) would be an infinite log-scale, which the renderer refuses.
            let mut log = s.max(f32::MIN_POSITIVE).ln();
            // The ln of a scale within a rounding of f32::MAX can round up to where exp overflows.
            while !log.exp().is_finite() {
                log = log.next_down();
            }
            g.log_scales[i][a] = log;
        }
        let o = opacity[i];
        if !(0.0..=1.0).contains(&o) {
            return Err(format!("Gaussian {i}: opacity {o} outside [0, 1]"));
        }
        let o = o.clamp(1e-7, 1.0 - 1e-7);
        g.opacity_logits[i] = (o / (1.0 - o)).ln();
    }
    Ok(g)
}

/// The SH coefficients of `n` Gaussians, band by band (degree 0 first), each band's
/// coefficients in order: every coefficient of each degree up to the file's, none partly.
fn sh_bands(attrs: &Attributes<'_>, n: usize) -> Result<Vec<Vec<Vec<f32>>>, String> {
    let mut bands: Vec<Vec<Vec<f32>>> = Vec::new();
    for degree in 0..=3u32 {
        let mut band = Vec::new();
        for order in 0..2 * degree + 1 {
            let name = format!("KHR_gaussian_splatting:SH_DEGREE_{degree}_COEF_{order}");
            band.push(attrs.get(&name, &["VEC3"], Some(n))?);
        }
        match band.iter().filter(|c| c.is_some()).count() {
            0 => {
                // Degrees come in order: a higher one after a missing one is a broken file.
                let later = attrs.attrs.as_object().into_iter().flatten().find(|(name, _)| {
                    (degree + 1..=3)
                        .any(|d| name.starts_with(&format!("{EXTENSION}:SH_DEGREE_{d}_")))
                });
                if let Some((name, _)) = later {
                    return Err(format!("{name} is present but SH degree {degree} is not"));
                }
                break;
            }
            k if k == band.len() => bands.push(band.into_iter().flatten().collect()),
            k => return Err(format!("SH degree {degree} is partly defined ({k} coefficients)")),
        }
    }
    if bands.is_empty() {
        return Err("no KHR_gaussian_splatting:SH_DEGREE_0_COEF_0 attribute".into());
    }
    Ok(bands)
}

/// trgs's own attributes, where the file has them: they replace what the standard ones gave.
fn read_trgs_attributes(attrs: &Attributes<'_>, g: &mut Gaussians<f32>) -> Result<(), String> {
    let n = g.len();
    if let Some(v) = attrs.get("_TRGS_OPACITY_LOGIT", &["SCALAR"], Some(n))? {
        g.opacity_logits = v;
    }
    if let Some(v) = attrs.get("_TRGS_MASK_LOGIT", &["SCALAR"], Some(n))? {
        g.mask_logits = v;
    }
    if let Some(v) = attrs.get("_TRGS_LOG_REFLECTION", &["SCALAR"], Some(n))? {
        g.log_reflections = v;
    }
    if let Some(v) = attrs.get("_TRGS_POPULATION", &["SCALAR"], Some(n))? {
        g.populations = v
            .iter()
            .enumerate()
            .map(|(i, &p)| match p {
                0.0 => Ok(Population::Primary),
                1.0 => Ok(Population::Glass),
                _ => Err(format!("Gaussian {i}: _TRGS_POPULATION {p}, expected 0 or 1")),
            })
            .collect::<Result<_, _>>()?;
    }
    Ok(())
}

/// Decodes one component (its little-endian bytes; whether it is normalised) to f32.
type Decode = fn(&[u8], bool) -> f32;
