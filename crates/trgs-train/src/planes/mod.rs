//! The reflection planes: their initialisation from the glass masks at the end of stage 1
//! ([`init`]), the reflection seeds placed behind each new plane ([`reflection_seed`]), Adam on
//! their parameters ([`adam`]) and the opacity perturbation of what the cameras see through them
//! in stage 3 ([`perturb`]).
pub mod adam;
pub mod init;
pub mod perturb;
pub mod reflection_seed;
