//! Formatting USD text: identifiers, strings and deterministic floats.

use crate::mesh::Point;
use std::fmt::Write;

/// A valid USD prim name (`[A-Za-z_][A-Za-z0-9_]*`) from `s`: other characters become `_`, a
/// leading digit gets a `_` prefix, an empty name is `_`.
pub(super) fn identifier(s: &str) -> String {
    let mut out: String = s
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if out.is_empty() || out.starts_with(|c: char| c.is_ascii_digit()) {
        out.insert(0, '_');
    }
    out
}

/// A double-quoted USD string with `\`, `"` and control characters escaped.
pub(super) fn quoted(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if (c as u32) < 0x20 => {
                let _ = write!(out, "\\x{:02x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// `x` as `f32` in the shortest decimal that reads back to the same `f32` (Rust's `Display`,
/// never an exponent), `0` for negative zero.
pub(super) fn f32_text(out: &mut String, x: f64) {
    let f = x as f32;
    if f == 0.0 {
        out.push('0');
    } else {
        let _ = write!(out, "{f}");
    }
}

/// `[(x, y, z), …]`.
pub(super) fn vec3_array(out: &mut String, p: &[Point]) {
    out.push('[');
    for (i, q) in p.iter().enumerate() {
        if i > 0 {
            out.push_str(", ");
        }
        out.push('(');
        for k in 0..3 {
            if k > 0 {
                out.push_str(", ");
            }
            f32_text(out, q[k]);
        }
        out.push(')');
    }
    out.push(']');
}

/// `[a, b, …]` of integers.
pub(super) fn int_array(out: &mut String, v: impl IntoIterator<Item = u32>) {
    out.push('[');
    for (i, x) in v.into_iter().enumerate() {
        if i > 0 {
            out.push_str(", ");
        }
        let _ = write!(out, "{x}");
    }
    out.push(']');
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_strings_and_floats() {
        assert_eq!(identifier("horse-gallop.01"), "horse_gallop_01");
        assert_eq!(identifier("9lives"), "_9lives");
        assert_eq!(identifier(""), "_");
        assert_eq!(quoted("a\"b\\c\n"), "\"a\\\"b\\\\c\\n\"");
        let mut s = String::new();
        f32_text(&mut s, 0.1);
        s.push(' ');
        f32_text(&mut s, -0.0);
        s.push(' ');
        f32_text(&mut s, 1e-7);
        assert_eq!(s, "0.1 0 0.0000001");
        let back: f32 = "0.0000001".parse().unwrap();
        assert_eq!(back, 1e-7f32);
    }
}
