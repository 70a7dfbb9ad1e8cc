//! The `trgs` command ([`commands`], one module per subcommand) and what its subcommands share:
//! argument parsers ([`args`]), the layers of `render` as OpenEXR ([`exr_layers`]), the
//! speed-against-error plot of `report` ([`plot`]), the stages of `prepare` ([`prepare`]) and
//! of `split` and `merge` ([`split`], [`merge`]), and a quiet Vulkan start on machines without a desktop session
//! ([`headless`]).
pub mod args;
pub mod commands;
pub mod exr_layers;
pub mod headless;
pub mod merge;
pub mod plot;
pub mod prepare;
pub mod split;
pub mod wording;
