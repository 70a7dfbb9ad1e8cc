//! Numbers in the commands' lines, with the noun in the number it takes.

/// `1 plane`, `2 planes`, `0 planes`.
pub fn count(n: usize, noun: &str) -> String {
    if n == 1 { format!("1 {noun}") } else { format!("{n} {noun}s") }
}

#[cfg(test)]
mod tests {
    #[test]
    fn one_is_singular() {
        assert_eq!(super::count(1, "plane"), "1 plane");
        assert_eq!(super::count(0, "plane"), "0 planes");
        assert_eq!(super::count(3, "view"), "3 views");
    }
}
