//! Reading whole files (gunzipping where needed) and splitting text into lines and tokens
//! without allocating per line.

use super::IoError;
use std::io::Read;
use std::path::Path;

/// The bytes of `path`, decompressed when the file starts with the gzip magic `1f 8b`.
///
/// A file named `*.gz` must be gzip data. Several concatenated gzip members are read as one
/// stream (as `gunzip` does), and zero bytes after the last member (tape padding) are ignored;
/// anything else after it is an error naming its byte offset.
///
/// Errors: a directory ([`IoError::IsDirectory`]), an unreadable file ([`IoError::Os`]), an
/// empty file or an empty decompressed stream ([`IoError::Empty`]), a `.gz` file that is not
/// gzip data, a corrupt or truncated gzip stream, trailing data.
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>, IoError> {
    if path.is_dir() {
        return Err(IoError::IsDirectory {
            path: path.to_path_buf(),
        });
    }
    let raw = std::fs::read(path).map_err(|e| IoError::os(path, "read the file", e))?;
    let named_gz = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gz"));
    let bytes = if raw.starts_with(&GZIP_MAGIC) {
        gunzip(path, &raw)?
    } else if named_gz && !raw.is_empty() {
        return Err(IoError::content(
            path,
            format!(
                "is named .gz but is not gzip data (it starts with {}, not the gzip magic 1f 8b)",
                hex_prefix(&raw)
            ),
        ));
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

const GZIP_MAGIC: [u8; 2] = [0x1f, 0x8b];

/// The first bytes of `b` in hex, for messages.
fn hex_prefix(b: &[u8]) -> String {
    let head: Vec<String> = b.iter().take(4).map(|x| format!("{x:02x}")).collect();
    head.join(" ")
}

/// Decompresses every gzip member of `raw` (which starts with the gzip magic).
pub(crate) fn gunzip(path: &Path, raw: &[u8]) -> Result<Vec<u8>, IoError> {
    let mut out = Vec::with_capacity(raw.len().saturating_mul(4));
    let mut rest = raw;
    let mut member = 0;
    while !rest.is_empty() {
        let offset = (raw.len() - rest.len()) as u64;
        if member > 0 && !rest.starts_with(&GZIP_MAGIC) {
            if rest.iter().all(|&b| b == 0) {
                break;
            }
            return Err(IoError::binary(
                path,
                offset,
                format!(
                    "{} bytes of trailing data after the end of the gzip stream",
                    rest.len()
                ),
            ));
        }
        let mut dec = flate2::bufread::GzDecoder::new(rest);
        if let Err(e) = dec.read_to_end(&mut out) {
            let message = if e.kind() == std::io::ErrorKind::UnexpectedEof {
                format!("the gzip stream (member {member}) is truncated")
            } else {
                format!("corrupt gzip stream (member {member}): {e}")
            };
            return Err(IoError::binary(path, offset, message));
        }
        rest = dec.into_inner();
        member += 1;
    }
    Ok(out)
}

/// `bytes` without a leading UTF-8 byte-order mark (`EF BB BF`), which some Windows editors
/// write at the start of text files. Every text format strips it before parsing.
pub fn strip_bom(bytes: &[u8]) -> &[u8] {
    bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes)
}

/// Like [`strip_bom`], for text.
pub fn strip_bom_str(text: &str) -> &str {
    text.strip_prefix('\u{feff}').unwrap_or(text)
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
