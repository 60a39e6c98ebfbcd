//! Per-frame weight files: JSON (`{"frames": [[…], …]}`, `{"weights": …}` or a bare array of
//! arrays) or CSV (one row per frame, values separated by `,`, `;` or tabs; blank lines and
//! `#` comments skipped; a first line that does not parse as numbers is a header).
//!
//! The reader only parses: whether a row has the right number of weights for a shape set, and
//! whether they are in range, is the caller's to check. Each row keeps the line it came from
//! and its text, so that such a check can name it.

use super::source::strip_bom_str;
use super::IoError;
use std::path::Path;

/// Most bytes a weights file may have (a million frames of a few weights each fit easily).
pub const MAX_WEIGHTS_FILE_BYTES: u64 = 256 << 20;

/// One frame's weights as read.
#[derive(Clone, Debug, PartialEq)]
pub struct WeightRow {
    /// 1-based line of a CSV row; `None` for JSON.
    pub line: Option<usize>,
    /// The row's text as written (CSV), shortened to its first 60 characters and `…` (a row
    /// of 10⁶ weights is not echoed whole in a message); empty for JSON.
    pub text: String,
    /// The weights.
    pub values: Vec<f64>,
}

/// Reads a weights file; JSON when the extension is `.json` or the text starts with `[` or `{`.
pub fn read_weights(path: &Path) -> Result<Vec<WeightRow>, IoError> {
    let (text, json) = read_text(path)?;
    parse_weights(path, &text, json)
}

/// The text of a weights file (size-limited, UTF-8), and whether its extension says JSON.
fn read_text(path: &Path) -> Result<(String, bool), IoError> {
    if path.is_dir() {
        return Err(IoError::IsDirectory {
            path: path.to_path_buf(),
        });
    }
    let meta = std::fs::metadata(path).map_err(|e| IoError::os(path, "read the file", e))?;
    if meta.len() > MAX_WEIGHTS_FILE_BYTES {
        return Err(IoError::content(
            path,
            format!(
                "the weights file has {} bytes, more than the {MAX_WEIGHTS_FILE_BYTES} accepted",
                meta.len()
            ),
        ));
    }
    let bytes = std::fs::read(path).map_err(|e| IoError::os(path, "read the file", e))?;
    let text = String::from_utf8(bytes)
        .map_err(|e| IoError::content(path, format!("not UTF-8 text: {e}")))?;
    let json = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"));
    Ok((text, json))
}

/// Reads a weights file for a rig whose morph targets are named `targets` (see
/// [`parse_named_weights`]).
pub fn read_named_weights(path: &Path, targets: &[String]) -> Result<Vec<WeightRow>, IoError> {
    let (text, json) = read_text(path)?;
    parse_named_weights(path, &text, json, targets)
}

/// Parses weights for a rig whose morph targets are named `targets`: a CSV whose header row
/// names targets (`jawOpen,smile`, in any order, any subset) gives rows of one weight per
/// target, in the order of `targets`, 0 for the targets it does not name. Without a header
/// (and for JSON) the rows are as [`parse_weights`] reads them: one weight per target, in
/// order, which is the caller's to check.
///
/// Errors: those of [`parse_weights`]; a header name that is no target (the error lists the
/// targets) or that several targets share (a header cannot choose among them; the error
/// names their indices and asks for rows without a header), a name given twice, a row with
/// another number of weights than the header names.
pub fn parse_named_weights(
    path: &Path,
    text: &str,
    json: bool,
    targets: &[String],
) -> Result<Vec<WeightRow>, IoError> {
    let rows = parse_weights(path, text, json)?;
    let text = strip_bom_str(text);
    if json || text.trim_start().starts_with(['[', '{']) {
        return Ok(rows);
    }
    let Some(first) = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))
    else {
        return Ok(rows);
    };
    let header: Vec<&str> = first.split([',', ';', '\t']).map(str::trim).collect();
    if header.iter().all(|f| f.parse::<f64>().is_ok()) {
        return Ok(rows);
    }
    let line = 1 + text.lines().position(|l| l.trim() == first).unwrap_or(0);
    let mut columns = Vec::with_capacity(header.len());
    for (i, name) in header.iter().enumerate() {
        let named: Vec<usize> = (0..targets.len())
            .filter(|&t| targets[t] == *name)
            .collect();
        if named.len() > 1 {
            let list: Vec<String> = named.iter().map(|t| t.to_string()).collect();
            return Err(IoError::parse(
                path,
                line,
                format!(
                    "column {} of the header is '{}', which {} morph targets share (targets {}); \
                     a header cannot tell them apart: write the rows without a header, one \
                     weight per target in the rig's order ({} targets)",
                    i + 1,
                    show(name),
                    named.len(),
                    list.join(", "),
                    targets.len()
                ),
            ));
        }
        let Some(&t) = named.first() else {
            return Err(IoError::parse(
                path,
                line,
                format!(
                    "column {} of the header is '{}', which names no morph target; the targets: {}",
                    i + 1,
                    show(name),
                    show(&targets.join(", "))
                ),
            ));
        };
        if columns.contains(&t) {
            return Err(IoError::content(
                path,
                format!("the header names the target '{name}' twice"),
            ));
        }
        columns.push(t);
    }
    rows.into_iter()
        .map(|r| {
            if r.values.len() != columns.len() {
                return Err(IoError::parse(
                    path,
                    r.line.unwrap_or(0),
                    format!(
                        "{} weights, but the header names {} targets",
                        r.values.len(),
                        columns.len()
                    ),
                ));
            }
            let mut values = vec![0.0; targets.len()];
            for (&t, &x) in columns.iter().zip(&r.values) {
                values[t] = x;
            }
            Ok(WeightRow { values, ..r })
        })
        .collect()
}

