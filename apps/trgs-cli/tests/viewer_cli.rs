//! The `viewer` command line without a display: files it cannot read and bad options get a clear
//! error naming the file or option, before any window opens.
use std::process::Command;

fn viewer(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_viewer"))
        .args(args)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("viewer runs");
    (out.status.success(), String::from_utf8_lossy(&out.stderr).into_owned())
}

#[test]
fn a_missing_model_is_named() {
    let (ok, err) = viewer(&["/nonexistent/run/model.ply"]);
    assert!(!ok);
    assert!(err.contains("/nonexistent/run/model.ply"), "{err}");
}

#[test]
fn a_malformed_model_is_named_with_what_was_expected() {
    let dir = trgs_core::scratch::ScratchDir::new("viewer-cli");
    let ply = dir.join("broken.ply");
    std::fs::write(&ply, b"ply\nformat ascii 1.0\nelement vertex 2\nend_header\n").expect("write");
    let (ok, err) = viewer(&[ply.to_str().expect("utf-8 path")]);
    assert!(!ok);
    assert!(err.contains("broken.ply"), "{err}");
    let glb = dir.join("broken.glb");
    std::fs::write(&glb, b"glTF not really").expect("write");
    let (ok, err) = viewer(&[glb.to_str().expect("utf-8 path")]);
    assert!(!ok);
    assert!(err.contains("broken.glb"), "{err}");
}

#[test]
fn bad_options_say_what_is_expected() {
    let (ok, err) = viewer(&["--layer", "shiny"]);
    assert!(!ok);
    assert!(err.contains("'shiny'") && err.contains("--layer") && err.contains("transmission"));
    let (ok, err) = viewer(&["--size", "big"]);
    assert!(!ok && err.contains("WxH"), "{err}");
    let (ok, err) = viewer(&["--view", "2"]);
    assert!(!ok && err.contains("cameras.json"), "{err}");
    let (ok, err) = viewer(&["--layer", "depth_variance"]);
    assert!(!ok && err.contains("'depth_variance'") && err.contains("--layer"), "{err}");
    let (ok, err) = viewer(&["--size", "0x600"]);
    assert!(!ok && err.contains("at least 1"), "{err}");
    let (ok, err) = viewer(&["--frames", "0"]);
    assert!(!ok && err.contains("'0'") && err.contains("--frames"), "{err}");
    // A scripted run with nothing to draw would never exit.
    let (ok, err) = viewer(&["--screenshot", "x.png", "--exit"]);
    assert!(!ok && err.contains("need a model"), "{err}");
}
