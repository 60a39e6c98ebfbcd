//! The order of a sequence's frame files: by name, with runs of digits compared as numbers.
//!
//! DCCs number exported frames without padding (Blender's OBJ exporter writes `anim1.obj`,
//! `anim2.obj`, …, `anim10.obj`), so a plain sort by name would play frame 10 second. A name is
//! compared as a sequence of runs: a run of ASCII digits against a run of digits by value
//! (leading zeros aside, so any length compares, and `frame_0010` still sorts after
//! `frame_0009`), anything else character by character. Zero-padded names, which sort the
//! same either way, keep their order. Names equal as numbers (`f1`, `f01`) fall back to the
//! plain order of their bytes, so the order is total and the same on every machine.

use std::cmp::Ordering;
use std::path::{Path, PathBuf};

/// Compares two paths as frame files: component strings in natural order (see the
/// [module documentation](self)), then bytes.
pub fn natural_cmp(a: &Path, b: &Path) -> Ordering {
    let (sa, sb) = (a.to_string_lossy(), b.to_string_lossy());
    natural_str_cmp(&sa, &sb).then_with(|| a.cmp(b))
}

/// Sorts frame files in the order of [`natural_cmp`].
pub fn sort_frame_paths(paths: &mut [PathBuf]) {
    paths.sort_by(|a, b| natural_cmp(a, b));
}

/// Natural order of two strings: digit runs by value, other characters as they are.
fn natural_str_cmp(a: &str, b: &str) -> Ordering {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        if a[i].is_ascii_digit() && b[j].is_ascii_digit() {
            let (ei, ej) = (run_end(a, i), run_end(b, j));
            // Leading zeros do not change a run's value.
            let (mut si, mut sj) = (i, j);
            while si + 1 < ei && a[si] == b'0' {
                si += 1;
            }
            while sj + 1 < ej && b[sj] == b'0' {
                sj += 1;
            }
            let by_value = (ei - si)
                .cmp(&(ej - sj))
                .then_with(|| a[si..ei].cmp(&b[sj..ej]));
            if by_value != Ordering::Equal {
                return by_value;
            }
            (i, j) = (ei, ej);
        } else {
            if a[i] != b[j] {
                return a[i].cmp(&b[j]);
            }
            i += 1;
            j += 1;
        }
    }
    (a.len() - i).cmp(&(b.len() - j))
}

/// The end of the run of ASCII digits starting at `i`.
fn run_end(s: &[u8], mut i: usize) -> usize {
    while i < s.len() && s[i].is_ascii_digit() {
        i += 1;
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sorted(names: &[&str]) -> Vec<String> {
        let mut p: Vec<PathBuf> = names.iter().map(PathBuf::from).collect();
        sort_frame_paths(&mut p);
        p.iter().map(|p| p.to_string_lossy().into_owned()).collect()
    }

    #[test]
    fn unpadded_frame_numbers_play_in_numeric_order() {
        let names = [
            "anim10.obj",
            "anim2.obj",
            "anim1.obj",
            "anim100.obj",
            "anim9.obj",
        ];
        assert_eq!(
            sorted(&names),
            [
                "anim1.obj",
                "anim2.obj",
                "anim9.obj",
                "anim10.obj",
                "anim100.obj"
            ]
        );
    }

    #[test]
    fn padded_names_keep_the_plain_order() {
        let mut names: Vec<String> = (0..1200).map(|k| format!("frame_{k:04}.obj")).collect();
        names.reverse();
        let refs: Vec<&str> = names.iter().map(String::as_str).collect();
        let mut plain = names.clone();
        plain.sort();
        assert_eq!(sorted(&refs), plain);
    }

    #[test]
    fn the_order_is_total_and_does_not_overflow() {
        // Equal as numbers: the bytes decide, so no two names compare equal.
        assert_eq!(sorted(&["f01.obj", "f1.obj"]), ["f01.obj", "f1.obj"]);
        assert_ne!(
            natural_cmp(Path::new("f01.obj"), Path::new("f1.obj")),
            Ordering::Equal
        );
        // Runs longer than any integer type compare by length, then digits.
        let long = format!("s{}.obj", "9".repeat(40));
        let longer = format!("s1{}.obj", "0".repeat(40));
        assert_eq!(sorted(&[&longer, &long]), [long.clone(), longer.clone()]);
        // Letters and digits: a digit sorts before a letter, as bytes do.
        assert_eq!(
            sorted(&["a.obj", "a1.obj", "1.obj"]),
            ["1.obj", "a.obj", "a1.obj"]
        );
        // Directories too (a glob over several folders).
        assert_eq!(
            sorted(&["take10/f1.obj", "take2/f3.obj", "take2/f20.obj"]),
            ["take2/f3.obj", "take2/f20.obj", "take10/f1.obj"]
        );
    }
}
