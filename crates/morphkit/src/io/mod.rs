//! Mesh file formats.

/// Placeholder until the I/O module lands: writes `bytes` to `path` atomically.
pub fn write_atomic(path: &std::path::Path, bytes: &[u8]) -> std::io::Result<()> {
    let tmp = path.with_extension("morphkit-tmp");
    std::fs::write(&tmp, bytes)?;
    std::fs::rename(tmp, path)
}
