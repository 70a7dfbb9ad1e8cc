//! `train`: `trgs train` under the name the design card gives it (`cargo run --bin train`).
use clap::CommandFactory;
use trgs_cli::commands::train;

fn main() -> anyhow::Result<()> {
    trgs_cli::headless::quiet_vulkan_layers();
    train::run(&train::Args::command().get_matches())
}
