//! Stage `regularisers` (the CPU twin of the WGSL stage of that name): the paper's regularisers
//! (section 3.3), each as its value and dL/d(layer):
//! - `mask_loss`: L_m = mean |M - M_a| on annotated views;
//! - `depth_variance_loss`: L_d = mean H V, with V = sum |z - D_t| w the renderer's layer;
//! - `gradient_conflict_loss`: L_c = mean H |grad C_t . sg(grad C_r)|, per channel the dot
//!   product of the two images' Sobel derivative estimates (kernel / 8, units per pixel), on
//!   interior pixels (no padding) whose whole 3x3 window hits the same plane (C_r is zero off
//!   the rectangle: a window across its outline would see a step no reflection has).
//!
//! [`regularisers`] weights and combines the three as the GPU stage does: it writes the direct
//! gradients of the transmission layer (C_t, alpha) and of the geometry layer (D_t, V, M).
use crate::image::Image;
use crate::pipeline::RegulariserWeights;

/// A regulariser's value and its gradient with respect to one layer.
#[derive(Clone, Debug)]
pub struct LayerLoss {
    pub value: f64,
    pub grad: Image<f64>,
}

/// L_m for the rendered mask `m` (one channel) and the annotation (label > 0 is glass).
pub fn mask_loss(m: &Image<f64>, annotation: &Image<u8>, covered: Option<&Image<u8>>) -> LayerLoss {
    let n = m.data.len().max(1) as f64;
    let mut grad = Image::<f64>::new(m.width, m.height, 1);
    let mut value = 0.0;
    for (i, ((g, &v), &a)) in grad.data.iter_mut().zip(&m.data).zip(&annotation.data).enumerate() {
        // A pixel without a source in the photo has no label either.
        if covered.is_some_and(|c| c.data[i] == 0) {
            continue;
        }
        let d = v - if a > 0 { 1.0 } else { 0.0 };
        value += d.abs();
        *g = d.signum() * f64::from(u8::from(d != 0.0)) / n;
    }
    LayerLoss { value: value / n, grad }
}

/// L_d for the depth-variance layer `v` and the hit mask `hit` (nonzero: a plane's pixel).
pub fn depth_variance_loss(v: &Image<f64>, hit: &Image<u32>) -> LayerLoss {
    let n = v.data.len().max(1) as f64;
    let mut grad = Image::<f64>::new(v.width, v.height, 1);
    let mut value = 0.0;
    for ((g, &x), &h) in grad.data.iter_mut().zip(&v.data).zip(&hit.data) {
        if h != 0 {
            value += x;
            *g = 1.0 / n;
        }
    }
    LayerLoss { value: value / n, grad }
}

// Sobel derivative estimates: the kernels over 8, so that a ramp of 1 per pixel gives 1. (With
// the raw kernels, L_c would be 64 times stronger at the paper's weight 0.2; at that strength it
// flattened the transmission's own edges wherever the reflection had any.)
const SOBEL_X: [[f64; 3]; 3] = [[-0.125, 0.0, 0.125], [-0.25, 0.0, 0.25], [-0.125, 0.0, 0.125]];
const SOBEL_Y: [[f64; 3]; 3] = [[-0.125, -0.25, -0.125], [0.0, 0.0, 0.0], [0.125, 0.25, 0.125]];

fn sobel(im: &Image<f64>, k: &[[f64; 3]; 3], x: usize, y: usize, c: usize) -> f64 {
    let (w, ch) = (im.width as usize, im.channels as usize);
    let mut s = 0.0;
    for (dy, row) in k.iter().enumerate() {
        for (dx, &kv) in row.iter().enumerate() {
            s += kv * im.data[((y + dy - 1) * w + x + dx - 1) * ch + c];
        }
    }
    s
}

/// L_c between the transmission `ct` and the reflection `cr` (3 channels each) under the hit
/// mask; the gradient is with respect to `ct` only (the reflection side is stop-gradient).
pub fn gradient_conflict_loss(ct: &Image<f64>, cr: &Image<f64>, hit: &Image<u32>) -> LayerLoss {
    let (w, h, ch) = (ct.width as usize, ct.height as usize, ct.channels as usize);
    let n = (w * h * ch).max(1) as f64;
    let mut grad = Image::<f64>::new(ct.width, ct.height, ct.channels);
    let mut value = 0.0;
    if w < 3 || h < 3 {
        return LayerLoss { value, grad };
    }
    // The whole window on one plane (see the module comment).
    let counts = |x: usize, y: usize| {
        let plane = hit.data[y * w + x];
        plane != 0 && (0..9).all(|k| hit.data[(y + k / 3 - 1) * w + x + k % 3 - 1] == plane)
    };
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            if !counts(x, y) {
                continue;
            }
            for c in 0..ch {
                let (gtx, gty) = (sobel(ct, &SOBEL_X, x, y, c), sobel(ct, &SOBEL_Y, x, y, c));
                let (grx, gry) = (sobel(cr, &SOBEL_X, x, y, c), sobel(cr, &SOBEL_Y, x, y, c));
                let dot = gtx * grx + gty * gry;
                value += dot.abs();
                if dot == 0.0 {
                    continue;
                }
                // d|g^t . g^r|/d g^t_k = sign(dot) g^r_k, then the Sobel correlations' adjoints.
                let (up_x, up_y) = (dot.signum() * grx / n, dot.signum() * gry / n);
                for dy in 0..3 {
                    for dx in 0..3 {
                        grad.data[((y + dy - 1) * w + x + dx - 1) * ch + c] +=
                            SOBEL_X[dy][dx] * up_x + SOBEL_Y[dy][dx] * up_y;
                    }
                }
            }
        }
    }
    LayerLoss { value: value / n, grad }
}

