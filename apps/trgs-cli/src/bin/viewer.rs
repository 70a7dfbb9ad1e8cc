//! `viewer`: `trgs view` under the name the design card gives it (`cargo run --bin viewer`).
use clap::CommandFactory;
use trgs_cli::commands::view;

fn main() -> anyhow::Result<()> {
    trgs_cli::headless::quiet_vulkan_layers();
    view::run(&view::Args::command().get_matches())
}
