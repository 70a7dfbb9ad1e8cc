//! `planes.json`: one format for the input annotation (label and material of each masked plane)
//! and the trained planes (full geometry), e.g.
//! `{"planes": [{"label": 1, "material": "glass", "centre": [0, 0, 0], "normal": [0, 0, 1],
//! "axis": [1, 0, 0], "width": 1.2, "height": 0.8, "r0": 0.2}]}`.
//! The geometry fields come all together or not at all; `r0` defaults from the material.
use std::collections::HashSet;
use std::path::Path;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::error::read_text;
use super::{FormatError, write_atomic};
use crate::scene::{Material, ReflectionPlane};

/// One entry of `planes.json`: the mask label, the material and, for trained or hand-measured
/// planes, the geometry.
#[derive(Clone, Debug, PartialEq)]
pub struct PlaneSpec {
    pub label: u32,
    pub material: Material,
    pub plane: Option<ReflectionPlane>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PlanesFile {
    planes: Vec<PlaneEntry>,
}

/// Unknown fields are refused so that a typo (`"hieght"`) is an error rather than a silently
/// missing value; `center` is accepted as a spelling of `centre`.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PlaneEntry {
    label: u32,
    #[serde(default)]
    material: Material,
    #[serde(default, alias = "center", skip_serializing_if = "Option::is_none")]
    centre: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    normal: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    axis: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    width: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    height: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    r0: Option<f64>,
}

/// The largest base reflectance we store. A perfect mirror has R0 = 1, but R0 is learnt as
/// sigmoid(r0_logit) and logit(1) is infinite, which would put inf into the optimiser (and
/// sigmoid's gradient there is 0, so it could never learn away from it).
const MAX_R0: f64 = 0.999;

/// Read and check `planes.json`: labels are positive and unique, geometry is complete or absent,
/// every plane passes [`ReflectionPlane::validate`], `r0` is in (0, 1].
pub fn read_planes_json(path: &Path) -> Result<Vec<PlaneSpec>, FormatError> {
    let text = read_text(path)?;
    let file: PlanesFile = serde_json::from_str(&text).map_err(|e| {
        let expected =
            r#"expected planes.json: {"planes": [{"label": 1, "material": "glass", ...}]}"#;
        FormatError::new(path, format!("{e}; {expected}"))
    })?;
    let mut labels = HashSet::new();
    let mut out = Vec::with_capacity(file.planes.len());
    for (index, entry) in file.planes.iter().enumerate() {
        let fail = |what: String| {
            FormatError::new(path, format!("planes[{index}] (label {}): {what}", entry.label))
        };
        if entry.label == 0 {
            return Err(fail("label 0 means \"no plane\" in the masks; labels start at 1".into()));
        }
        if entry.label > 255 {
            return Err(fail("masks hold 8-bit labels: a label must be 1 to 255".into()));
        }
        if !labels.insert(entry.label) {
            return Err(fail(format!("label {} appears more than once", entry.label)));
        }
        let plane = plane_of(entry, index).map_err(fail)?;
        out.push(PlaneSpec { label: entry.label, material: entry.material, plane });
    }
    Ok(out)
}

fn plane_of(e: &PlaneEntry, index: usize) -> Result<Option<ReflectionPlane>, String> {
    let present = [
        ("centre", e.centre.is_some()),
        ("normal", e.normal.is_some()),
        ("axis", e.axis.is_some()),
        ("width", e.width.is_some()),
        ("height", e.height.is_some()),
    ];
    let (centre, normal, axis, width, height) = match (
        e.centre, e.normal, e.axis, e.width, e.height,
    ) {
        (Some(c), Some(n), Some(a), Some(w), Some(h)) => (c, n, a, w, h),
        (None, None, None, None, None) => {
            return match e.r0 {
                Some(_) => Err("r0 is given without the plane's geometry".into()),
                None => Ok(None),
            };
        }
        _ => {
            let missing =
                present.iter().filter(|p| !p.1).map(|p| p.0).collect::<Vec<_>>().join(", ");
            let given = present.iter().filter(|p| p.1).map(|p| p.0).collect::<Vec<_>>().join(", ");
            return Err(format!(
                "the geometry is incomplete: {missing} missing (given: {given}); give all of centre, \
                 normal, axis, width and height, or none"
            ));
        }
    };
    let r0 = match e.r0 {
        None => e.material.initial_r0(),
        Some(r) if r > 0.0 && r <= 1.0 => r.min(MAX_R0),
        Some(r) => return Err(format!("r0 = {r} is outside (0, 1]")),
    };
    let mut plane = ReflectionPlane {
        centre: DVec3::from_array(centre),
        normal: DVec3::from_array(normal),
        axis: DVec3::from_array(axis),
        width,
        height,
        r0_logit: (r0 / (1.0 - r0)).ln(),
        material: e.material,
    };
    if !plane.normal.is_finite() || !plane.axis.is_finite() || plane.normal.length_squared() < 1e-24
    {
        plane.validate(index).map_err(|err| err.to_string())?;
    }
    // Re-orthogonalise a roughly given axis as the trainer does after each step, but refuse one
    // along the normal: which in-plane direction was meant would be a guess.
    let n = plane.unit_normal();
    let in_plane = plane.axis - n * plane.axis.dot(n);
    if in_plane.length() <= 1e-6 * plane.axis.length().max(1e-300) {
        return Err("axis is parallel to the normal (it must lie in the plane)".into());
    }
    if (plane.axis.length() - 1.0).abs() > 1e-9 || plane.axis.dot(n).abs() > 1e-9 {
        plane.orthogonalise_axis();
    }
    plane.validate(index).map_err(|err| err.to_string())?;
    Ok(Some(plane))
}

