//! What the trgs commands share: argument parsers ([`args`]), the layers of `render` as OpenEXR
//! ([`exr_layers`]), the speed-against-error plot of `report` ([`plot`]) and the stages of
//! `prepare` ([`prepare`]). Each command is a bin of this package.
pub mod args;
pub mod exr_layers;
pub mod plot;
pub mod prepare;
