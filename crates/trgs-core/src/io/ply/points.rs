//! Point clouds as PLY (`x y z` and optional `red green blue`), as nerfstudio writes its sparse
//! points (`sparse_pc.ply`) and COLMAP its `points3D.ply`: the seeds of a transforms.json scene.
//! As for Gaussians, data after the elements the header declares is refused.
use std::collections::HashMap;
use std::path::Path;

use super::end::check_end;
use super::header::ScalarType;
use super::vertex_section;
use crate::io::FormatError;
use crate::io::error::read_bytes;

/// A sparse point: position and colour.
pub type ColouredPoint = ([f64; 3], [u8; 3]);

/// The vertices of a point-cloud PLY: positions (required, finite) and colours (`red green blue`
/// as 8-bit values, or floats in [0, 1]; grey when absent).
pub fn read_point_cloud_ply(path: &Path) -> Result<Vec<ColouredPoint>, FormatError> {
    let bytes = read_bytes(path)?;
    let fail = |m: String| FormatError::new(path, m);
    let (mut body, header, index) = vertex_section(&bytes, "one per point").map_err(fail)?;
    let vertex = &header.elements[index];
    let names = ["x", "y", "z", "red", "green", "blue"];
    let slot: HashMap<&str, usize> = names.iter().enumerate().map(|(i, n)| (*n, i)).collect();
    let mut found = [None::<ScalarType>; 6];
    for p in &vertex.properties {
        if let Some(&s) = slot.get(p.name.as_str())
            && p.list_count.is_none()
        {
            found[s] = Some(p.ty);
        }
    }
    if let Some(missing) = names[..3].iter().zip(&found).find(|(_, f)| f.is_none()) {
        return Err(fail(format!(
            "vertex property `{}` is missing; a point cloud needs x, y, z",
            missing.0
        )));
    }
    let colour_scale = |ty: Option<ScalarType>| match ty {
        Some(ScalarType::F32 | ScalarType::F64) => 255.0,
        Some(ScalarType::U16) => 255.0 / 65535.0,
        _ => 1.0,
    };
    let n = vertex.count;
    let bound = body.remaining() / vertex.properties.len().max(1);
    let mut out = Vec::with_capacity(usize::try_from(n).map_or(bound, |n| n.min(bound)));
    for i in 0..n {
        let mut row = [0.0f64, 0.0, 0.0, 128.0, 128.0, 128.0];
        for p in &vertex.properties {
            let what = || format!("vertex {i} of {n}: property {}", p.name);
            let count = match p.list_count {
                Some(ty) => body.count(ty, &what).map_err(fail)?,
                None => 1,
            };
            for _ in 0..count {
                let v = body.scalar(p.ty, &what).map_err(fail)?;
                if p.list_count.is_none()
                    && let Some(&s) = slot.get(p.name.as_str())
                {
                    row[s] = if s >= 3 { v * colour_scale(found[s]) } else { v };
                }
            }
        }
        if !row[..3].iter().all(|v| v.is_finite()) {
            return Err(fail(format!(
                "vertex {i} has a position that is not finite: {:?}",
                &row[..3]
            )));
        }
        let colour = [row[3], row[4], row[5]].map(|c| c.round().clamp(0.0, 255.0) as u8);
        out.push(([row[0], row[1], row[2]], colour));
    }
    check_end(&mut body, &header.elements[index + 1..], &header.elements).map_err(fail)?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::test_util::{assert_mentions, scratch_dir};

    #[test]
    fn ascii_and_binary_clouds_with_and_without_colour() {
        let dir = scratch_dir("ply-points");
        let path = dir.join("sparse_pc.ply");
        let ascii = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
                     property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n\
                     end_header\n1 2 3 255 0 10\n-1 0.5 2 0 128 0\n";
        std::fs::write(&path, ascii).expect("write");
        let points = read_point_cloud_ply(&path).expect("ascii");
        assert_eq!(points, vec![([1.0, 2.0, 3.0], [255, 0, 10]), ([-1.0, 0.5, 2.0], [0, 128, 0])]);
        // Binary little-endian doubles with float colours in [0, 1], and an extra property.
        let mut bytes = b"ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty double x\n\
                          property double y\nproperty double z\nproperty float nx\n\
                          property float red\nproperty float green\nproperty float blue\nend_header\n"
            .to_vec();
        for v in [0.5f64, 1.5, 2.5] {
            bytes.extend(v.to_le_bytes());
        }
        for v in [0.0f32, 1.0, 0.5, 0.0] {
            bytes.extend(v.to_le_bytes());
        }
        std::fs::write(&path, &bytes).expect("write");
        assert_eq!(
            read_point_cloud_ply(&path).expect("binary"),
            vec![([0.5, 1.5, 2.5], [255, 128, 0])]
        );
        // No colour: grey.
        let plain = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                     property float z\nend_header\n0 0 1\n";
        std::fs::write(&path, plain).expect("write");
        assert_eq!(read_point_cloud_ply(&path).expect("plain"), vec![([0.0, 0.0, 1.0], [128; 3])]);
    }

    #[test]
    fn missing_positions_and_nan_are_named() {
        let dir = scratch_dir("ply-points-bad");
        let path = dir.join("pc.ply");
        let no_z = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                    end_header\n0 0\n";
        std::fs::write(&path, no_z).expect("write");
        assert_mentions(&read_point_cloud_ply(&path).expect_err("no z"), &["pc.ply", "`z`"]);
        let nan = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                   property float z\nend_header\n0 nan 1\n";
        std::fs::write(&path, nan).expect("write");
        assert_mentions(&read_point_cloud_ply(&path).expect_err("nan"), &["pc.ply", "vertex 0"]);
        let more = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                    property float z\nend_header\n0 0 1\n1 1 1\n";
        std::fs::write(&path, more).expect("write");
        let err = read_point_cloud_ply(&path).expect_err("a point more than declared");
        assert_mentions(&err, &["pc.ply", "element vertex 1", "3 values on 1 line"]);
    }
}
