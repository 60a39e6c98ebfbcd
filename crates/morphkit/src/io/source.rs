//! Reading whole files (gunzipping where needed) and splitting text into lines and tokens
//! without allocating per line.

use super::IoError;
use std::io::Read;
use std::path::Path;

/// The bytes of `path`, decompressed when the file starts with the gzip magic `1f 8b`.
///
/// Errors: a directory ([`IoError::IsDirectory`]), an unreadable file ([`IoError::Os`]), an
/// empty file or an empty decompressed stream ([`IoError::Empty`]), a corrupt gzip stream.
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>, IoError> {
    if path.is_dir() {
        return Err(IoError::IsDirectory {
            path: path.to_path_buf(),
        });
    }
    let raw = std::fs::read(path).map_err(|e| IoError::os(path, "read the file", e))?;
    let bytes = if raw.starts_with(&[0x1f, 0x8b]) {
        let mut out = Vec::with_capacity(raw.len() * 4);
        flate2::read::MultiGzDecoder::new(raw.as_slice())
            .read_to_end(&mut out)
            .map_err(|e| IoError::os(path, "decompress the gzip stream", e))?;
        out
    } else {
        raw
    };
    if bytes.is_empty() {
        return Err(IoError::Empty {
            path: path.to_path_buf(),
        });
    }
    Ok(bytes)
}

/// Lines of `bytes` with their 1-based numbers, `\r\n` and `\n` endings stripped.
pub(crate) fn lines(bytes: &[u8]) -> impl Iterator<Item = (usize, &[u8])> {
    bytes.split(|&b| b == b'\n').enumerate().map(|(i, l)| {
        let l = l.strip_suffix(b"\r").unwrap_or(l);
        (i + 1, l)
    })
}

/// Whitespace-separated tokens of a line.
pub(crate) fn tokens(line: &[u8]) -> impl Iterator<Item = &[u8]> {
    line.split(|b| b.is_ascii_whitespace())
        .filter(|t| !t.is_empty())
}

/// A token as text for error messages (lossy, shortened).
pub(crate) fn show(tok: &[u8]) -> String {
    let s = String::from_utf8_lossy(tok);
    if s.chars().count() > 40 {
        format!("{}…", s.chars().take(40).collect::<String>())
    } else {
        s.into_owned()
    }
}

/// Parses a floating-point token (Rust syntax: `1`, `-2.5e-3`, `inf`, `nan`).
pub(crate) fn parse_f64(tok: &[u8]) -> Option<f64> {
    std::str::from_utf8(tok).ok()?.parse().ok()
}

/// Parses a signed integer token.
pub(crate) fn parse_i64(tok: &[u8]) -> Option<i64> {
    std::str::from_utf8(tok).ok()?.parse().ok()
}
