//! A prepared [`InteractiveSpace`] as bytes, so that reopening a rig costs a file read instead
//! of the preparation's solves (issue 38).
//!
//! Layout (little-endian): the magic `MKINTER6`; the rig's key (`u64`, [`Rig::cache_key`]);
//! the shape count $n$, free-coordinate count $n_f$ and vertex count $n_v$; the unconverged
//! count; the diagonal; the preparation's seconds; the $n - 1$ checked errors of frames of
//! one target, then the $n - 1$ of frames of several (version 4 had one list, and each
//! target's snapshots only at ¼, ½, ¾); the snapshot count, then per snapshot its $n$
//! coefficients, its active targets (count, then indices), its left-out error, its error held apart (version 3 had none, so its estimates are refused)
//! and its $n_f$ correction values; then, per target and per sample
//! ([`SAMPLES`](crate::springs::sampled_start::SAMPLES)), the sampled start's correction
//! field: a tag (0 not computed, 1 did not converge, 2 stored) and, for 2, its $3 n_v$
//! values; then, the same way, every pair's field ($t = 2 … n-1$, then $s = 1 … t-1$; version 2
//! had none, and its starts no pair correction, so its snapshots are refused). Every `f64` is stored by its bits, so a loaded space gives the same interactive
//! shapes, bit for bit, as the one that was saved; and since the start's fields come with it,
//! the first slider change after a reopening solves nothing either (version 1 left them out,
//! so each target's first change ran its three sample solves: 1 s on the horse). Last, the
//! checksum ([`checksum`], 8 bytes) of every byte before it: a damaged file is refused
//! whole, where version 5, without one, loaded a perturbed field silently and changed the
//! shapes (issue 55).
//!
//! Every version starts with `MKINTER` ([`is_cache_head`]): a cache file is replaced only
//! when it starts so (or is empty), so that a path given by mistake (`notes.txt`) is never
//! overwritten.

use super::{InteractiveSpace, Snapshot};
use crate::mesh::Point;
use crate::springs::rig::Rig;
use crate::springs::sampled_start::{pair_count, Field, StartSamples, SAMPLES};
use crate::springs::terms::EnergyTerm;
use crate::springs::BlendError;

const MAGIC: &[u8; 8] = b"MKINTER6";

/// What every version of the file starts with (then its version digit).
const FAMILY: &[u8; 7] = b"MKINTER";

/// Whether a file whose first bytes are `head` may be replaced by a new cache: empty, or
/// starting with the magic of some version of the cache (damaged or not).
pub(in crate::springs) fn is_cache_head(head: &[u8]) -> bool {
    head.is_empty() || head.starts_with(FAMILY)
}

/// The trailer's checksum of `bytes`: each 8-byte little-endian word (the last one padded
/// with zeros) enters the state by `h ← m((h ⊕ w) · P)`, with `P` odd and `m(x) = x ⊕ (x ≫ 29)`;
/// the length starts the state and MurmurHash3's finalizer ends it. Every step is a bijection
/// of the state, so two inputs of one length that differ within one word (any single-bit
/// flip) always differ in their checksum; other damage passes with odds of about 2⁻⁶⁴. About
/// 1 ns per word: a 100 MB cache adds a tenth of a second to loading.
pub(in crate::springs) fn checksum(bytes: &[u8]) -> u64 {
    const P: u64 = 0x9e37_79b9_7f4a_7c15;
    let step = |h: u64, w: u64| {
        let x = (h ^ w).wrapping_mul(P);
        x ^ (x >> 29)
    };
    let mut h = 0x6d6b_696e_7465_7236 ^ bytes.len() as u64;
    let mut words = bytes.chunks_exact(8);
    for w in &mut words {
        h = step(h, u64::from_le_bytes(w.try_into().expect("8 bytes")));
    }
    let rest = words.remainder();
    if !rest.is_empty() {
        let mut w = [0u8; 8];
        w[..rest.len()].copy_from_slice(rest);
        h = step(h, u64::from_le_bytes(w));
    }
    h ^= h >> 33;
    h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
    h ^= h >> 33;
    h = h.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    h ^ (h >> 33)
}

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

