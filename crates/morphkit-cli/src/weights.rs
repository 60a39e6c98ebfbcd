//! Checking blend weights as the user gave them, with messages that name where they came from
//! (the flag, or the weights file's line) and say what was expected and what was found.

use crate::util::num;
use morphkit::io::WeightRow;
use morphkit::springs::weights::MAX_WEIGHT;
use morphkit::springs::Weights;
use std::path::Path;

/// Where a weight vector came from, for messages.
#[derive(Clone, Copy, Debug)]
pub enum Origin<'a> {
    /// A flag: `--alpha` or `--weights`.
    Flag(&'a str),
    /// Row `frame` of a weights file.
    File {
        /// The file.
        path: &'a Path,
        /// The row.
        row: &'a WeightRow,
        /// Its frame number (0-based).
        frame: usize,
    },
}

impl Origin<'_> {
    fn prefix(&self) -> String {
        match self {
            Origin::Flag(f) => (*f).to_string(),
            Origin::File { path, row, frame } => match row.line {
                Some(l) => format!("{}:{l} (frame {frame}, '{}')", path.display(), row.text),
                None => format!("{} (frame {frame})", path.display()),
            },
        }
    }
}

/// The weights of `w` as given, with the word for them.
fn given(w: &Weights) -> (&[f64], &'static str) {
    match w {
        Weights::Alpha(a) => (std::slice::from_ref(a), "alpha"),
        Weights::Delta(v) => (v, "delta"),
        Weights::Convex(v) => (v, "convex"),
    }
}

/// Checks one weight vector for a blend of `n_shapes` shapes (base included): the count for
/// its form, finiteness, the bound ±[`MAX_WEIGHT`], and for convex weights a sum of 1 with no
/// negative entry. The error names `origin` and says what was expected and found.
pub fn check(w: &Weights, n_shapes: usize, origin: Origin) -> anyhow::Result<()> {
    let at = origin.prefix();
    let (values, form) = given(w);
    let n_targets = n_shapes.saturating_sub(1);
    let (expected, per) = match w {
        Weights::Alpha(_) => (1, "with exactly one --target"),
        Weights::Delta(_) => (n_targets, "one per --target"),
        Weights::Convex(_) => (n_shapes, "one per shape, the base first, with --convex"),
    };
    if let Weights::Alpha(_) = w {
        if n_shapes != 2 {
            anyhow::bail!(
                "{at}: blends the base with one target, but {n_targets} targets were given; use --weights for several"
            );
        }
    } else if values.len() != expected {
        let hint = match (&origin, values.len()) {
            (Origin::File { row, .. }, 2) if expected == 1 && row.text.contains(',') => {
                "; a decimal comma? write decimals with '.'"
            }
            _ => "",
        };
        anyhow::bail!(
            "{at}: expected {expected} {form} weight{} ({per}), found {}{hint}",
            if expected == 1 { "" } else { "s" },
            values.len()
        );
    }
    if let Some(i) = values.iter().position(|x| !x.is_finite()) {
        anyhow::bail!(
            "{at}: weight {i} is {}, not finite; expected a finite number",
            num(values[i])
        );
    }
    if let Some(i) = values.iter().position(|x| x.abs() > MAX_WEIGHT) {
        anyhow::bail!(
            "{at}: weight {i} is {}, expected at most {MAX_WEIGHT} in magnitude (extrapolating further follows no meaningful spring system)",
            num(values[i])
        );
    }
    if let Weights::Delta(v) = w {
        let base = 1.0 - v.iter().sum::<f64>();
        if base.abs() > MAX_WEIGHT {
            anyhow::bail!(
                "{at}: the base's weight 1 − Σw is {}, expected at most {MAX_WEIGHT} in magnitude",
                num(base)
            );
        }
    }
    if let Weights::Convex(v) = w {
        let sum: f64 = v.iter().sum();
        if let Some(i) = v.iter().position(|&x| x < -1e-12) {
            anyhow::bail!(
                "{at}: convex weight {i} is {}, expected non-negative weights summing to 1",
                num(v[i])
            );
        }
        if (sum - 1.0).abs() > 1e-9 {
            anyhow::bail!(
                "{at}: convex weights sum to {}, expected 1 (drop --convex for per-target delta weights)",
                num(sum)
            );
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(text: &str, values: &[f64]) -> WeightRow {
        WeightRow {
            line: Some(3),
            text: text.into(),
            values: values.to_vec(),
        }
    }

    #[test]
    fn messages_say_where_what_was_expected_and_what_was_found() {
        let e = |w: Weights, n, o| check(&w, n, o).unwrap_err().to_string();
        let s = e(Weights::Delta(vec![0.5, 0.2]), 2, Origin::Flag("--weights"));
        assert_eq!(
            s,
            "--weights: expected 1 delta weight (one per --target), found 2"
        );
        let s = e(
            Weights::Convex(vec![0.5, 0.4]),
            2,
            Origin::Flag("--weights"),
        );
        assert!(s.contains("sum to 0.9, expected 1"), "{s}");
        let s = e(Weights::Delta(vec![f64::NAN]), 2, Origin::Flag("--weights"));
        assert!(s.contains("weight 0 is NaN, not finite"), "{s}");
        let s = e(Weights::Alpha(1e6), 2, Origin::Flag("--alpha"));
        assert!(s.contains("weight 0 is 1e6, expected at most 100"), "{s}");
        let r = row("0,5", &[0.0, 5.0]);
        let p = Path::new("keys.csv");
        let s = e(
            Weights::Delta(r.values.clone()),
            2,
            Origin::File {
                path: p,
                row: &r,
                frame: 1,
            },
        );
        assert!(
            s.starts_with("keys.csv:3 (frame 1, '0,5'): expected 1"),
            "{s}"
        );
        assert!(s.contains("found 2; a decimal comma?"), "{s}");
        assert!(check(
            &Weights::Convex(vec![0.25, 0.75]),
            2,
            Origin::Flag("--weights")
        )
        .is_ok());
    }
}
