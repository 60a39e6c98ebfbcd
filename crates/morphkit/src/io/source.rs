//! Reading whole files (gunzipping where needed) and splitting text into lines and tokens
//! without allocating per line.

use super::IoError;
use std::io::{BufRead, Read};
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

/// The bytes of `path` exactly as they are, never decompressed: for what is embedded or
/// copied rather than parsed (a glTF's external images), where a file that starts with the
/// gzip magic is still only bytes. Errors as [`read_file`]'s: a directory, an unreadable or an
/// empty file.
pub(crate) fn read_raw(path: &Path) -> Result<Vec<u8>, IoError> {
    if path.is_dir() {
        return Err(IoError::IsDirectory {
            path: path.to_path_buf(),
        });
    }
    let bytes = std::fs::read(path).map_err(|e| IoError::os(path, "read the file", e))?;
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
    let mut out = Vec::new();
    gunzip_stream(path, raw, |chunk| {
        // A stream that inflates past what memory holds is an error, not an abort.
        out.try_reserve(chunk.len()).map_err(|e| {
            IoError::content(
                path,
                format!(
                    "the gzip data inflates to more than {} bytes, which cannot be held: {e}",
                    out.len()
                ),
            )
        })?;
        out.extend_from_slice(chunk);
        Ok(())
    })?;
    Ok(out)
}

/// Decompresses the gzip members of `input` (which starts with the gzip magic) in chunks of
/// at most 1 MiB, handing each to `on_chunk`. Zero bytes after the last member (tape padding)
/// are ignored; other trailing data, a corrupt or a truncated member are errors naming the
/// byte offset.
fn gunzip_stream(
    path: &Path,
    mut input: impl BufRead,
    mut on_chunk: impl FnMut(&[u8]) -> Result<(), IoError>,
) -> Result<(), IoError> {
    let mut chunk = vec![0u8; 1 << 20];
    let mut offset = 0u64;
    let mut member = 0;
    loop {
        let head = input
            .fill_buf()
            .map_err(|e| IoError::os(path, "read the file", e))?;
        if head.is_empty() {
            return Ok(());
        }
        if member > 0 && !head.starts_with(&GZIP_MAGIC) {
            let mut rest = Vec::new();
            input
                .read_to_end(&mut rest)
                .map_err(|e| IoError::os(path, "read the file", e))?;
            if rest.iter().all(|&b| b == 0) {
                return Ok(());
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
        let start = offset;
        let mut dec = flate2::bufread::GzDecoder::new(CountingReader {
            inner: &mut input,
            count: &mut offset,
        });
        loop {
            let k = match dec.read(&mut chunk) {
                Ok(k) => k,
                Err(e) => {
                    let message = if e.kind() == std::io::ErrorKind::UnexpectedEof {
                        format!("the gzip stream (member {member}) is truncated")
                    } else {
                        format!("corrupt gzip stream (member {member}): {e}")
                    };
                    return Err(IoError::binary(path, start, message));
                }
            };
            if k == 0 {
                break;
            }
            on_chunk(&chunk[..k])?;
        }
        member += 1;
    }
}

/// The longest line [`for_each_line`] accepts: far beyond any mesh record (a face of 10⁵
/// vertices is about 1 MB), short enough that a stream without line breaks (a decompression
/// bomb of zeros) is stopped after this many bytes.
pub(crate) const MAX_LINE: usize = 16 << 20;

/// Calls `f(line_number, line)` for every line of the text file `path` (1-based numbers,
/// `\r\n` and `\n` endings stripped, a leading byte-order mark removed), with the errors of
/// [`read_file`]. A gzip file (by magic) is decompressed as a stream, so memory stays bounded
/// by the longest line whatever the file expands to; a line longer than [`MAX_LINE`] is an
/// error naming its number.
pub(crate) fn for_each_line(
    path: &Path,
    mut f: impl FnMut(usize, &[u8]) -> Result<(), IoError>,
) -> Result<(), IoError> {
    if path.is_dir() {
        return Err(IoError::IsDirectory {
            path: path.to_path_buf(),
        });
    }
    let file = std::fs::File::open(path).map_err(|e| IoError::os(path, "read the file", e))?;
    let mut input = std::io::BufReader::with_capacity(1 << 16, file);
    let head = input
        .fill_buf()
        .map_err(|e| IoError::os(path, "read the file", e))?;
    if !head.starts_with(&GZIP_MAGIC) {
        drop(input);
        let bytes = read_file(path)?;
        for (n, line) in lines(strip_bom(&bytes)) {
            f(n, line)?;
        }
        return Ok(());
    }
    let mut lines = LineSplitter::default();
    gunzip_stream(path, input, |chunk| lines.push(path, chunk, &mut f))?;
    if lines.bytes == 0 {
        return Err(IoError::Empty {
            path: path.to_path_buf(),
        });
    }
    lines.finish(&mut f)
}

/// A `BufRead` that counts the bytes consumed from it (the offset for gzip errors).
struct CountingReader<'a, R> {
    inner: &'a mut R,
    count: &'a mut u64,
}

impl<R: BufRead> Read for CountingReader<'_, R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let k = self.inner.read(buf)?;
        *self.count += k as u64;
        Ok(k)
    }
}

