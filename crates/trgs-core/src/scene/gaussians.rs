//! Gaussians in structure-of-arrays form: one `Vec` per attribute, as the GPU buffers hold them.

/// The scalar a [`Gaussians`] set is stored in: `f32` for models and GPU buffers, `f64` for the
/// CPU reference and its finite-difference checks.
pub trait Scalar: Copy + Default + PartialEq + std::fmt::Debug + Send + Sync + 'static {
    fn to_f64(self) -> f64;
    fn from_f64(v: f64) -> Self;
}

impl Scalar for f32 {
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
    fn from_f64(v: f64) -> Self {
        v as f32
    }
}

impl Scalar for f64 {
    fn to_f64(self) -> f64 {
        self
    }
    fn from_f64(v: f64) -> Self {
        v
    }
}

/// Which population a Gaussian belongs to (docs/ARCHITECTURE.md, "Math conventions").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Population {
    /// Renders colour, depth and reflection; occludes the mask but never paints it.
    #[default]
    Primary = 0,
    /// Sampled on a plane (and its children): renders only into the glass mask M.
    Glass = 1,
}

impl Population {
    pub fn from_u8(v: u8) -> Option<Self> {
        match v {
            0 => Some(Self::Primary),
            1 => Some(Self::Glass),
            _ => None,
        }
    }
}

/// Number of SH coefficients per colour channel for a degree (1, 4, 9, 16).
pub const fn sh_coeff_count(degree: u32) -> usize {
    ((degree + 1) * (degree + 1)) as usize
}

/// A set of Gaussians. Every `Vec` has one entry per Gaussian except `sh`, which holds
/// `sh_coeff_count(sh_degree)` RGB triples per Gaussian (coefficient-major within a Gaussian:
/// DC first, then the degree-1 band, ...).
///
/// Activations: scale = exp(log_scale), opacity = sigmoid(opacity_logit),
/// mask = sigmoid(mask_logit) (glass Gaussians only; primary ones have m = 0),
/// reflection intensity = exp(log_reflection) (positive; 1 at initialisation).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Gaussians<F: Scalar = f32> {
    pub means: Vec<[F; 3]>,
    /// Unnormalised quaternions (w, x, y, z).
    pub rotations: Vec<[F; 4]>,
    pub log_scales: Vec<[F; 3]>,
    pub opacity_logits: Vec<F>,
    pub sh_degree: u32,
    pub sh: Vec<[F; 3]>,
    pub mask_logits: Vec<F>,
    pub log_reflections: Vec<F>,
    pub populations: Vec<Population>,
}

impl<F: Scalar> Gaussians<F> {
    /// An empty set with the given SH degree (0..=3).
    pub fn empty(sh_degree: u32) -> Self {
        Self { sh_degree, ..Default::default() }
    }

    /// A set of `n` Gaussians with every attribute zero (unit quaternion), for gradients and tests.
    pub fn zeros(n: usize, sh_degree: u32) -> Self {
        let z = F::default();
        Self {
            means: vec![[z; 3]; n],
            rotations: vec![[z; 4]; n],
            log_scales: vec![[z; 3]; n],
            opacity_logits: vec![z; n],
            sh_degree,
            sh: vec![[z; 3]; n * sh_coeff_count(sh_degree)],
            mask_logits: vec![z; n],
            log_reflections: vec![z; n],
            populations: vec![Population::Primary; n],
        }
    }

    pub fn len(&self) -> usize {
        self.means.len()
    }

    pub fn is_empty(&self) -> bool {
        self.means.is_empty()
    }

    pub fn sh_coeffs(&self) -> usize {
        sh_coeff_count(self.sh_degree)
    }

    /// The SH coefficients of Gaussian `i`.
    pub fn sh_of(&self, i: usize) -> &[[F; 3]] {
        let k = self.sh_coeffs();
        &self.sh[i * k..(i + 1) * k]
    }

    /// Append one Gaussian; `sh` must hold `sh_coeffs()` triples (missing ones are zero).
    pub fn push(
        &mut self,
        mean: [F; 3],
        rotation: [F; 4],
        log_scale: [F; 3],
        opacity_logit: F,
        sh: &[[F; 3]],
        population: Population,
    ) {
        self.means.push(mean);
        self.rotations.push(rotation);
        self.log_scales.push(log_scale);
        self.opacity_logits.push(opacity_logit);
        let k = self.sh_coeffs();
        for j in 0..k {
            self.sh.push(sh.get(j).copied().unwrap_or_default());
        }
        self.mask_logits.push(F::default());
        self.log_reflections.push(F::default());
        self.populations.push(population);
    }

