//! The train/test split: `test_views.txt` (one image name a line) or, without it, every 8th image
//! of the name-sorted list (3DGS's `llffhold = 8`: indices 0, 8, 16, ...).
use std::collections::HashSet;
use std::path::Path;

use super::error::read_text;
use super::{FormatError, write_atomic};

/// The test views listed in `path`. Blank lines and `#` comments are skipped, names are trimmed,
/// a name listed twice counts once; a name that is not in `known` is an error naming the line.
pub fn read_test_views(path: &Path, known: &[String]) -> Result<Vec<String>, FormatError> {
    let text = read_text(path)?;
    let known_set: HashSet<&str> = known.iter().map(String::as_str).collect();
    let mut seen = HashSet::new();
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let name = line.trim();
        if name.is_empty() || name.starts_with('#') {
            continue;
        }
        if !known_set.contains(name) {
            let example =
                known.first().map(|k| format!(" (names look like {k:?})")).unwrap_or_default();
            let problem =
                format!("line {}: {name:?} is not an image of this dataset{example}", i + 1);
            return Err(FormatError::new(path, problem));
        }
        if seen.insert(name) {
            out.push(name.to_string());
        }
    }
    Ok(out)
}

/// Every 8th name of the sorted list, starting with the first.
pub fn default_test_views(names: &[String]) -> Vec<String> {
    let mut sorted = names.to_vec();
    sorted.sort();
    sorted.into_iter().step_by(8).collect()
}

/// Write one name a line.
pub fn write_test_views(path: &Path, names: &[String]) -> Result<(), FormatError> {
    let mut text = String::from("# test views, one image name a line\n");
    for name in names {
        if name.contains(['\n', '\r'])
            || name.trim() != name
            || name.is_empty()
            || name.starts_with('#')
        {
            return Err(FormatError::new(
                path,
                format!("the image name {name:?} cannot be written as a line"),
            ));
        }
        text.push_str(name);
        text.push('\n');
    }
    write_atomic(path, text.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::test_util::{assert_mentions, scratch_dir};

    fn names(n: usize) -> Vec<String> {
        (0..n).rev().map(|i| format!("{i:03}.png")).collect()
    }

    #[test]
    fn default_split_is_every_eighth_of_sorted_names() {
        assert_eq!(default_test_views(&names(17)), ["000.png", "008.png", "016.png"]);
        assert!(default_test_views(&[]).is_empty());
    }

    #[test]
    fn round_trip_with_comments() {
        let dir = scratch_dir("split-rt");
        let path = dir.join("test_views.txt");
        let picked = vec!["003.png".to_string(), "001.png".to_string()];
        write_test_views(&path, &picked).expect("write");
        assert_eq!(read_test_views(&path, &names(5)).expect("read"), picked);
        std::fs::write(&path, "# c\n\n  003.png  \n003.png\n").expect("write");
        assert_eq!(read_test_views(&path, &names(5)).expect("read"), ["003.png"]);
    }

    #[test]
    fn unknown_name_names_file_and_line() {
        let dir = scratch_dir("split-unknown");
        let path = dir.join("test_views.txt");
        std::fs::write(&path, "001.png\n# c\nnope.png\n").expect("write");
        let err = read_test_views(&path, &names(5)).expect_err("unknown");
        assert_mentions(&err, &["test_views.txt", "line 3", "\"nope.png\""]);
    }
}