impl<R: BufRead> std::io::BufRead for CountingReader<'_, R> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        self.inner.fill_buf()
    }
    fn consume(&mut self, amt: usize) {
        *self.count += amt as u64;
        self.inner.consume(amt);
    }
}

/// Splits a stream of chunks into lines (ended by `\n`, `\r\n` or a lone `\r`, as [`lines`]
/// splits them), keeping only the unfinished last line.
#[derive(Default)]
struct LineSplitter {
    partial: Vec<u8>,
    number: usize,
    bytes: u64,
    /// The last line ended with `\r`: a `\n` at the start of the next chunk belongs to it.
    after_cr: bool,
}

impl LineSplitter {
    fn push(
        &mut self,
        path: &Path,
        mut chunk: &[u8],
        f: &mut impl FnMut(usize, &[u8]) -> Result<(), IoError>,
    ) -> Result<(), IoError> {
        if self.bytes == 0 {
            chunk = strip_bom(chunk);
        }
        self.bytes += chunk.len() as u64;
        loop {
            if self.after_cr && !chunk.is_empty() {
                self.after_cr = false;
                chunk = chunk.strip_prefix(b"\n").unwrap_or(chunk);
            }
            let Some(i) = chunk.iter().position(|&b| b == b'\n' || b == b'\r') else {
                break;
            };
            self.number += 1;
            if self.partial.is_empty() {
                f(self.number, &chunk[..i])?;
            } else {
                self.partial.extend_from_slice(&chunk[..i]);
                self.check(path)?;
                let line = std::mem::take(&mut self.partial);
                f(self.number, &line)?;
                self.partial = line;
                self.partial.clear();
            }
            self.after_cr = chunk[i] == b'\r';
            chunk = &chunk[i + 1..];
        }
        self.partial.extend_from_slice(chunk);
        self.check(path)
    }

    fn check(&self, path: &Path) -> Result<(), IoError> {
        if self.partial.len() > MAX_LINE {
            return Err(IoError::parse(
                path,
                self.number + 1,
                format!(
                    "the line is longer than {} MiB (no line break in the data; not a text mesh?)",
                    MAX_LINE >> 20
                ),
            ));
        }
        Ok(())
    }

    fn finish(
        self,
        f: &mut impl FnMut(usize, &[u8]) -> Result<(), IoError>,
    ) -> Result<(), IoError> {
        f(self.number + 1, &self.partial)
    }
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

/// Lines of `bytes` with their 1-based numbers, the `\n`, `\r\n` and lone `\r` (classic Mac)
/// endings stripped.
pub(crate) fn lines(bytes: &[u8]) -> impl Iterator<Item = (usize, &[u8])> {
    lines_with_ends(bytes).map(|(n, l, _)| (n, l))
}

/// Lines of `bytes` as [`lines`] splits them, each with its line break as the file has it
/// (`\n`, `\r\n` or `\r`; empty for the last line), so that a file can be written back with
/// its own line breaks. Text ending in a line break has an empty last line.
pub(crate) fn lines_with_ends(bytes: &[u8]) -> impl Iterator<Item = (usize, &[u8], &[u8])> {
    let mut rest = Some(bytes);
    let mut number = 0;
    std::iter::from_fn(move || {
        let b = rest?;
        number += 1;
        match b.iter().position(|&c| c == b'\n' || c == b'\r') {
            Some(i) => {
                let end = if b[i] == b'\r' && b.get(i + 1) == Some(&b'\n') {
                    i + 2
                } else {
                    i + 1
                };
                rest = Some(&b[end..]);
                Some((number, &b[..i], &b[i..end]))
            }
            None => {
                rest = None;
                Some((number, b, &b[..0]))
            }
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_end_in_lf_crlf_or_a_lone_cr() {
        let text = b"a\nb\r\nc\rd\r\r\ne";
        let got: Vec<(usize, &[u8], &[u8])> = lines_with_ends(text).collect();
        let want: Vec<(usize, &[u8], &[u8])> = vec![
            (1, b"a", b"\n"),
            (2, b"b", b"\r\n"),
            (3, b"c", b"\r"),
            (4, b"d", b"\r"),
            (5, b"", b"\r\n"),
            (6, b"e", b""),
        ];
        assert_eq!(got, want);
        // A stream splits the same wherever its chunks end (a \r\n across two chunks too).
        for cut in 0..=text.len() {
            let mut split = LineSplitter::default();
            let mut seen: Vec<(usize, Vec<u8>)> = Vec::new();
            let mut f = |n: usize, l: &[u8]| {
                seen.push((n, l.to_vec()));
                Ok(())
            };
            let p = Path::new("t");
            split.push(p, &text[..cut], &mut f).unwrap();
            split.push(p, &text[cut..], &mut f).unwrap();
            split.finish(&mut f).unwrap();
            let want: Vec<(usize, Vec<u8>)> = lines(text).map(|(n, l)| (n, l.to_vec())).collect();
            assert_eq!(seen, want, "cut at {cut}");
        }
    }
}