/// The bytes of `space` and of the start's fields `samples`, prepared for the rig with key
/// `key`, `n` shapes, `nf` free coordinates and `nv` vertices.
pub(in crate::springs) fn encode(
    space: &InteractiveSpace,
    samples: &StartSamples,
    key: u64,
    [n, nf, nv]: [usize; 3],
) -> Vec<u8> {
    let per = 8 * (2 * n + nf + 5);
    let fields = 8 * ((n - 1) * SAMPLES.len() + pair_count(n - 1)) * (1 + 3 * nv);
    let mut out = Vec::with_capacity(80 + 8 * n + per * space.snapshots.len() + fields);
    out.extend_from_slice(MAGIC);
    let word = |out: &mut Vec<u8>, w: u64| out.extend_from_slice(&w.to_le_bytes());
    for w in [
        key,
        n as u64,
        nf as u64,
        nv as u64,
        space.unconverged as u64,
    ] {
        word(&mut out, w);
    }
    word(&mut out, space.diagonal.to_bits());
    word(&mut out, space.prepare_seconds.to_bits());
    for e in space.checked.iter().chain(&space.checked_many) {
        word(&mut out, e.to_bits());
    }
    word(&mut out, space.snapshots.len() as u64);
    for s in &space.snapshots {
        s.c.iter().for_each(|x| word(&mut out, x.to_bits()));
        word(&mut out, s.active.len() as u64);
        s.active.iter().for_each(|&a| word(&mut out, a as u64));
        word(&mut out, s.left_out.to_bits());
        word(&mut out, s.apart.to_bits());
        s.d.iter().for_each(|x| word(&mut out, x.to_bits()));
    }
    let put = |out: &mut Vec<u8>, cell: Option<&Field>| match cell {
        None => word(out, 0),
        Some(None) => word(out, 1),
        Some(Some(field)) => {
            word(out, 2);
            for x in field.iter().flatten() {
                word(out, x.to_bits());
            }
        }
    };
    for s in 1..n {
        for k in 0..SAMPLES.len() {
            put(&mut out, samples.computed(s, k));
        }
    }
    for t in 2..n {
        for s in 1..t {
            put(&mut out, samples.pair_computed(s, t));
        }
    }
    let sum = checksum(&out);
    word(&mut out, sum);
    out
}

/// A decoded preparation: the space, per target and sample the start's field where it was
/// stored (`None`: not computed when saved), and per pair (in the file's order) the same.
pub(in crate::springs) type Decoded = (
    InteractiveSpace,
    Vec<[Option<Field>; 3]>,
    Vec<Option<Field>>,
);

/// Reads what [`encode`] wrote, for the rig with key `key`, `n` shapes, `nf` free
/// coordinates and `nv` vertices; anything else is refused, saying why.
pub(in crate::springs) fn decode(
    bytes: &[u8],
    key: u64,
    [n, nf, nv]: [usize; 3],
) -> Result<Decoded, BlendError> {
    let fail = |problem: String| BlendError::InteractiveCache { problem };
    if bytes.len() < 8 || &bytes[..8] != MAGIC {
        return Err(fail(
            "not a morphkit interactive preparation (or another version of it)".into(),
        ));
    }
    // The checksum first: nothing of a damaged file is used.
    let Some((body, trailer)) = bytes.split_last_chunk::<8>().filter(|(b, _)| b.len() >= 8) else {
        return Err(fail(format!("truncated: {} bytes", bytes.len())));
    };
    let (stored, computed) = (u64::from_le_bytes(*trailer), checksum(body));
    if stored != computed {
        return Err(fail(format!(
            "damaged: the checksum of its {} bytes is {computed:016x}, the file says {stored:016x}",
            body.len()
        )));
    }
    let bytes = body;
    let mut r = Reader { bytes, at: 8 };
    let stored = r.word()?;
    let (sn, snf, snv) = (r.word()? as usize, r.word()? as usize, r.word()? as usize);
    if stored != key || sn != n || snf != nf || snv != nv {
        return Err(fail(format!(
            "made for another rig or other options ({sn} shapes, {snf} free coordinates, {snv} vertices, key {stored:016x}; this rig: {n}, {nf}, {nv}, {key:016x})"
        )));
    }
    let unconverged = r.word()? as usize;
    let diagonal = r.float()?;
    let prepare_seconds = r.float()?;
    let checked = (1..n).map(|_| r.float()).collect::<Result<Vec<_>, _>>()?;
    let checked_many = (1..n).map(|_| r.float()).collect::<Result<Vec<_>, _>>()?;
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
        let apart = r.float()?;
        let d = (0..nf).map(|_| r.float()).collect::<Result<Vec<_>, _>>()?;
        snapshots.push(Snapshot {
            c,
            active,
            d,
            left_out,
            apart,
        });
    }
    let cell =
        |r: &mut Reader<'_>, what: &dyn Fn() -> String| -> Result<Option<Field>, BlendError> {
            Ok(match r.word()? {
                0 => None,
                1 => Some(None),
                2 => {
                    let mut field: Vec<Point> = Vec::with_capacity(nv);
                    for _ in 0..nv {
                        field.push([r.float()?, r.float()?, r.float()?]);
                    }
                    Some(Some(std::sync::Arc::new(field)))
                }
                tag => return Err(fail(format!("{}: unknown field tag {tag}", what()))),
            })
        };
    let mut fields = Vec::with_capacity(n - 1);
    for s in 1..n {
        let mut three: [Option<Field>; 3] = Default::default();
        for (k, c) in three.iter_mut().enumerate() {
            *c = cell(&mut r, &|| format!("target {s}, start sample {k}"))?;
        }
        fields.push(three);
    }
    let mut pairs = Vec::with_capacity(pair_count(n - 1));
    for t in 2..n {
        for s in 1..t {
            pairs.push(cell(&mut r, &|| {
                format!("targets {s} and {t}, start pair")
            })?);
        }
    }
    if r.at != bytes.len() {
        return Err(fail(format!(
            "{} bytes after the last start field",
            bytes.len() - r.at
        )));
    }
    let space = InteractiveSpace::new(
        snapshots,
        [checked, checked_many],
        unconverged,
        diagonal,
        prepare_seconds,
    );
    Ok((space, fields, pairs))
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
