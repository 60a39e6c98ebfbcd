//! PC2 point caches (3ds Max, Blender's Mesh Cache modifier).
//!
//! Little endian throughout. A 32-byte header — `"POINTCACHE2\0"`, `i32` version (1), `i32`
//! number of points, `f32` start frame, `f32` sample rate (frames between samples), `i32`
//! number of samples — then `f32` x, y, z per point per sample. A cache holds positions only;
//! the connectivity comes from a reference mesh. The frame rate is not stored.

use super::IoError;
use crate::mesh::Point;
use std::io::Write;
use std::path::Path;

const MAGIC: &[u8; 12] = b"POINTCACHE2\0";
const HEADER: usize = 32;

/// The samples of a point cache with its timing header.
#[derive(Clone, Debug, PartialEq)]
pub struct PointCache {
    /// Frame of the first sample.
    pub start_frame: f32,
    /// Frames between consecutive samples.
    pub sample_rate: f32,
    /// One position array per sample, each with the same number of points.
    pub samples: Vec<Vec<Point>>,
}

fn i32_at(b: &[u8], o: usize) -> i32 {
    i32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]])
}
fn f32_at(b: &[u8], o: usize) -> f32 {
    f32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]])
}

/// Parses a PC2 file's bytes. Errors name the byte offset: a wrong magic or version, negative
/// counts, a body shorter than the header promises, non-finite values (with the sample and
/// point).
pub fn parse_pc2(path: &Path, b: &[u8]) -> Result<PointCache, IoError> {
    if b.len() < HEADER {
        return Err(IoError::binary(
            path,
            b.len() as u64,
            format!("the file ends inside the {HEADER}-byte PC2 header"),
        ));
    }
    if &b[..12] != MAGIC {
        return Err(IoError::binary(
            path,
            0,
            "not a PC2 file: no 'POINTCACHE2' signature",
        ));
    }
    let version = i32_at(b, 12);
    if version != 1 {
        return Err(IoError::binary(
            path,
            12,
            format!("unsupported PC2 version {version}"),
        ));
    }
    let (np, ns) = (i32_at(b, 16), i32_at(b, 28));
    if np < 0 || ns < 0 {
        return Err(IoError::binary(
            path,
            16,
            format!("negative counts: {np} points, {ns} samples"),
        ));
    }
    let (np, ns) = (np as usize, ns as usize);
    if np == 0 && ns > 0 {
        return Err(IoError::binary(
            path,
            16,
            format!("the header promises {ns} samples of 0 points"),
        ));
    }
    // Saturating: `np` and `ns` may each be up to 2³¹, and 12 · np · ns overflows 64 bits.
    let need = (12 * np as u64)
        .saturating_mul(ns as u64)
        .saturating_add(HEADER as u64);
    if (b.len() as u64) < need {
        let full = (b.len() - HEADER) / (12 * np.max(1));
        return Err(IoError::binary(
            path,
            b.len() as u64,
            format!(
                "the file ends in sample {full}: the header promises {ns} samples of {np} points ({need} bytes), the file has {} bytes",
                b.len()
            ),
        ));
    }
    // The length check above bounds `ns * np` by the file size; cap anyway so that no header
    // can make a reservation larger than the file could fill.
    let room = (b.len() - HEADER) / 12;
    let mut samples = Vec::with_capacity(ns.min(room));
    for s in 0..ns {
        let mut pts = Vec::with_capacity(np.min(room));
        for p in 0..np {
            let o = HEADER + 12 * (s * np + p);
            let q = [
                f32_at(b, o) as f64,
                f32_at(b, o + 4) as f64,
                f32_at(b, o + 8) as f64,
            ];
            if q.iter().any(|x| !x.is_finite()) {
                return Err(IoError::binary(
                    path,
                    o as u64,
                    format!("sample {s}, point {p} has a non-finite coordinate {q:?}"),
                ));
            }
            pts.push(q);
        }
        samples.push(pts);
    }
    Ok(PointCache {
        start_frame: f32_at(b, 20),
        sample_rate: f32_at(b, 24),
        samples,
    })
}

