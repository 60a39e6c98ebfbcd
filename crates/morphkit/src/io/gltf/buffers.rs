//! Loading the buffers of a glTF document: the GLB `BIN` chunk, base64 `data:` URIs, and
//! external files.
//!
//! External files are resolved **relative to the glTF file's directory only** (glTF 2.0 §3.2:
//! a relative URI reference). Absolute paths, URIs with a scheme (`file:`, `http:`), paths
//! with `..` components, and paths that leave the directory through a symbolic link are
//! refused, and so is anything that is not a regular file (`/dev/zero`, a FIFO). At most the
//! declared `byteLength` is read, so a buffer never costs more memory than the document says,
//! and a buffer holds exactly its `byteLength` bytes (a longer BIN chunk or data URI is cut),
//! within which every buffer view must lie ([`check_views`]). External files are read as
//! they are: never decompressed, even when they start with the gzip magic.

use crate::io::IoError;
use std::io::Read;
use std::path::{Component, Path, PathBuf};

/// The data of every buffer of `doc`, in index order, each at least `byteLength` bytes long.
///
/// `path` is the glTF file (errors name it and the buffer); `blob` is the GLB `BIN` chunk;
/// buffers marked in `fallback` (meshopt compression) are left empty.
pub(crate) fn load_buffers(
    path: &Path,
    doc: &::gltf::Document,
    mut blob: Option<Vec<u8>>,
    fallback: &[bool],
) -> Result<Vec<Vec<u8>>, IoError> {
    let mut out = Vec::with_capacity(doc.buffers().len());
    for buffer in doc.buffers() {
        let i = buffer.index();
        let len = buffer.length();
        // A meshopt fallback buffer is never read (its views are decoded from another buffer);
        // it usually has no data at all.
        if fallback.get(i).copied().unwrap_or(false) {
            out.push(Vec::new());
            continue;
        }
        let at = |m: String| IoError::content(path, format!("buffer {i}: {m}"));
        let data = match buffer.source() {
            ::gltf::buffer::Source::Bin => blob.take().ok_or_else(|| {
                at("has no uri and the file has no GLB binary chunk to refer to".into())
            })?,
            ::gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                let Some((_, payload)) = uri.split_once(";base64,") else {
                    return Err(at("a data: URI that is not base64-encoded".into()));
                };
                decode_base64(payload)
                    .ok_or_else(|| at("invalid base64 in its data: URI".into()))?
            }
            ::gltf::buffer::Source::Uri(uri) => read_external(path, uri, len).map_err(at)?,
        };
        if data.len() < len {
            return Err(at(format!(
                "byteLength is {len} but the data holds only {} bytes",
                data.len()
            )));
        }
        // Bytes past byteLength (a GLB BIN chunk's padding, or more) are not the buffer's: the
        // writer does not keep them, so the reader does not read them either.
        let mut data = data;
        data.truncate(len);
        out.push(data);
    }
    Ok(out)
}

/// Fails when a buffer view, used or not, reaches past its buffer's `byteLength` (glTF 2.0
/// §3.6.1: a view lies within its buffer); the sum is checked, so no offset wraps around.
pub(crate) fn check_views(path: &Path, doc: &::gltf::Document) -> Result<(), IoError> {
    for view in doc.views() {
        let (o, n, b) = (view.offset(), view.length(), view.buffer());
        if o.checked_add(n).is_none_or(|end| end > b.length()) {
            return Err(IoError::content(
                path,
                format!(
                    "buffer view {}: byteOffset {o} + byteLength {n} reaches past the {} bytes \
                     of buffer {} (its byteLength)",
                    view.index(),
                    b.length(),
                    b.index()
                ),
            ));
        }
    }
    Ok(())
}

