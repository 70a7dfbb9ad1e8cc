//! The learnable attributes of a Gaussian by name. Everything kept per attribute (GPU buffers,
//! gradients, Adam moments, learning rates) is a [`PerAttribute`], indexed by [`Attribute`]
//! rather than by a bare number.
use std::ops::{Index, IndexMut};

/// One learnable attribute of every Gaussian (the fields of [`crate::scene::Gaussians`] that an
/// optimiser steps; the population is fixed and not one of them).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Attribute {
    Means,
    Rotations,
    LogScales,
    OpacityLogits,
    Sh,
    MaskLogits,
    LogReflections,
}

impl Attribute {
    /// Every attribute, in storage order (the order of checkpoint arrays and GPU buffers).
    pub const ALL: [Attribute; 7] = [
        Self::Means,
        Self::Rotations,
        Self::LogScales,
        Self::OpacityLogits,
        Self::Sh,
        Self::MaskLogits,
        Self::LogReflections,
    ];

    /// The field's name, as in [`crate::scene::Gaussians`] and in GPU buffer labels.
    pub fn name(self) -> &'static str {
        match self {
            Self::Means => "means",
            Self::Rotations => "rotations",
            Self::LogScales => "log_scales",
            Self::OpacityLogits => "opacity_logits",
            Self::Sh => "sh",
            Self::MaskLogits => "mask_logits",
            Self::LogReflections => "log_reflections",
        }
    }

    /// Floats per Gaussian, with `sh_coeffs` SH coefficients per colour channel.
    pub fn width(self, sh_coeffs: usize) -> usize {
        match self {
            Self::Means | Self::LogScales => 3,
            Self::Rotations => 4,
            Self::Sh => 3 * sh_coeffs,
            Self::OpacityLogits | Self::MaskLogits | Self::LogReflections => 1,
        }
    }

    /// The position in [`Attribute::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }
}

/// One value per [`Attribute`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PerAttribute<T>(pub [T; 7]);

impl<T> PerAttribute<T> {
    /// The value of each attribute from `f`.
    pub fn from_fn(mut f: impl FnMut(Attribute) -> T) -> Self {
        Self(Attribute::ALL.map(&mut f))
    }

    /// (attribute, value) pairs in storage order.
    pub fn iter(&self) -> impl Iterator<Item = (Attribute, &T)> {
        Attribute::ALL.into_iter().zip(&self.0)
    }

    /// (attribute, value) pairs in storage order, mutably.
    pub fn iter_mut(&mut self) -> impl Iterator<Item = (Attribute, &mut T)> {
        Attribute::ALL.into_iter().zip(&mut self.0)
    }

    /// Each value mapped by `f`.
    pub fn map<U>(self, f: impl FnMut(T) -> U) -> PerAttribute<U> {
        PerAttribute(self.0.map(f))
    }

    /// Each value by reference.
    pub fn as_ref(&self) -> PerAttribute<&T> {
        PerAttribute(self.0.each_ref())
    }

    pub fn values(&self) -> &[T; 7] {
        &self.0
    }
}

/// Floats per Gaussian of every attribute, with `sh_coeffs` SH coefficients per channel.
pub fn attribute_widths(sh_coeffs: usize) -> PerAttribute<usize> {
    PerAttribute::from_fn(|a| a.width(sh_coeffs))
}

impl<T> Index<Attribute> for PerAttribute<T> {
    type Output = T;
    fn index(&self, a: Attribute) -> &T {
        &self.0[a.index()]
    }
}

impl<T> IndexMut<Attribute> for PerAttribute<T> {
    fn index_mut(&mut self, a: Attribute) -> &mut T {
        &mut self.0[a.index()]
    }
}

impl<T> IntoIterator for PerAttribute<T> {
    type Item = T;
    type IntoIter = std::array::IntoIter<T, 7>;
    fn into_iter(self) -> Self::IntoIter {
        self.0.into_iter()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn attributes_index_in_storage_order() {
        for (k, a) in Attribute::ALL.into_iter().enumerate() {
            assert_eq!(a.index(), k);
        }
        let widths = attribute_widths(16);
        assert_eq!(widths[Attribute::Sh], 48);
        assert_eq!(widths.values(), &[3, 4, 3, 1, 48, 1, 1]);
        let mut names = PerAttribute::from_fn(Attribute::name);
        names[Attribute::Means] = "positions";
        assert_eq!(names.iter().next(), Some((Attribute::Means, &"positions")));
    }
}