/// Writes a point cache (positions rounded to `f32`). All samples must have the same number of
/// points, else an [`IoError::Content`] error naming the first offending sample.
pub fn write_pc2(path: &Path, cache: &PointCache) -> Result<(), IoError> {
    let np = cache.samples.first().map_or(0, Vec::len);
    if let Some(s) = cache.samples.iter().position(|s| s.len() != np) {
        return Err(IoError::content(
            path,
            format!(
                "sample {s} has {} points, sample 0 has {np}",
                cache.samples[s].len()
            ),
        ));
    }
    let too_big = |n: usize| i32::try_from(n).is_err();
    if too_big(np) || too_big(cache.samples.len()) {
        return Err(IoError::content(
            path,
            "too many points or samples for PC2's 32-bit counts",
        ));
    }
    for (k, s) in cache.samples.iter().enumerate() {
        super::atomic::check_fits_f32(path, &format!("sample {k}"), s)?;
    }
    super::atomic::write_atomic_with(path, |w: &mut dyn Write| {
        write_header(
            w,
            np,
            cache.start_frame,
            cache.sample_rate,
            cache.samples.len(),
        )?;
        for s in &cache.samples {
            for p in s {
                for x in p {
                    w.write_all(&(*x as f32).to_le_bytes())?;
                }
            }
        }
        Ok(())
    })
}

/// Writes the 32-byte header of a cache of `samples` samples of `points` points (counts that
/// fit PC2's `i32`, checked by the callers).
pub(crate) fn write_header(
    w: &mut dyn Write,
    points: usize,
    start_frame: f32,
    sample_rate: f32,
    samples: usize,
) -> std::io::Result<()> {
    w.write_all(MAGIC)?;
    w.write_all(&1i32.to_le_bytes())?;
    w.write_all(&(points as i32).to_le_bytes())?;
    w.write_all(&start_frame.to_le_bytes())?;
    w.write_all(&sample_rate.to_le_bytes())?;
    w.write_all(&(samples as i32).to_le_bytes())
}

#[cfg(test)]
mod fuzz_regressions {
    use super::*;

    /// Issue 39: coordinates beyond f32's range were written as ±inf with exit status 0.
    #[test]
    fn values_beyond_f32_are_refused_and_nothing_is_written() {
        let p = std::env::temp_dir().join(format!("morphkit-pc2-big-{}.pc2", std::process::id()));
        let cache = PointCache {
            start_frame: 0.0,
            sample_rate: 1.0,
            samples: vec![vec![[0.0; 3]; 2], vec![[0.0, 1e150, 0.0], [0.0; 3]]],
        };
        let e = write_pc2(&p, &cache).unwrap_err().to_string();
        assert!(e.contains("sample 1: vertex 0"), "{e}");
        assert!(e.contains("not representable as f32"), "{e}");
        assert!(!p.exists());
        // A denormal mesh would collapse to one point in single precision.
        let cache = PointCache {
            start_frame: 0.0,
            sample_rate: 1.0,
            samples: vec![vec![[1e-310, 0.0, 0.0], [0.0, 2e-310, 0.0]]],
        };
        let e = write_pc2(&p, &cache).unwrap_err().to_string();
        assert!(e.contains("sample 0: every coordinate is below"), "{e}");
        assert!(!p.exists());
    }

    /// Found by `cargo fuzz` (target `pc2`): counts whose product overflowed the size check.
    #[test]
    fn huge_counts_are_an_error_not_an_overflow() {
        let mut b = MAGIC.to_vec();
        b.extend_from_slice(&1i32.to_le_bytes());
        b.extend_from_slice(&i32::MAX.to_le_bytes());
        b.extend_from_slice(&0f32.to_le_bytes());
        b.extend_from_slice(&1f32.to_le_bytes());
        b.extend_from_slice(&i32::MAX.to_le_bytes());
        b.extend_from_slice(&[0; 12]);
        let e = parse_pc2(Path::new("x.pc2"), &b).unwrap_err().to_string();
        assert!(e.contains("the header promises 2147483647 samples"), "{e}");
        // The byte count saturates instead of wrapping around.
        assert!(e.contains(&format!("({} bytes)", u64::MAX)), "{e}");
    }
}
