//! What a plane carries when it moves. A Gaussian that no camera sees directly is seen only as its
//! mirror image about the plane that shows it (the reflection seeds and what grew from them).
//! When a refit moves that plane, the mirror images the photos trained would move by twice the
//! step; moved with the plane by [`PlaneCarry`], the Gaussian keeps its image where it was.
use crate::bake::sh_reflect::ShTransform;
use crate::plane_math::{householder, reflect_point};
use crate::scene::{Gaussians, ReflectionPlane, Scalar};
use glam::{DMat3, DQuat, DVec3};

/// Below this angle (radians) between the two planes' normals the carry is a pure shift, and the
/// rotations and SH colours stay as they are.
const SAME_NORMAL: f64 = 1e-9;

/// The rigid map `x -> M x + t` that keeps a point's mirror image when its plane moves from
/// `from` to `to`: the reflection about `from`, then about `to` (a rotation by twice the angle
/// between the normals, and a shift by twice the step along a shared normal).
#[derive(Clone, Debug)]
pub struct PlaneCarry {
    linear: DMat3,
    shift: DVec3,
    /// Whether the map turns (the normals differ): else the rotations and colours stay.
    turns: bool,
    /// `c'(d) = c(M^T d)` for SH colours above degree 0, where the map turns.
    sh: Option<ShTransform>,
}

impl PlaneCarry {
    /// The carry from `from` to `to` of Gaussians with SH of degree `sh_degree`.
    pub fn between(from: &ReflectionPlane, to: &ReflectionPlane, sh_degree: u32) -> Self {
        let linear = householder(to.unit_normal()) * householder(from.unit_normal());
        let shift = reflect_point(to, reflect_point(from, DVec3::ZERO));
        let turns = from.unit_normal().angle_between(to.unit_normal()) > SAME_NORMAL;
        let sh = (turns && sh_degree > 0).then(|| ShTransform::new(sh_degree, linear.transpose()));
        Self { linear, shift, turns, sh }
    }

    /// Where the carry takes point `x`.
    pub fn point(&self, x: DVec3) -> DVec3 {
        self.linear * x + self.shift
    }

    /// Whether the carry moves anything: the two planes differ as planes, not only in their
    /// rectangles (a rectangle moved within its plane keeps every mirror image).
    pub fn moves(&self) -> bool {
        const STILL: f64 = 1e-12;
        self.turns || self.shift.length() > STILL
    }

    /// The linear part `M` (a rotation): what the carry does to directions.
    pub fn linear(&self) -> DMat3 {
        self.linear
    }

    /// Carry Gaussian `i` of `g`: its mean, its rotation (turned by `M`, unnormalised as stored)
    /// and its SH colour (as seen from directions turned by `M`).
    pub fn apply<F: Scalar>(&self, g: &mut Gaussians<F>, i: usize) {
        let mean = DVec3::from_array(g.means[i].map(Scalar::to_f64));
        g.means[i] = self.point(mean).to_array().map(F::from_f64);
        if !self.turns {
            return;
        }
        let turn = DQuat::from_mat3(&self.linear);
        let [w, x, y, z] = g.rotations[i].map(Scalar::to_f64);
        let q = turn * DQuat::from_xyzw(x, y, z, w);
        g.rotations[i] = [q.w, q.x, q.y, q.z].map(F::from_f64);
        let Some(sh) = &self.sh else { return };
        let k = g.sh_coeffs();
        let coeffs: Vec<[f64; 3]> =
            g.sh[i * k..(i + 1) * k].iter().map(|c| c.map(Scalar::to_f64)).collect();
        for (dst, src) in g.sh[i * k..(i + 1) * k].iter_mut().zip(sh.apply(&coeffs)) {
            *dst = src.map(F::from_f64);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Material;

    #[test]
    fn a_rectangle_moved_within_its_plane_carries_nothing() {
        let n = DVec3::new(0.1, -0.2, 1.0).normalize();
        let axis = n.cross(DVec3::Y).normalize();
        let plane =
            ReflectionPlane::new(DVec3::new(0.3, 1.0, 2.0), n, axis, 1.6, 1.0, Material::Glass);
        let within = ReflectionPlane { centre: plane.centre + 0.2 * axis, width: 1.2, ..plane };
        assert!(!PlaneCarry::between(&plane, &within, 3).moves());
        let stepped = ReflectionPlane { centre: plane.centre - 0.04 * n, ..plane };
        let carry = PlaneCarry::between(&plane, &stepped, 3);
        assert!(carry.moves());
        // A step along the normal moves what the plane shows by twice the step, the same way.
        let x = DVec3::new(1.0, 0.5, 3.0);
        assert!((carry.point(x) - (x - 0.08 * n)).length() < 1e-12);
    }
}
