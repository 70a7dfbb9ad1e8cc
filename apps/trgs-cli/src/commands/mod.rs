//! The `trgs` command and its subcommands, one module each. Every subcommand's arguments are a
//! clap-derived `Args`; its `run` takes the matches `trgs` parsed (train reads which flags were
//! given, not only their values). `train` and `viewer` are also commands of their own, the names
//! the design card gives (`cargo run --bin train`), parsed by the same `Args`.
use anyhow::Result;
use clap::{ArgMatches, Command, CommandFactory, FromArgMatches};

pub mod bench;
pub mod completions;
pub mod eval;
pub mod export;
pub mod family;
pub mod merge;
pub mod prepare;
pub mod render;
pub mod report;
pub mod split;
pub mod train;
pub mod view;

/// A subcommand: its name under `trgs`, its arguments and what runs it.
struct Subcommand {
    name: &'static str,
    command: fn() -> Command,
    run: fn(&ArgMatches) -> Result<()>,
}

/// Every subcommand of `trgs`, in the order `trgs --help` lists them.
const SUBCOMMANDS: &[Subcommand] = &[
    Subcommand { name: "prepare", command: prepare::Args::command, run: prepare::run },
    Subcommand { name: "train", command: train::Args::command, run: train::run },
    Subcommand { name: "view", command: view::Args::command, run: view::run },
    Subcommand { name: "eval", command: eval::Args::command, run: eval::run },
    Subcommand { name: "render", command: render::Args::command, run: render::run },
    Subcommand { name: "export", command: export::Args::command, run: export::run },
    Subcommand { name: "report", command: report::Args::command, run: report::run },
    Subcommand { name: "bench", command: bench::Args::command, run: bench::run },
    Subcommand { name: "family", command: family::Args::command, run: family::run },
    Subcommand { name: "split", command: split::Args::command, run: split::run },
    Subcommand { name: "merge", command: merge::Args::command, run: merge::run },
    Subcommand { name: "completions", command: completions::Args::command, run: completions::run },
];

/// The names of `trgs`'s subcommands (tests cover each one's `--help`).
pub fn subcommand_names() -> impl Iterator<Item = &'static str> {
    SUBCOMMANDS.iter().map(|s| s.name)
}

/// The `trgs` command line.
pub fn cli() -> Command {
    let trgs = Command::new("trgs")
        .version(env!("CARGO_PKG_VERSION"))
        .about(
            "TR-Gaussians: 3D Gaussian Splatting with learnable reflection planes, for scenes \
             with glass and mirrors",
        )
        .after_help(
            "Start: trgs train (the built-in demo scene), or trgs prepare PHOTOS --out SCENE \
             then trgs train --data SCENE --out RUN; trgs view RUN shows the result.",
        )
        .subcommand_required(true)
        .arg_required_else_help(true);
    SUBCOMMANDS.iter().fold(trgs, |c, s| c.subcommand((s.command)().name(s.name)))
}

/// `trgs` with the process's arguments.
pub fn main() -> Result<()> {
    let matches = cli().get_matches();
    let (name, sub) = matches.subcommand().expect("clap requires a subcommand");
    let subcommand = SUBCOMMANDS.iter().find(|s| s.name == name).expect("a listed subcommand");
    (subcommand.run)(sub)
}

/// A command's arguments from the matches clap has already checked against them.
fn parsed<T: FromArgMatches>(matches: &ArgMatches) -> T {
    T::from_arg_matches(matches).unwrap_or_else(|e| e.exit())
}