/// What stage `regularisers` reads: the frame's layers and the view's annotation.
#[derive(Clone, Copy, Debug)]
pub struct RegulariserInputs<'a> {
    /// C_t (3 channels).
    pub transmission: &'a Image<f64>,
    /// C_r (3 channels).
    pub reflection: &'a Image<f64>,
    /// V (1 channel).
    pub depth_variance: &'a Image<f64>,
    /// M (1 channel).
    pub mask: &'a Image<f64>,
    /// The plane hit by each pixel's ray (0: none).
    pub hit: &'a Image<u32>,
    /// The view's glass labels, when it has them.
    pub annotation: Option<&'a Image<u8>>,
    /// Which pixels the photo covers (nonzero), when not all: L_m skips the others. L_d and L_c
    /// are priors on the model's layers, not comparisons with the photo, and count everywhere.
    pub covered: Option<&'a Image<u8>>,
}

/// The unweighted values and the weighted direct gradients of stage `regularisers`.
#[derive(Clone, Debug)]
pub struct Regularisers {
    pub depth: f64,
    pub conflict: f64,
    pub mask: f64,
    /// dL/d(C_t) (3 channels; the alpha channel's gradient is zero).
    pub transmission: Image<f64>,
    /// dL/d(V) (1 channel).
    pub depth_variance: Image<f64>,
    /// dL/d(M) (1 channel).
    pub mask_grad: Image<f64>,
}

