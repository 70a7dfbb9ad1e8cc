//! `trgs`: every trgs command as a subcommand (`trgs --help`).
fn main() -> anyhow::Result<()> {
    trgs_cli::headless::quiet_vulkan_layers();
    trgs_cli::commands::main()
}
