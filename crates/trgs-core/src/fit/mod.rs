//! Plane fitting for initialisation.
