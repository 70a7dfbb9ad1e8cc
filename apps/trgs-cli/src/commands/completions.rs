//! `completions`: the shell's completion script for `trgs`, printed.
use anyhow::Result;
use clap::Parser;
use clap_complete::Shell;

/// Print the completion script of `trgs` for a shell.
///
/// bash: trgs completions bash > ~/.local/share/bash-completion/completions/trgs
/// zsh: trgs completions zsh > ~/.zfunc/_trgs (with ~/.zfunc in fpath)
/// fish: trgs completions fish > ~/.config/fish/completions/trgs.fish
#[derive(Debug, Parser)]
#[command(name = "completions")]
pub struct Args {
    /// The shell
    #[arg(value_enum)]
    shell: Shell,
}

pub fn run(matches: &clap::ArgMatches) -> Result<()> {
    let args = super::parsed::<Args>(matches);
    clap_complete::generate(args.shell, &mut super::cli(), "trgs", &mut std::io::stdout());
    Ok(())
}
