//! A prepared [`InteractiveSpace`] as bytes, so that reopening a rig costs a file read instead
//! of the preparation's solves (issue 38).
//!
//! Layout (little-endian): the magic `MKINTER1`; the rig's key (`u64`, [`Rig::cache_key`]);
//! the shape count $n$ and free-coordinate count $n_f$; the unconverged count; the diagonal;
//! the preparation's seconds; the $n - 1$ checked errors; the snapshot count, then per
//! snapshot its $n$ coefficients, its active targets (count, then indices), its left-out
//! error and its $n_f$ correction values. Every `f64` is stored by its bits, so a loaded space
//! gives the same interactive shapes, bit for bit, as the one that was saved.

use super::{InteractiveSpace, Snapshot};
use crate::springs::rig::Rig;
use crate::springs::terms::EnergyTerm;
use crate::springs::BlendError;

const MAGIC: &[u8; 8] = b"MKINTER1";

impl Rig {
    /// A fingerprint of everything an interactive space depends on: every shape's positions
    /// and the triangles, the options that shape a solve (not memory limits or thread
    /// counts), and each energy term's name and energy at every shape under each shape's
    /// parameters (so extra terms — pulls, anchors — count with their parameters).
    pub(in crate::springs) fn cache_key(&self) -> u64 {
        let mut h = Fnv::default();
        let n = self.shapes.len();
        h.word(n as u64);
        h.word(self.shapes.num_vertices() as u64);
        h.word(self.system.num_free() as u64);
        for t in self.shapes.triangles() {
            t.iter().for_each(|&v| h.word(v as u64));
        }
        let mut flat = Vec::with_capacity(3 * self.shapes.num_vertices());
        let mut options = self.options.clone();
        options.max_memory_bytes = 0;
        options.reference_factor_bytes = 0;
        h.bytes(format!("{options:?}").as_bytes());
        for s in 0..n {
            flat.clear();
            for p in self.shapes.positions(s) {
                flat.extend_from_slice(p);
            }
            flat.iter().for_each(|x| h.word(x.to_bits()));
            let mut c = vec![0.0; n];
            c[s] = 1.0;
            for term in &self.terms {
                h.bytes(term.name().as_bytes());
                h.word(energy(term.as_ref(), &c, &flat).to_bits());
            }
        }
        h.0
    }
}

fn energy(term: &dyn EnergyTerm, c: &[f64], x: &[f64]) -> f64 {
    term.energy(&term.prepare(c), x)
}

/// 64-bit FNV-1a (stable across platforms and releases, unlike `std`'s hasher).
struct Fnv(u64);

impl Default for Fnv {
    fn default() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 ^= x as u64;
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
    fn word(&mut self, w: u64) {
        self.bytes(&w.to_le_bytes());
    }
}

/// The bytes of `space`, prepared for the rig with key `key`.
pub(in crate::springs) fn encode(
    space: &InteractiveSpace,
    key: u64,
    n: usize,
    nf: usize,
) -> Vec<u8> {
    let per = 8 * (2 * n + nf + 4);
    let mut out = Vec::with_capacity(64 + 8 * n + per * space.snapshots.len());
    out.extend_from_slice(MAGIC);
    let word = |out: &mut Vec<u8>, w: u64| out.extend_from_slice(&w.to_le_bytes());
    for w in [key, n as u64, nf as u64, space.unconverged as u64] {
        word(&mut out, w);
    }
    word(&mut out, space.diagonal.to_bits());
    word(&mut out, space.prepare_seconds.to_bits());
    for e in &space.checked {
        word(&mut out, e.to_bits());
    }
    word(&mut out, space.snapshots.len() as u64);
    for s in &space.snapshots {
        s.c.iter().for_each(|x| word(&mut out, x.to_bits()));
        word(&mut out, s.active.len() as u64);
        s.active.iter().for_each(|&a| word(&mut out, a as u64));
        word(&mut out, s.left_out.to_bits());
        s.d.iter().for_each(|x| word(&mut out, x.to_bits()));
    }
    out
}

/// Reads what [`encode`] wrote, for the rig with key `key`, `n` shapes and `nf` free
/// coordinates; anything else is refused, saying why.
pub(in crate::springs) fn decode(
    bytes: &[u8],
    key: u64,
    n: usize,
    nf: usize,
) -> Result<InteractiveSpace, BlendError> {
    let fail = |problem: String| BlendError::InteractiveCache { problem };
    if bytes.len() < 8 || &bytes[..8] != MAGIC {
        return Err(fail(
            "not a morphkit interactive preparation (or another version of it)".into(),
        ));
    }
    let mut r = Reader { bytes, at: 8 };
    let stored = r.word()?;
    let (sn, snf) = (r.word()? as usize, r.word()? as usize);
    if stored != key || sn != n || snf != nf {
        return Err(fail(format!(
            "made for another rig or other options ({sn} shapes, {snf} free coordinates, key {stored:016x}; this rig: {n}, {nf}, {key:016x})"
        )));
    }
    let unconverged = r.word()? as usize;
    let diagonal = r.float()?;
    let prepare_seconds = r.float()?;
    let checked = (1..n).map(|_| r.float()).collect::<Result<Vec<_>, _>>()?;
    let count = r.word()? as usize;
    if count > bytes.len() / 8 {
        return Err(r.truncated());
    }
    let mut snapshots = Vec::with_capacity(count);
    for _ in 0..count {
        let c = (0..n).map(|_| r.float()).collect::<Result<Vec<_>, _>>()?;
        let m = r.word()? as usize;
        if m >= n {
            return Err(fail(format!(
                "a snapshot with {m} active targets of {}",
                n - 1
            )));
        }
        let mut active = Vec::with_capacity(m);
        for _ in 0..m {
            let a = r.word()? as usize;
            if a == 0 || a >= n {
                return Err(fail(format!("a snapshot names shape {a} as a target")));
            }
            active.push(a);
        }
        let left_out = r.float()?;
        let d = (0..nf).map(|_| r.float()).collect::<Result<Vec<_>, _>>()?;
        snapshots.push(Snapshot {
            c,
            active,
            d,
            left_out,
        });
    }
    if r.at != bytes.len() {
        return Err(fail(format!(
            "{} bytes after the last snapshot",
            bytes.len() - r.at
        )));
    }
    Ok(InteractiveSpace {
        snapshots,
        checked,
        unconverged,
        diagonal,
        prepare_seconds,
    })
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn truncated(&self) -> BlendError {
        BlendError::InteractiveCache {
            problem: format!("truncated at byte {} of {}", self.at, self.bytes.len()),
        }
    }
    fn word(&mut self) -> Result<u64, BlendError> {
        let b = self
            .bytes
            .get(self.at..self.at + 8)
            .ok_or_else(|| self.truncated())?;
        self.at += 8;
        Ok(u64::from_le_bytes(b.try_into().expect("8 bytes")))
    }
    fn float(&mut self) -> Result<f64, BlendError> {
        let x = f64::from_bits(self.word()?);
        if x.is_nan() {
            return Err(BlendError::InteractiveCache {
                problem: format!("a NaN at byte {}", self.at - 8),
            });
        }
        Ok(x)
    }
}