    /// Append every Gaussian of `other` (its SH converted to this set's degree).
    pub fn append(&mut self, other: &Self) {
        let other = other.with_sh_degree(self.sh_degree);
        self.means.extend_from_slice(&other.means);
        self.rotations.extend_from_slice(&other.rotations);
        self.log_scales.extend_from_slice(&other.log_scales);
        self.opacity_logits.extend_from_slice(&other.opacity_logits);
        self.sh.extend_from_slice(&other.sh);
        self.mask_logits.extend_from_slice(&other.mask_logits);
        self.log_reflections.extend_from_slice(&other.log_reflections);
        self.populations.extend_from_slice(&other.populations);
    }

    /// The same set in another scalar type.
    pub fn cast<G: Scalar>(&self) -> Gaussians<G> {
        let c = |v: F| G::from_f64(v.to_f64());
        Gaussians {
            means: self.means.iter().map(|a| a.map(c)).collect(),
            rotations: self.rotations.iter().map(|a| a.map(c)).collect(),
            log_scales: self.log_scales.iter().map(|a| a.map(c)).collect(),
            opacity_logits: self.opacity_logits.iter().map(|&v| c(v)).collect(),
            sh_degree: self.sh_degree,
            sh: self.sh.iter().map(|a| a.map(c)).collect(),
            mask_logits: self.mask_logits.iter().map(|&v| c(v)).collect(),
            log_reflections: self.log_reflections.iter().map(|&v| c(v)).collect(),
            populations: self.populations.clone(),
        }
    }

    /// The Gaussians at `indices`, in that order (an index may repeat).
    pub fn gather(&self, indices: impl IntoIterator<Item = usize>) -> Self {
        let k = self.sh_coeffs();
        let mut out = Self::empty(self.sh_degree);
        for i in indices {
            out.means.push(self.means[i]);
            out.rotations.push(self.rotations[i]);
            out.log_scales.push(self.log_scales[i]);
            out.opacity_logits.push(self.opacity_logits[i]);
            out.sh.extend_from_slice(&self.sh[i * k..(i + 1) * k]);
            out.mask_logits.push(self.mask_logits[i]);
            out.log_reflections.push(self.log_reflections[i]);
            out.populations.push(self.populations[i]);
        }
        out
    }

    /// The Gaussians `i` with `keep(i)`, in their order (indices renumbered).
    pub fn subset(&self, keep: impl Fn(usize) -> bool) -> Self {
        self.gather((0..self.len()).filter(|&i| keep(i)))
    }

    /// Keep only the first `sh_coeff_count(degree)` coefficients (or pad with zeros).
    pub fn with_sh_degree(&self, degree: u32) -> Self {
        let (old, new) = (self.sh_coeffs(), sh_coeff_count(degree));
        let mut sh = Vec::with_capacity(self.len() * new);
        for i in 0..self.len() {
            for j in 0..new {
                sh.push(if j < old { self.sh[i * old + j] } else { [F::default(); 3] });
            }
        }
        Self { sh, sh_degree: degree, ..self.clone() }
    }

    /// Check that every per-Gaussian `Vec` has the same length; a message names the first one off.
    pub fn check_lengths(&self) -> Result<(), String> {
        let n = self.len();
        let lens = [
            ("rotations", self.rotations.len()),
            ("log_scales", self.log_scales.len()),
            ("opacity_logits", self.opacity_logits.len()),
            ("mask_logits", self.mask_logits.len()),
            ("log_reflections", self.log_reflections.len()),
            ("populations", self.populations.len()),
        ];
        for (name, len) in lens {
            if len != n {
                return Err(format!("{name} has {len} entries, means has {n}"));
            }
        }
        if self.sh_degree > 3 {
            return Err(format!("SH degree {} is above 3", self.sh_degree));
        }
        if self.sh.len() != n * self.sh_coeffs() {
            return Err(format!(
                "sh has {} RGB triples, expected {} ({} Gaussians x {} coefficients)",
                self.sh.len(),
                n * self.sh_coeffs(),
                n,
                self.sh_coeffs()
            ));
        }
        Ok(())
    }
}
