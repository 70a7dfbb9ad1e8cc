//! The shape of the code, checked against the tree: no import circle of more than two files
//! inside any crate, no function of 120 lines or more, every path that a doc or a comment names
//! exists, and every command is where the docs list the commands. Each check also has a test
//! showing that it fails on what it is meant to catch.

mod doc_paths;
mod graph;
mod imports;
mod source;

use source::{CrateRoot, crates, files_with, root, shown, split};

/// The longest a function may be (lines from `fn` to its closing brace).
const MAX_FUNCTION_LINES: usize = 120;

/// Circles of more than two files in `krate`, each described with what ties it.
fn long_circles(krate: &CrateRoot) -> Vec<String> {
    let edges = graph::file_edges(&imports::modules(krate));
    let mut out = Vec::new();
    for circle in graph::circles(&edges) {
        if circle.len() <= 2 {
            continue;
        }
        let mut text = format!("{}: a circle of {} files:", krate.name, circle.len());
        for from in &circle {
            for (to, names) in &edges[from] {
                if circle.contains(to) {
                    let names: Vec<&str> = names.iter().map(String::as_str).collect();
                    text += &format!("\n  {} -> {}: {}", shown(from), shown(to), names.join(", "));
                }
            }
        }
        out.push(text);
    }
    out
}

#[test]
fn no_import_circle_inside_a_crate_spans_more_than_two_files() {
    let crates = crates();
    assert!(crates.len() >= 6, "found {} crates", crates.len());
    let circles: Vec<String> = crates.iter().flat_map(long_circles).collect();
    assert!(circles.is_empty(), "{}", circles.join("\n"));
}

#[test]
fn the_import_check_finds_a_circle_through_a_re_export() {
    let dir = std::env::temp_dir().join(format!("trgs-structure-{}", std::process::id()));
    let src = dir.join("src");
    std::fs::create_dir_all(src.join("b")).expect("temporary folder");
    let files = [
        ("lib.rs", "mod a;\nmod b;\npub use a::A;\npub struct C;\npub struct D(pub A);\n"),
        (
            "a.rs",
            "use crate::b::B; // the facade b/mod.rs re-exports it from b/inner.rs\npub struct A;\n",
        ),
        ("b/mod.rs", "mod inner;\npub use inner::B;\n"),
        ("b/inner.rs", "pub struct B(crate::C);\n"),
    ];
    for (name, text) in files {
        std::fs::write(src.join(name), text).expect("fixture file");
    }
    // The root -> module a -> b's inner module -> the root; b's mod file only passes B on.
    let krate = CrateRoot { name: "fixture".into(), root_file: src.join("lib.rs") };
    let circles = long_circles(&krate);
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(circles.len(), 1, "{circles:?}");
    assert!(circles[0].contains("a circle of 3 files"), "{}", circles[0]);
    assert!(!circles[0].contains("b/mod.rs"), "the re-export is followed: {}", circles[0]);
}

/// Functions of `MAX_FUNCTION_LINES` lines or more in `text`: (first line, name, lines).
fn long_functions(text: &str) -> Vec<(usize, String, usize)> {
    let code = split(text).code;
    let lines: Vec<&str> = code.lines().collect();
    let mut out = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let words: Vec<&str> = line.split(|c: char| !(c.is_alphanumeric() || c == '_')).collect();
        let Some(at) = words.iter().position(|&w| w == "fn") else { continue };
        let Some(name) = words.get(at + 1).filter(|w| !w.is_empty()) else { continue };
        let (mut depth, mut opened) = (0i32, false);
        for (j, l) in lines[i..].iter().enumerate() {
            for c in l.chars() {
                match c {
                    '{' => (depth, opened) = (depth + 1, true),
                    '}' => depth -= 1,
                    _ => {}
                }
            }
            let declared_only = !opened && l.trim_end().ends_with(';');
            if declared_only || (opened && depth == 0) {
                if opened && j + 1 >= MAX_FUNCTION_LINES {
                    out.push((i + 1, name.to_string(), j + 1));
                }
                break;
            }
        }
    }
    out
}