/// Parses weights text (see the module docs); `json` forces JSON. `path` names the file in
/// errors.
pub fn parse_weights(path: &Path, text: &str, json: bool) -> Result<Vec<WeightRow>, IoError> {
    let text = strip_bom_str(text);
    let rows = if json || text.trim_start().starts_with(['[', '{']) {
        parse_json(path, text)?
    } else {
        parse_csv(path, text)?
    };
    if rows.is_empty() {
        return Err(IoError::content(path, "no weight rows"));
    }
    Ok(rows)
}

fn parse_json(path: &Path, text: &str) -> Result<Vec<WeightRow>, IoError> {
    let v: serde_json::Value = serde_json::from_str(text)
        .map_err(|e| IoError::parse(path, e.line(), format!("invalid JSON: {e}")))?;
    let arr = v.get("frames").or_else(|| v.get("weights")).unwrap_or(&v);
    let shape = "expected an array of weight arrays (or {\"frames\": [[…], …]})";
    let frames = arr
        .as_array()
        .ok_or_else(|| IoError::content(path, shape))?;
    frames
        .iter()
        .enumerate()
        .map(|(k, row)| {
            let items = row.as_array().ok_or_else(|| {
                IoError::content(path, format!("frame {k}: {row} is not an array; {shape}"))
            })?;
            let values = items
                .iter()
                .enumerate()
                .map(|(i, x)| {
                    x.as_f64().ok_or_else(|| {
                        IoError::content(
                            path,
                            format!("frame {k}, weight {i}: {x} is not a number"),
                        )
                    })
                })
                .collect::<Result<Vec<f64>, _>>()?;
            Ok(WeightRow {
                line: None,
                text: String::new(),
                values,
            })
        })
        .collect()
}

fn parse_csv(path: &Path, text: &str) -> Result<Vec<WeightRow>, IoError> {
    let mut rows = Vec::new();
    let mut first_content = true;
    for (n, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let header_allowed = first_content;
        first_content = false;
        let fields: Vec<&str> = line.split([',', ';', '\t']).map(str::trim).collect();
        let mut values = Vec::with_capacity(fields.len());
        for (i, f) in fields.iter().enumerate() {
            match f.parse::<f64>() {
                Ok(x) => values.push(x),
                Err(_) if header_allowed => break,
                Err(_) => {
                    let what = if f.is_empty() {
                        "is empty".to_string()
                    } else {
                        format!("'{}' is not a number", show(f))
                    };
                    return Err(IoError::parse(
                        path,
                        n + 1,
                        format!("field {} {what} in '{}'", i + 1, show(line)),
                    ));
                }
            }
        }
        if values.len() < fields.len() {
            continue; // a header line
        }
        rows.push(WeightRow {
            line: Some(n + 1),
            text: show(line),
            values,
        });
    }
    Ok(rows)
}