/// Stage `regularisers`: `w.depth L_d + w.conflict L_c + w.mask L_m` (L_m on annotated views).
pub fn regularisers(inputs: &RegulariserInputs<'_>, w: RegulariserWeights) -> Regularisers {
    let scaled = |l: LayerLoss, weight: f64| {
        let mut grad = l.grad;
        grad.data.iter_mut().for_each(|g| *g *= weight);
        (l.value, grad)
    };
    let (depth, depth_variance) =
        scaled(depth_variance_loss(inputs.depth_variance, inputs.hit), w.depth);
    let (conflict, transmission) = scaled(
        gradient_conflict_loss(inputs.transmission, inputs.reflection, inputs.hit),
        w.conflict,
    );
    let (mask, mask_grad) = match inputs.annotation {
        Some(a) => scaled(mask_loss(inputs.mask, a, inputs.covered), w.mask),
        None => (0.0, Image::new(inputs.mask.width, inputs.mask.height, 1)),
    };
    Regularisers { depth, conflict, mask, transmission, depth_variance, mask_grad }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn conflict_gradient_matches_central_differences() {
        let mut rng = Rng::new(4);
        let (w, h) = (9, 7);
        let mut ct = Image::<f64>::new(w, h, 3);
        let mut cr = Image::<f64>::new(w, h, 3);
        for v in ct.data.iter_mut().chain(cr.data.iter_mut()) {
            *v = rng.uniform();
        }
        // Plane 1 over most of the image, plane 2 in its lower right corner: windows inside
        // either count, windows across an outline do not.
        let mut hit = Image::<u32>::new(w, h, 1);
        for (i, v) in hit.data.iter_mut().enumerate() {
            let (x, y) = (i % w as usize, i / w as usize);
            *v = match (x, y) {
                (0, _) | (_, 0) => 0,
                (5.., 4..) => 2,
                _ => 1,
            };
        }
        let l = gradient_conflict_loss(&ct, &cr, &hit);
        assert!(l.value > 0.0, "some windows count");
        let eps = 1e-7;
        for k in 0..ct.data.len() {
            let mut p = ct.clone();
            p.data[k] += eps;
            let mut m = ct.clone();
            m.data[k] -= eps;
            let fd = (gradient_conflict_loss(&p, &cr, &hit).value
                - gradient_conflict_loss(&m, &cr, &hit).value)
                / (2.0 * eps);
            assert!((fd - l.grad.data[k]).abs() < 1e-6, "sample {k}: {fd} vs {}", l.grad.data[k]);
        }
    }

    #[test]
    fn the_rectangle_outline_is_no_conflict() {
        // C_r constant on the plane and zero off it (as the mirrored pass leaves it), C_t with
        // an edge everywhere: the only gradient of C_r is the outline, which is no reflection.
        let (w, h) = (10, 8);
        let mut ct = Image::<f64>::new(w, h, 3);
        let mut cr = Image::<f64>::new(w, h, 3);
        let mut hit = Image::<u32>::new(w, h, 1);
        for y in 0..h as usize {
            for x in 0..w as usize {
                let on = (2..8).contains(&x) && (2..6).contains(&y);
                hit.data[y * w as usize + x] = u32::from(on);
                for c in 0..3 {
                    ct.data[(y * w as usize + x) * 3 + c] = (x + 2 * y) as f64 * 0.1;
                    cr.data[(y * w as usize + x) * 3 + c] = if on { 0.75 } else { 0.0 };
                }
            }
        }
        let l = gradient_conflict_loss(&ct, &cr, &hit);
        assert_eq!(l.value, 0.0);
        assert!(l.grad.data.iter().all(|&g| g == 0.0));
    }

    #[test]
    fn the_weighted_stage_gradients_match_central_differences() {
        // Every input the stage differentiates (C_t, V, M), through the weighted total, with
        // two planes, a border off every plane, an annotation and an uncovered corner.
        let mut rng = Rng::new(9);
        let (w, h) = (8, 6);
        let random = |ch: u32, rng: &mut Rng| {
            let mut im = Image::<f64>::new(w, h, ch);
            im.data.iter_mut().for_each(|v| *v = 0.05 + 0.9 * rng.uniform());
            im
        };
        let (ct, cr, v, m) =
            (random(3, &mut rng), random(3, &mut rng), random(1, &mut rng), random(1, &mut rng));
        let mut hit = Image::<u32>::new(w, h, 1);
        let mut annotation = Image::<u8>::new(w, h, 1);
        let mut covered = Image::<u8>::new(w, h, 1);
        for i in 0..(w * h) as usize {
            let (x, y) = (i % w as usize, i / w as usize);
            hit.data[i] = match (x, y) {
                (0, _) | (_, 0) => 0,
                (5.., 3..) => 2,
                _ => 1,
            };
            annotation.data[i] = u8::from(x > 2);
            covered.data[i] = u8::from(!(x < 2 && y < 2));
        }
        let weights = RegulariserWeights { depth: 0.005, conflict: 0.2, mask: 0.5 };
        let total = |ct: &Image<f64>, v: &Image<f64>, m: &Image<f64>| {
            let inputs = RegulariserInputs {
                transmission: ct,
                reflection: &cr,
                depth_variance: v,
                mask: m,
                hit: &hit,
                annotation: Some(&annotation),
                covered: Some(&covered),
            };
            let r = regularisers(&inputs, weights);
            (weights.depth * r.depth + weights.conflict * r.conflict + weights.mask * r.mask, r)
        };
        let (_, r) = total(&ct, &v, &m);
        let eps = 1e-6;
        let check = |name: &str,
                     at: &Image<f64>,
                     grad: &Image<f64>,
                     f: &dyn Fn(&Image<f64>) -> f64| {
            for k in 0..at.data.len() {
                let (mut p, mut n) = (at.clone(), at.clone());
                p.data[k] += eps;
                n.data[k] -= eps;
                let fd = (f(&p) - f(&n)) / (2.0 * eps);
                assert!((fd - grad.data[k]).abs() < 1e-7, "{name} {k}: {fd} vs {}", grad.data[k]);
            }
        };
        check("C_t", &ct, &r.transmission, &|x| total(x, &v, &m).0);
        check("V", &v, &r.depth_variance, &|x| total(&ct, x, &m).0);
        check("M", &m, &r.mask_grad, &|x| total(&ct, &v, x).0);
    }

    #[test]
    fn mask_and_depth_losses() {
        let mut m = Image::<f64>::new(2, 1, 1);
        m.data = vec![0.25, 0.5];
        let mut a = Image::<u8>::new(2, 1, 1);
        a.data = vec![1, 0];
        let l = mask_loss(&m, &a, None);
        assert!((l.value - 0.625).abs() < 1e-12);
        assert_eq!(l.grad.data, vec![-0.5, 0.5]);
        // A pixel the photo does not cover has no label: no loss, no gradient.
        let mut covered = Image::<u8>::new(2, 1, 1);
        covered.data = vec![1, 0];
        let l = mask_loss(&m, &a, Some(&covered));
        assert!((l.value - 0.375).abs() < 1e-12);
        assert_eq!(l.grad.data, vec![-0.5, 0.0]);
        let mut hit = Image::<u32>::new(2, 1, 1);
        hit.data = vec![0, 2];
        let d = depth_variance_loss(&m, &hit);
        assert!((d.value - 0.25).abs() < 1e-12);
        assert_eq!(d.grad.data, vec![0.0, 0.5]);
    }
}
