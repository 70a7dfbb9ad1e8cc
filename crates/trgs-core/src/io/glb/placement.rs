//! Where a `.glb`'s Gaussians are: the splat mesh's node transform (with its parents') and the
//! glTF-to-trgs flip, applied to means, rotations, scales and, for axis flips, SH coefficients.
use glam::{DMat3, DMat4, DQuat, DVec3};
use serde_json::Value;

use crate::scene::Gaussians;

/// glTF (y up, z backward) to trgs's frame (y down, z forward): 180 degrees about x, the
/// inverse of the root node `encode_glb` writes.
pub(super) const GLTF_TO_TRGS: DMat4 = DMat4::from_cols_array(&[
    1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
]);

/// The transform from the splat mesh's local frame to trgs's frame: its node's world transform
/// (the KHR extension places Gaussians in their node's frame), then glTF to trgs. None when that
/// is the identity, as in trgs's own files (their root node undoes the conversion).
pub(super) fn mesh_to_trgs(doc: &Value, mesh: usize) -> Result<Option<DMat4>, String> {
    let nodes = doc["nodes"].as_array().map_or(&[][..], Vec::as_slice);
    // A mesh no node places is in glTF's frame as it stands.
    let Some(mut node) = nodes.iter().position(|n| n["mesh"].as_u64() == Some(mesh as u64)) else {
        return Ok(Some(GLTF_TO_TRGS));
    };
    let parent_of = |child: usize| {
        nodes.iter().position(|n| {
            n["children"].as_array().into_iter().flatten().any(|c| c.as_u64() == Some(child as u64))
        })
    };
    let mut world = DMat4::IDENTITY;
    for _ in 0..=nodes.len() {
        world = local_matrix(&nodes[node]).map_err(|m| format!("node {node}: {m}"))? * world;
        match parent_of(node) {
            Some(p) => node = p,
            None => {
                let m = GLTF_TO_TRGS * world;
                let identity = m.abs_diff_eq(DMat4::IDENTITY, 1e-9);
                return Ok((!identity).then_some(m));
            }
        }
    }
    Err("the node hierarchy has a cycle".into())
}

/// A node's own transform: `matrix`, or translation, rotation (x y z w) and scale.
fn local_matrix(node: &Value) -> Result<DMat4, String> {
    let numbers = |field: &str, n: usize| -> Result<Option<Vec<f64>>, String> {
        match &node[field] {
            Value::Null => Ok(None),
            v => {
                let a: Vec<f64> =
                    v.as_array().into_iter().flatten().filter_map(Value::as_f64).collect();
                if a.len() != n || !a.iter().all(|x| x.is_finite()) {
                    return Err(format!("{field} must be {n} finite numbers, found {v}"));
                }
                Ok(Some(a))
            }
        }
    };
    if let Some(m) = numbers("matrix", 16)? {
        let mut cols = [0.0; 16];
        cols.copy_from_slice(&m);
        return Ok(DMat4::from_cols_array(&cols));
    }
    let t = numbers("translation", 3)?.map_or(DVec3::ZERO, |v| DVec3::new(v[0], v[1], v[2]));
    let r = numbers("rotation", 4)?
        .map_or(DQuat::IDENTITY, |v| DQuat::from_xyzw(v[0], v[1], v[2], v[3]));
    let s = numbers("scale", 3)?.map_or(DVec3::ONE, |v| DVec3::new(v[0], v[1], v[2]));
    if !(r.length() > 1e-9) {
        return Err("rotation is a zero quaternion".into());
    }
    Ok(DMat4::from_scale_rotation_translation(s, r.normalize(), t))
}

/// Move Gaussians by `m`, a rotation, a uniform scale and a translation: means, rotations and
/// log-scales exactly; SH coefficients of degree 1 and up only for a rotation that maps the axes
/// onto themselves up to sign (the glTF/trgs flip and its like), where the rotated coefficients
/// are the same ones with signs. Shear, non-uniform scale and other rotations with view-dependent
/// colour are refused rather than rendered wrong.
pub(super) fn place(g: &mut Gaussians<f32>, m: &DMat4) -> Result<(), String> {
    let l = DMat3::from_mat4(*m);
    let det = l.determinant();
    let s = det.cbrt();
    let r = l * (1.0 / s);
    if !(det > 0.0) || !(r.transpose() * r).abs_diff_eq(DMat3::IDENTITY, 1e-6) {
        return Err(
            "the Gaussians' node transform has a non-uniform scale, a shear or a reflection, \
             which trgs cannot apply to Gaussians: bake it into the data"
                .into(),
        );
    }
    // A rotation that maps each axis onto itself up to sign turns every real SH basis function
    // into itself up to sign (`sh_flip_sign`).
    let flips = [r.x_axis, r.y_axis, r.z_axis];
    let axis_sign = |a: usize| -> Option<f64> {
        let col = flips[a];
        let sign = col[a];
        (sign.abs() > 1.0 - 1e-9).then_some(sign.signum())
    };
    if g.sh_degree > 0 {
        let signs = [axis_sign(0), axis_sign(1), axis_sign(2)];
        let [Some(sx), Some(sy), Some(sz)] = signs else {
            return Err(format!(
                "the Gaussians' node rotates them, and trgs rotates SH of degree {} only by \
                 axis flips: bake the rotation into the data or export SH degree 0",
                g.sh_degree
            ));
        };
        let k = g.sh_coeffs();
        for l in 1..=g.sh_degree as usize {
            for n in 0..2 * l + 1 {
                let sign = sh_flip_sign(l as i64, n as i64 - l as i64, sx, sy, sz);
                if sign < 0.0 {
                    for i in 0..g.len() {
                        let c = &mut g.sh[i * k + l * l + n];
                        *c = c.map(|v| -v);
                    }
                }
            }
        }
    }
    let q = DQuat::from_mat3(&r);
    let t = m.w_axis.truncate();
    for i in 0..g.len() {
        let p = DVec3::from_array(g.means[i].map(f64::from));
        g.means[i] = (l * p + t).to_array().map(|v| v as f32);
        let [w, x, y, z] = g.rotations[i].map(f64::from);
        let turned = q * DQuat::from_xyzw(x, y, z, w);
        g.rotations[i] = [turned.w, turned.x, turned.y, turned.z].map(|v| v as f32);
        for v in &mut g.log_scales[i] {
            *v += s.ln() as f32;
        }
    }
    Ok(())
}

/// The sign of the real SH basis function of degree `l` and order `m` when each axis is flipped
/// by `sx`, `sy`, `sz` (+1 or -1). Y_lm is a sum of monomials x^a y^b z^c of one parity per axis:
/// its azimuthal part Re or Im of (x + iy)^|m| gives b odd iff m < 0 and a + b of the parity of
/// |m|; its polar part gives c of the parity of l - |m|.
fn sh_flip_sign(l: i64, m: i64, sx: f64, sy: f64, sz: f64) -> f64 {
    let b_odd = m < 0;
    let ab_odd = m.abs() % 2 == 1;
    let a_odd = ab_odd != b_odd;
    let c_odd = (l % 2 == 1) != ab_odd;
    let f = |odd: bool, s: f64| if odd { s } else { 1.0 };
    f(a_odd, sx) * f(b_odd, sy) * f(c_odd, sz)
}