/// Text shortened for messages.
fn show(s: &str) -> String {
    if s.chars().count() > 60 {
        format!("{}…", s.chars().take(60).collect::<String>())
    } else {
        s.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 39: an error about a row of 10⁶ weights quoted the whole 4 MB line.
    #[test]
    fn long_rows_are_kept_and_quoted_short() {
        let row = vec!["0.5"; 1_000_000].join(",");
        let rows = parse_weights(p(), &format!("{row}\n{row}\n"), false).unwrap();
        assert_eq!(rows[1].values.len(), 1_000_000);
        assert!(rows[1].text.chars().count() <= 61, "{}", rows[1].text.len());
        let bad = format!("{row},x\n");
        let e = parse_weights(p(), &bad, false).unwrap_err().to_string();
        assert!(e.len() < 300, "{} bytes", e.len());
    }

    fn p() -> &'static Path {
        Path::new("w.csv")
    }

    #[test]
    fn csv_rows_keep_their_lines_and_a_header_and_bom_are_skipped() {
        let rows = parse_weights(p(), "\u{feff}jaw,smile\n# c\n0.5,0.25\n\n1;0\n", false).unwrap();
        assert_eq!(rows.len(), 2);
        assert_eq!(rows[0].line, Some(3));
        assert_eq!(rows[0].values, [0.5, 0.25]);
        assert_eq!(rows[1].text, "1;0");
    }

    #[test]
    fn malformed_rows_name_line_and_field() {
        let e = parse_weights(p(), "0.5\n0.x\n", false)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("w.csv:2: field 1 '0.x' is not a number"),
            "{e}"
        );
        let e = parse_weights(p(), "0.5,\n", false).unwrap_err().to_string();
        assert!(e.contains("no weight rows"), "{e}");
        let e = parse_weights(p(), "0.5\n0.5,\n", false)
            .unwrap_err()
            .to_string();
        assert!(e.contains("field 2 is empty"), "{e}");
    }

    #[test]
    fn a_header_names_the_targets_of_each_column() {
        let names = ["jaw".to_string(), "smile".into(), "blink".into()];
        let rows =
            parse_named_weights(p(), "# keys\nsmile,jaw\n0.5,0.25\n1,0\n", false, &names).unwrap();
        assert_eq!(rows[0].values, [0.25, 0.5, 0.0]);
        assert_eq!(rows[1].values, [0.0, 1.0, 0.0]);
        assert_eq!(rows[1].line, Some(4));
        // Without a header: as read.
        let rows = parse_named_weights(p(), "0.5,0.25\n", false, &names).unwrap();
        assert_eq!(rows[0].values, [0.5, 0.25]);
        let e = parse_named_weights(p(), "jaw,frown\n0,1\n", false, &names)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("w.csv:1: column 2 of the header is 'frown'")
                && e.contains("jaw, smile, blink"),
            "{e}"
        );
        let e = parse_named_weights(p(), "jaw,smile\n0,1,1\n", false, &names)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("w.csv:2: 3 weights, but the header names 2"),
            "{e}"
        );
    }

    /// Issue 55: a header naming a target that two targets share drove only the first.
    #[test]
    fn a_header_naming_a_shared_target_name_is_refused() {
        let names = ["same".to_string(), "jaw".into(), "same".into()];
        let e = parse_named_weights(p(), "jaw,same\n0,1\n", false, &names)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("w.csv:1: column 2 of the header is 'same', which 2 morph targets share (targets 0, 2)"),
            "{e}"
        );
        assert!(
            e.contains("without a header") && e.contains("(3 targets)"),
            "{e}"
        );
        // A header that names only unshared targets, and rows without a header, still work.
        let rows = parse_named_weights(p(), "jaw\n0.5\n", false, &names).unwrap();
        assert_eq!(rows[0].values, [0.0, 0.5, 0.0]);
        let rows = parse_named_weights(p(), "0.1,0.2,0.3\n", false, &names).unwrap();
        assert_eq!(rows[0].values, [0.1, 0.2, 0.3]);
    }

    #[test]
    fn json_forms() {
        let rows = parse_weights(p(), "\u{feff}{\"frames\": [[0.5], [1]]}", false).unwrap();
        assert_eq!(rows.len(), 2);
        assert_eq!(rows[1].values, [1.0]);
        let e = parse_weights(p(), "[[0.5, \"a\"]]", true)
            .unwrap_err()
            .to_string();
        assert!(e.contains("frame 0, weight 1"), "{e}");
        let e = parse_weights(p(), "[]", true).unwrap_err().to_string();
        assert!(e.contains("no weight rows"), "{e}");
    }
}