#[test]
fn every_function_is_under_120_lines() {
    let mut long = Vec::new();
    for file in files_with(&root(), ".rs") {
        let text = std::fs::read_to_string(&file).expect("a source file");
        for (line, name, lines) in long_functions(&text) {
            long.push(format!("{}:{line} {name}: {lines} lines", shown(&file)));
        }
    }
    assert!(
        long.is_empty(),
        "functions of {MAX_FUNCTION_LINES} lines or more:\n{}",
        long.join("\n")
    );
}

#[test]
fn the_length_check_counts_a_long_function() {
    let body = "    let x = \"}\"; // }\n".repeat(MAX_FUNCTION_LINES);
    let text = format!("fn short() {{}}\n\nfn long() {{\n{body}}}\n");
    assert_eq!(long_functions(&text), vec![(3, "long".to_string(), MAX_FUNCTION_LINES + 2)]);
}

#[test]
fn every_path_the_docs_and_comments_name_exists() {
    let files = doc_paths::repository_files();
    let mut missing = Vec::new();
    let mut checked = 0;
    for (doc, text) in doc_paths::documents() {
        for named in doc_paths::named_paths(&text) {
            checked += 1;
            if !doc_paths::exists(&named, &doc, &files) {
                missing.push(format!("{} names {named}", shown(&doc)));
            }
        }
    }
    assert!(checked > 300, "only {checked} paths found");
    missing.sort();
    missing.dedup();
    assert!(missing.is_empty(), "paths that do not exist:\n{}", missing.join("\n"));
}

#[test]
fn the_path_check_refuses_what_does_not_exist() {
    let files = doc_paths::repository_files();
    let doc = root().join("docs/ARCHITECTURE.md");
    let named = doc_paths::named_paths(
        "see shaders/render/tile_ranges.wgsl, `stages/sort.rs`, depth_order_{compact,counts}.wgsl, \
         renders/<stem>.png and shaders/tile_ranges.wgsl (moved) or docs/NOWHERE.md.",
    );
    let found: Vec<(&str, bool)> =
        named.iter().map(|n| (n.as_str(), doc_paths::exists(n, &doc, &files))).collect();
    assert_eq!(
        found,
        [
            ("shaders/render/tile_ranges.wgsl", true),
            ("stages/sort.rs", true),
            ("depth_order_{compact,counts}.wgsl", true),
            ("shaders/tile_ranges.wgsl", false),
            ("docs/NOWHERE.md", false),
        ]
    );
}

#[test]
fn every_command_is_listed_where_the_docs_list_the_commands() {
    let root = root();
    // `trgs`'s subcommands: a module each under apps/trgs-cli/src/commands/ (a file, or a folder).
    let mut commands: Vec<String> = std::fs::read_dir(root.join("apps/trgs-cli/src/commands"))
        .expect("the commands' folder")
        .flatten()
        .map(|e| e.path().file_stem().unwrap_or_default().to_string_lossy().into_owned())
        .filter(|name| name != "mod")
        .collect();
    commands.sort();
    assert!(commands.len() >= 9, "{commands:?}");
    let architecture = std::fs::read_to_string(root.join("docs/ARCHITECTURE.md")).expect("map");
    let diagram =
        architecture.lines().find(|l| l.contains("subcommands:")).expect("the diagram's commands");
    let readme = std::fs::read_to_string(root.join("README.md")).expect("README");
    let manifest =
        std::fs::read_to_string(root.join("apps/trgs-cli/Cargo.toml")).expect("manifest");
    for command in &commands {
        let word = |text: &str| {
            text.split(|c: char| !(c.is_alphanumeric() || c == '_' || c == '-'))
                .any(|w| w == command)
        };
        assert!(
            word(diagram),
            "ARCHITECTURE.md's crate diagram does not list `{command}`: {diagram}"
        );
        assert!(
            readme.contains(&format!("trgs {command}")),
            "README.md's commands lack `trgs {command}`"
        );
        let description = manifest.lines().find(|l| l.starts_with("description")).unwrap_or("");
        assert!(word(description), "apps/trgs-cli/Cargo.toml's description lacks `{command}`");
    }
}