/// The directory the glTF file's relative URIs refer to.
fn base_dir(gltf: &Path) -> &Path {
    match gltf.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Reads at most `len` bytes of the external buffer file `uri`; errors are messages.
fn read_external(gltf: &Path, uri: &str, len: usize) -> Result<Vec<u8>, String> {
    let file = resolve_uri(gltf, uri)?;
    let show = file.display();
    let meta = std::fs::metadata(&file).map_err(|e| format!("{show} (uri '{uri}'): {e}"))?;
    if !meta.is_file() {
        return Err(format!(
            "{show} (uri '{uri}') is not a regular file; buffers must be files next to the glTF"
        ));
    }
    if meta.len() < len as u64 {
        return Err(format!(
            "{show} (uri '{uri}') has {} bytes, but byteLength declares {len}",
            meta.len()
        ));
    }
    let f = std::fs::File::open(&file).map_err(|e| format!("{show} (uri '{uri}'): {e}"))?;
    let mut data = Vec::with_capacity(len);
    f.take(len as u64)
        .read_to_end(&mut data)
        .map_err(|e| format!("{show} (uri '{uri}'): {e}"))?;
    Ok(data)
}

/// The file a buffer URI names, inside the glTF file's directory; errors are messages.
pub(crate) fn resolve_uri(gltf: &Path, uri: &str) -> Result<PathBuf, String> {
    let decoded = percent_decode(uri)
        .ok_or_else(|| format!("uri '{uri}' is not valid UTF-8 after percent-decoding"))?;
    if decoded.is_empty() {
        return Err("has an empty uri".into());
    }
    let scheme = decoded
        .split_once(':')
        .is_some_and(|(s, _)| !s.is_empty() && !s.contains(['/', '\\']));
    let rel = Path::new(&decoded);
    if scheme || rel.is_absolute() || decoded.starts_with(['/', '\\']) {
        return Err(format!(
            "uri '{uri}' is absolute or has a scheme; only paths relative to the glTF file are read"
        ));
    }
    if rel
        .components()
        .any(|c| !matches!(c, Component::Normal(_) | Component::CurDir))
        || decoded.split(['/', '\\']).any(|c| c == "..")
    {
        return Err(format!(
            "uri '{uri}' leaves the glTF file's directory; only files inside it are read"
        ));
    }
    let dir = base_dir(gltf);
    let file = dir.join(rel);
    // A symbolic link inside the directory may still point out of it.
    if let (Ok(d), Ok(f)) = (dir.canonicalize(), file.canonicalize()) {
        if !f.starts_with(&d) {
            return Err(format!(
                "uri '{uri}' resolves to {}, outside the glTF file's directory",
                f.display()
            ));
        }
    }
    Ok(file)
}

/// Decodes `%XX` escapes (URIs in glTF are URI-encoded); `None` for invalid UTF-8.
fn percent_decode(s: &str) -> Option<String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8(out).ok()
}

/// Standard base64 (with optional `=` padding, whitespace ignored); `None` when invalid.
fn decode_base64(s: &str) -> Option<Vec<u8>> {
    let val = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return None,
        } as u32)
    };
    let mut out = Vec::with_capacity(s.len() / 4 * 3);
    let (mut acc, mut bits) = (0u32, 0u32);
    let body = s.trim_end_matches(|c: char| c == '=' || c.is_ascii_whitespace());
    for c in body.bytes().filter(|c| !c.is_ascii_whitespace()) {
        acc = (acc << 6) | val(c)?;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_and_percent_decoding() {
        assert_eq!(decode_base64("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(decode_base64("aGVsbG8h").unwrap(), b"hello!");
        assert!(decode_base64("a*b").is_none());
        assert_eq!(percent_decode("a%20b.bin").unwrap(), "a b.bin");
        assert_eq!(percent_decode("100%").unwrap(), "100%");
    }

    #[test]
    fn uris_outside_the_directory_are_refused() {
        let g = Path::new("/tmp/some/dir/a.gltf");
        for bad in [
            "/dev/zero",
            "../x.bin",
            "sub/../../x.bin",
            "%2e%2e/x.bin",
            "file:///etc/passwd",
            "C:/x.bin",
            "",
        ] {
            assert!(resolve_uri(g, bad).is_err(), "{bad}");
        }
        assert_eq!(
            resolve_uri(g, "sub/a%20b.bin").unwrap(),
            Path::new("/tmp/some/dir/sub/a b.bin")
        );
    }
}
