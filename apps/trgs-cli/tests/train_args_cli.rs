//! `train` refuses flag combinations where one flag would be silently ignored, before any work,
//! `render` refuses a malformed background colour, and `report` bad arguments; each error names
//! the flags (clap's wording for what clap checks).
use std::process::Command;

/// `command` is a program and the subcommand if any, e.g. `[trgs, "render"]`.
fn refused(command: &[&str], args: &[&str]) -> String {
    let out = Command::new(command[0]).args(&command[1..]).args(args).output().expect("run");
    assert!(!out.status.success(), "{args:?} was accepted");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn conflicting_flags_are_refused_by_name() {
    let train = [env!("CARGO_BIN_EXE_train")];
    let cases: [(&[&str], &[&str]); 7] = [
        (&["--resolution", "128", "--downscale", "2"], &["--resolution", "--downscale"]),
        (
            &["--demo-scene", "attic"],
            &["'attic'", "showcase", "window", "night-window", "no-glass"],
        ),
        (&["--data", "somewhere", "--demo-scene", "window"], &["--demo-scene", "--data"]),
        (&["--cap", "1000"], &["--cap", "--densify mcmc"]),
        (&["--no-planes", "--no-fresnel"], &["--no-planes", "--no-fresnel"]),
        (&["--resume", "--iterations", "5"], &["--resume", "drop --iterations"]),
        (&["--iterations", "0"], &["--iterations"]),
    ];
    for (args, words) in cases {
        let stderr = refused(&train, args);
        for w in words {
            assert!(stderr.contains(w), "{args:?}: {stderr}");
        }
    }
}

#[test]
fn render_background_must_be_three_numbers_in_range() {
    let render = [env!("CARGO_BIN_EXE_trgs"), "render"];
    for bad in ["1,x,0", "1,1", "2,0,0", "NaN,0,0"] {
        let stderr = refused(&render, &["--model", "m.ply", "--background", bad]);
        assert!(stderr.contains("--background") && stderr.contains("[0, 1]"), "{bad}: {stderr}");
    }
}

#[test]
fn report_refuses_unknown_options_and_mismatched_names() {
    let report = [env!("CARGO_BIN_EXE_trgs"), "report"];
    let stderr = refused(&report, &["runs/a", "--foo"]);
    assert!(stderr.contains("unexpected argument '--foo'"), "{stderr}");
    let stderr = refused(&report, &["runs/a", "runs/b", "--names", "A"]);
    assert!(stderr.contains("--names has 1 names for 2 runs"), "{stderr}");
    let nine: Vec<String> = (0..9).map(|i| format!("runs/{i}")).collect();
    let args: Vec<&str> = nine.iter().map(String::as_str).collect();
    assert!(refused(&report, &args).contains("at most 8"));
}

#[test]
fn train_help_lists_its_settings() {
    let help = Command::new(env!("CARGO_BIN_EXE_train")).arg("--help").output().expect("run");
    let help = String::from_utf8_lossy(&help.stdout);
    for flag in [
        "--data <DIR>",
        "--resume",
        "--no-fresnel",
        "[default: 1000 on the built-in",
        "30000 with --data",
    ] {
        assert!(help.contains(flag), "train --help lacks {flag}: {help}");
    }
}

#[test]
fn family_lists_its_members_and_refuses_unknown_ones_and_bad_train_flags() {
    let family = [env!("CARGO_BIN_EXE_trgs"), "family"];
    let out = Command::new(family[0])
        .args(["family", "--list", "--members", "all,drawn-5"])
        .output()
        .expect("run");
    assert!(out.status.success());
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(stdout.lines().count(), 9, "{stdout}");
    for name in ["arc-lights", "mirror-unlabelled", "two-turned-panes", "walk-by", "drawn-5"] {
        assert!(stdout.contains(name), "{stdout}");
    }
    let stderr = refused(&family, &["--list", "--members", "attic"]);
    assert!(stderr.contains("\"attic\"") && stderr.contains("arc-lights"), "{stderr}");
    let dir = std::env::temp_dir().join(format!("trgs-family-flags-{}", std::process::id()));
    let out = dir.to_string_lossy().into_owned();
    // Refused before the scene is generated.
    let stderr =
        refused(&family, &["--members", "walk-by", "--tr-flags", "--frobnicate", "--out", &out]);
    assert!(stderr.contains("--frobnicate"), "{stderr}");
    assert!(!dir.join("walk-by").join("dataset").exists());
    // Flags that parse but that training refuses: refused before the scene too.
    let stderr = refused(
        &family,
        &[
            "--members",
            "walk-by",
            "--tr-flags",
            "--densify mcmc --grow-fraction 0.5",
            "--out",
            &out,
        ],
    );
    assert!(stderr.contains("needs --densify classic"), "{stderr}");
    assert!(!dir.join("walk-by").join("dataset").exists());
    let _ = std::fs::remove_dir_all(&dir);
}
