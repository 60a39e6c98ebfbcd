//! Per-frame weight vectors from a file: JSON (`{"frames": [[…], …]}`, `{"weights": …}` or a
//! bare array of arrays) or CSV (one row per frame; `#` comments, blank lines and a
//! non-numeric header line skipped), the formats of `morphkit blend --weights-file`.

use std::path::Path;

/// The rows of `path`, or a message naming the file and line.
pub(crate) fn read(path: &Path) -> Result<Vec<Vec<f64>>, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("{}: cannot read the weights file: {e}", path.display()))?;
    let json = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"))
        || text.trim_start().starts_with(['[', '{']);
    let rows: Vec<Vec<f64>> = if json {
        let v: serde_json::Value = serde_json::from_str(&text)
            .map_err(|e| format!("{}: invalid JSON: {e}", path.display()))?;
        let arr = v.get("frames").or_else(|| v.get("weights")).unwrap_or(&v);
        serde_json::from_value(arr.clone()).map_err(|_| {
            format!(
                "{}: expected an array of weight arrays (or {{\"frames\": [[…], …]}})",
                path.display()
            )
        })?
    } else {
        let mut rows = Vec::new();
        for (n, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let parsed: Result<Vec<f64>, _> = line
                .split([',', ';', '\t'])
                .map(|s| s.trim().parse::<f64>())
                .collect();
            match parsed {
                Ok(r) => rows.push(r),
                Err(_) if rows.is_empty() && n == 0 => continue,
                Err(e) => {
                    return Err(format!(
                        "{}: line {}: {e} in '{line}'",
                        path.display(),
                        n + 1
                    ))
                }
            }
        }
        rows
    };
    if rows.is_empty() {
        return Err(format!("{}: no weight rows", path.display()));
    }
    Ok(rows)
}