/// Write trained planes, labelled 1..=N in order, with their full geometry and `r0`.
pub fn write_planes_json(path: &Path, planes: &[ReflectionPlane]) -> Result<(), FormatError> {
    let mut entries = Vec::with_capacity(planes.len());
    for (i, p) in planes.iter().enumerate() {
        p.validate(i).map_err(|e| FormatError::new(path, e.to_string()))?;
        entries.push(PlaneEntry {
            label: i as u32 + 1,
            material: p.material,
            centre: Some(p.centre.to_array()),
            normal: Some(p.normal.to_array()),
            axis: Some(p.axis.to_array()),
            width: Some(p.width),
            height: Some(p.height),
            r0: Some(p.r0()),
        });
    }
    let json = serde_json::to_string_pretty(&PlanesFile { planes: entries })
        .map_err(|e| FormatError::new(path, e.to_string()))?;
    write_atomic(path, format!("{json}\n").as_bytes())
}

/// Write the annotation form: each label's material and nothing else (the input of a scene folder,
/// where the geometry is estimated from the glass masks).
pub fn write_plane_materials(path: &Path, materials: &[Material]) -> Result<(), FormatError> {
    let entries: Vec<PlaneEntry> = materials
        .iter()
        .enumerate()
        .map(|(i, &material)| PlaneEntry {
            label: i as u32 + 1,
            material,
            centre: None,
            normal: None,
            axis: None,
            width: None,
            height: None,
            r0: None,
        })
        .collect();
    let json = serde_json::to_string_pretty(&PlanesFile { planes: entries })
        .map_err(|e| FormatError::new(path, e.to_string()))?;
    write_atomic(path, format!("{json}\n").as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::test_util::{assert_mentions, scratch_dir};

    #[test]
    fn materials_only_round_trip() {
        let dir = scratch_dir("planes-materials");
        let path = dir.join("planes.json");
        write_plane_materials(&path, &[Material::Glass, Material::Mirror]).expect("write");
        let specs = read_planes_json(&path).expect("read");
        assert_eq!(specs.len(), 2);
        assert_eq!(
            (specs[1].label, specs[1].material, specs[1].plane),
            (2, Material::Mirror, None)
        );
    }

    /// `json` in a planes.json of its own folder (kept while the returned guard lives).
    fn write(tag: &str, json: &str) -> (crate::scratch::ScratchDir, std::path::PathBuf) {
        let dir = scratch_dir(tag);
        let path = dir.join("planes.json");
        std::fs::write(&path, json).expect("write");
        (dir, path)
    }

    #[test]
    fn annotation_without_geometry() {
        let (_dir, path) = write(
            "planes-ann",
            r#"{"planes": [{"label": 2, "material": "mirror"}, {"label": 1}]}"#,
        );
        let specs = read_planes_json(&path).expect("read");
        assert_eq!(specs[0], PlaneSpec { label: 2, material: Material::Mirror, plane: None });
        assert_eq!(specs[1].material, Material::Glass);
    }

    #[test]
    fn trained_planes_round_trip() {
        let a = ReflectionPlane::new(
            DVec3::new(1.0, 2.0, 3.0),
            DVec3::new(0.0, 0.0, 2.0),
            DVec3::X,
            1.2,
            0.8,
            Material::Glass,
        );
        let mut b = ReflectionPlane::new(
            DVec3::ZERO,
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::Z,
            2.0,
            1.0,
            Material::Mirror,
        );
        b.r0_logit = 1.5;
        let dir = scratch_dir("planes-rt");
        let path = dir.join("planes.json");
        write_planes_json(&path, &[a, b]).expect("write");
        let specs = read_planes_json(&path).expect("read");
        assert_eq!(specs.iter().map(|s| s.label).collect::<Vec<_>>(), [1, 2]);
        for (spec, orig) in specs.iter().zip([a, b]) {
            let p = spec.plane.expect("geometry");
            assert_eq!(
                (p.centre, p.normal, p.axis, p.width, p.height),
                (orig.centre, orig.normal, orig.axis, orig.width, orig.height)
            );
            assert!((p.r0_logit - orig.r0_logit).abs() < 1e-9);
            assert_eq!(spec.material, orig.material);
        }
    }

    #[test]
    fn mirror_r0_of_one_is_clamped() {
        let (_dir, path) = write(
            "planes-r0",
            r#"{"planes": [{"label": 1, "material": "mirror", "center": [0,0,0], "normal": [0,0,1],
                "axis": [2,0,0.5], "width": 1, "height": 1, "r0": 1.0}]}"#,
        );
        let p = read_planes_json(&path).expect("read")[0].plane.expect("geometry");
        assert!((p.r0() - MAX_R0).abs() < 1e-12 && p.r0_logit.is_finite());
        assert!((p.axis - DVec3::X).length() < 1e-12, "axis re-orthogonalised: {}", p.axis);
    }

    #[test]
    fn missing_geometry_field_is_named() {
        let (_dir, path) = write(
            "planes-partial",
            r#"{"planes": [{"label": 1, "centre": [0,0,0], "normal": [0,0,1], "width": 1, "height": 1}]}"#,
        );
        let err = read_planes_json(&path).expect_err("no axis");
        assert_mentions(&err, &["planes.json", "planes[0]", "axis missing"]);
        let (_dir, path) = write("planes-nolabel", r#"{"planes": [{"material": "glass"}]}"#);
        assert_mentions(
            &read_planes_json(&path).expect_err("no label"),
            &["planes.json", "missing field `label`", "line 1"],
        );
        // An empty file (e.g. `--planes /dev/null`) says what the file should hold.
        let (_dir, path) = write("planes-empty", "");
        assert_mentions(
            &read_planes_json(&path).expect_err("empty"),
            &["planes.json", "EOF", r#"expected planes.json: {"planes": ["#],
        );
    }

    #[test]
    fn bad_planes_are_refused() {
        let geometry = r#""centre": [0,0,0], "normal": [0,0,1], "axis": [1,0,0], "height": 1"#;
        let (_dir, path) = write(
            "planes-zero",
            &format!(r#"{{"planes": [{{"label": 1, {geometry}, "width": 0}}]}}"#),
        );
        assert_mentions(
            &read_planes_json(&path).expect_err("zero area"),
            &["planes.json", "zero-area"],
        );
        let (_dir, path) = write("planes-dup", r#"{"planes": [{"label": 1}, {"label": 1}]}"#);
        assert_mentions(
            &read_planes_json(&path).expect_err("duplicate"),
            &["planes.json", "planes[1]", "more than once"],
        );
        let (_dir, path) = write("planes-big", r#"{"planes": [{"label": 256}]}"#);
        assert_mentions(
            &read_planes_json(&path).expect_err("label 256"),
            &["planes.json", "planes[0]", "1 to 255"],
        );
        let (_dir, path) = write("planes-typo", r#"{"planes": [{"label": 1, "hieght": 2}]}"#);
        assert_mentions(
            &read_planes_json(&path).expect_err("typo"),
            &["planes.json", "unknown field `hieght`"],
        );
        let (_dir, path) =
            write("planes-wood", r#"{"planes": [{"label": 1, "material": "wood"}]}"#);
        assert_mentions(
            &read_planes_json(&path).expect_err("wood"),
            &["planes.json", "unknown variant `wood`"],
        );
        let (_dir, path) = write(
            "planes-par",
            r#"{"planes": [{"label": 1, "centre": [0,0,0], "normal": [0,0,1], "axis": [0,0,3],
                "width": 1, "height": 1}]}"#,
        );
        assert_mentions(
            &read_planes_json(&path).expect_err("parallel"),
            &["planes.json", "parallel"],
        );
        let (_dir, path) = write(
            "planes-r0",
            &format!(r#"{{"planes": [{{"label": 1, {geometry}, "width": 1, "r0": 1.5}}]}}"#),
        );
        assert_mentions(&read_planes_json(&path).expect_err("r0"), &["planes.json", "r0 = 1.5"]);
        let (_dir, path) = write("planes-syntax", "{\"planes\": [\n{\"label\": 1,}]}");
        assert_mentions(&read_planes_json(&path).expect_err("syntax"), &["planes.json", "line 2"]);
    }
}
