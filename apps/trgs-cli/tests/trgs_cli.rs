//! The `trgs` command: every subcommand answers `--help` with clap's generated help, the two
//! commands the design card names (`train`, `viewer`) are the same commands under those names,
//! completions are generated for the shells, and the package installs no other program.
use std::collections::BTreeSet;
use std::path::Path;
use std::process::Command;

fn help_of(program: &str, subcommand: Option<&str>) -> String {
    let mut c = Command::new(program);
    c.args(subcommand).arg("--help");
    let out = c.output().expect("run");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(out.status.success(), "{program} {subcommand:?} --help: {stdout}");
    assert!(stdout.contains("Usage:") && stdout.contains("-h, --help"), "{stdout}");
    stdout
}

#[test]
fn every_subcommand_has_generated_help() {
    let trgs = env!("CARGO_BIN_EXE_trgs");
    let top = help_of(trgs, None);
    let names: Vec<&str> = trgs_cli::commands::subcommand_names().collect();
    for expected in ["prepare", "train", "view", "eval", "render", "export", "report", "bench"] {
        assert!(names.contains(&expected), "{names:?}");
    }
    for name in &names {
        assert!(top.contains(&format!("  {name} ")), "trgs --help does not list {name}: {top}");
        let help = help_of(trgs, Some(name));
        assert!(help.contains(&format!("Usage: trgs {name}")), "{help}");
    }
    // No subcommand: the help, and a failure status for scripts.
    let bare = Command::new(trgs).output().expect("run");
    assert!(!bare.status.success());
    assert!(String::from_utf8_lossy(&bare.stderr).contains("Usage: trgs"));
}

#[test]
fn the_card_names_are_the_same_commands() {
    let trgs = env!("CARGO_BIN_EXE_trgs");
    let options = |help: &str| -> Vec<String> {
        help.lines().filter(|l| l.trim_start().starts_with("--")).map(str::to_owned).collect()
    };
    let train = help_of(env!("CARGO_BIN_EXE_train"), None);
    assert_eq!(options(&train), options(&help_of(trgs, Some("train"))));
    let viewer = help_of(env!("CARGO_BIN_EXE_viewer"), None);
    assert_eq!(options(&viewer), options(&help_of(trgs, Some("view"))));
}

#[test]
fn completions_cover_the_subcommands() {
    let trgs = env!("CARGO_BIN_EXE_trgs");
    for shell in ["bash", "zsh", "fish"] {
        let out = Command::new(trgs).args(["completions", shell]).output().expect("run");
        assert!(out.status.success(), "{shell}");
        let script = String::from_utf8_lossy(&out.stdout);
        for word in ["trgs", "export", "demo-scene"] {
            assert!(script.contains(word), "{shell} completions lack {word}");
        }
    }
}

/// What `cargo install --path apps/trgs-cli` puts on PATH: the package's binary targets, which
/// cargo finds as the .rs files of src/bin/ and its folders holding a main.rs, and [[bin]]
/// sections of its manifest.
#[test]
fn the_package_installs_trgs_and_the_two_card_names_only() {
    let package = Path::new(env!("CARGO_MANIFEST_DIR"));
    let manifest = std::fs::read_to_string(package.join("Cargo.toml")).expect("manifest");
    assert!(!manifest.contains("[[bin]]"), "binaries come from src/bin/ alone");
    assert!(!package.join("src/main.rs").exists());
    let bins: BTreeSet<String> = std::fs::read_dir(package.join("src/bin"))
        .expect("src/bin")
        .map(|e| e.expect("entry").path())
        .filter_map(|p| {
            if p.extension().is_some_and(|e| e == "rs") {
                p.file_stem().map(|s| s.to_string_lossy().into_owned())
            } else if p.join("main.rs").is_file() {
                p.file_name().map(|s| s.to_string_lossy().into_owned())
            } else {
                None
            }
        })
        .collect();
    let expected: BTreeSet<String> = ["trgs", "train", "viewer"].map(String::from).into();
    assert_eq!(bins, expected);
}
