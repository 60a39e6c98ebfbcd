//! Preparing the interactive space ([`PhysicalBlend::prepare_interactive`]), through a cache
//! file or not, and stopping a preparation between its solves
//! ([`PhysicalBlend::prepare_interactive_until`]: a caller's hook, Ctrl-C in Python, is asked
//! before each snapshot solve and each check; a stopped preparation keeps and writes nothing).

use super::super::blender::PhysicalBlend;
use super::super::options::BlendResult;
use super::super::{BlendError, Weights};
use super::{
    decode, encode, fine_target, is_cache_head, snapshot_coefficients, InteractiveSpace, CHECKS,
};

/// The error of a preparation that its caller stopped.
fn stopped() -> BlendError {
    BlendError::Stopped {
        what: "the interactive preparation".into(),
    }
}

impl PhysicalBlend {
    /// Prepares the [interactive mode](super): the canonical solves at the
    /// snapshot weights, spread over up to `threads` threads (the space, hence every
    /// interactive shape, does not depend on the thread count). Done once; later calls return
    /// the prepared space.
    pub fn prepare_interactive(&mut self, threads: usize) -> &InteractiveSpace {
        if self.interactive.is_none() {
            let space = self.space_until(threads, &|| false).expect("never stopped");
            self.interactive = Some(space);
        }
        self.interactive.as_ref().expect("prepared above")
    }

    /// [`prepare_interactive`](Self::prepare_interactive) that a caller can stop: `stop` is
    /// called before each snapshot solve and each check (from every thread that solves; see
    /// [`map_frames_until`](Self::map_frames_until)), and once it returns `true` the
    /// preparation ends after the solves running then, keeps nothing, and fails with
    /// [`BlendError::Stopped`]. The Python module's hook checks for Ctrl-C. Where the space is
    /// prepared already, it is returned and `stop` is not called.
    pub fn prepare_interactive_until(
        &mut self,
        threads: usize,
        stop: &(dyn Fn() -> bool + Sync),
    ) -> Result<&InteractiveSpace, BlendError> {
        if self.interactive.is_none() {
            let space = self.space_until(threads, stop).ok_or_else(stopped)?;
            self.interactive = Some(space);
        }
        Ok(self.interactive.as_ref().expect("prepared above"))
    }

    /// The interactive space's solves (see [`prepare_interactive_until`](Self::prepare_interactive_until));
    /// `None` when `stop` stopped them.
    fn space_until(
        &mut self,
        threads: usize,
        stop: &(dyn Fn() -> bool + Sync),
    ) -> Option<InteractiveSpace> {
        {
            let started = std::time::Instant::now();
            let coefficients = snapshot_coefficients(self.rig.shapes.len());
            let solved = self
                .map_frames_until(&coefficients, threads, stop, |f, c| f.rig.snapshot(f.ws, c))?;
            let targets = self.rig.shapes.len() - 1;
            let mut snapshots = Vec::with_capacity(solved.len());
            let mut unconverged = 0;
            // A target whose snapshot off the coarse weights did not converge has no check
            // for frames of several targets there: its estimate is unknown (infinite).
            let mut checked_many = vec![0.0; targets];
            for (s, c) in solved.into_iter().zip(&coefficients) {
                match s {
                    Some(Some(s)) => snapshots.push(s),
                    _ => {
                        unconverged += 1;
                        if let Some(t) = fine_target(c) {
                            checked_many[t - 1] = f64::INFINITY;
                        }
                    }
                }
            }
            let diagonal = crate::mesh::bbox_diagonal(self.rig.shapes.positions(0));
            let mut space = InteractiveSpace::new(
                snapshots,
                [vec![0.0; targets], checked_many],
                unconverged,
                diagonal,
                0.0,
            );
            // The error estimate's data: each combination left out, and with all of its
            // pair's snapshots (held apart); each target's snapshots off the coarse weights
            // against the coarse ones alone (frames of several targets); each target checked
            // between its snapshots (frames of one).
            let indices: Vec<usize> = (0..space.len()).collect();
            let errors = self.map_frames_until(&indices, threads, stop, |f, &k| {
                let truth = &space.snapshots[k];
                let same: Vec<usize> = (0..space.len())
                    .filter(|&j| space.snapshots[j].active == truth.active)
                    .collect();
                if truth.active.len() == 1 {
                    if !truth.fine() {
                        return (0.0, 0.0);
                    }
                    let fine: Vec<usize> = same
                        .into_iter()
                        .filter(|&j| space.snapshots[j].fine())
                        .collect();
                    return (f.rig.interactive_error(f.ws, &space, truth, &fine), 0.0);
                }
                let left_out = f.rig.interactive_error(f.ws, &space, truth, &[k]);
                (
                    left_out,
                    f.rig.interactive_error(f.ws, &space, truth, &same),
                )
            })?;
            for (k, e) in errors.into_iter().enumerate() {
                let e = e.unwrap_or((f64::INFINITY, f64::INFINITY));
                let s = &mut space.snapshots[k];
                if s.active.len() == 1 {
                    let t = s.active[0] - 1;
                    space.checked_many[t] = space.checked_many[t].max(e.0);
                } else {
                    (s.left_out, s.apart) = e;
                }
            }
            let checks: Vec<(usize, f64)> = (1..=targets)
                .flat_map(|s| CHECKS.iter().map(move |&a| (s, a)))
                .collect();
            let n = self.rig.shapes.len();
            let errors = self.map_frames_until(&checks, threads, stop, |f, &(s, a)| {
                let mut c = vec![0.0; n];
                c[0] = 1.0 - a;
                c[s] = a;
                match f.rig.snapshot(f.ws, &c) {
                    Some(truth) => f.rig.interactive_error(f.ws, &space, &truth, &[]),
                    None => f64::INFINITY,
                }
            })?;
            for (&(s, _), e) in checks.iter().zip(errors) {
                let e = e.unwrap_or(f64::INFINITY);
                space.checked[s - 1] = space.checked[s - 1].max(e);
            }
            space.prepare_seconds = started.elapsed().as_secs_f64();
            Some(space)
        }
    }

    /// The prepared interactive space as bytes (see [`interactive`](super) for
    /// the layout), to be given to [`load_interactive`](Self::load_interactive) when the
    /// same rig is opened again; `None` before [`prepare_interactive`](Self::prepare_interactive).
    pub fn interactive_bytes(&self) -> Option<Vec<u8>> {
        let space = self.interactive.as_ref()?;
        let sizes = self.cache_sizes();
        Some(encode(
            space,
            &self.rig.samples,
            self.rig.cache_key(),
            sizes,
        ))
    }

    /// Takes a preparation saved by [`interactive_bytes`](Self::interactive_bytes): the same
    /// space, so the same interactive shapes bit for bit, without the preparation's solves.
    /// Refused with [`BlendError::InteractiveCache`] when the bytes are damaged, of another
    /// format version, or were made for another rig (other shapes, triangles, options or
    /// energy terms); the blend is then unchanged.
    pub fn load_interactive(&mut self, bytes: &[u8]) -> Result<&InteractiveSpace, BlendError> {
        let (space, fields, pairs) = decode(bytes, self.rig.cache_key(), self.cache_sizes())?;
        let mut pairs = pairs.into_iter();
        for t in 2..self.rig.shapes.len() {
            for s in 1..t {
                if let Some(Some(field)) = pairs.next() {
                    self.rig.samples.restore_pair(s, t, field);
                }
            }
        }
        for (s, three) in fields.into_iter().enumerate() {
            for (k, field) in three.into_iter().enumerate() {
                if let Some(field) = field {
                    self.rig.samples.restore(s + 1, k, field);
                }
            }
        }
        Ok(self.interactive.insert(space))
    }

    /// Shape, free-coordinate and vertex counts, as the interactive cache records them.
    fn cache_sizes(&self) -> [usize; 3] {
        let r = &self.rig;
        [r.shapes.len(), r.system.num_free(), r.shapes.num_vertices()]
    }

    /// [`prepare_interactive`](Self::prepare_interactive) through a cache file: where `path`
    /// holds a preparation of this very rig (same shapes, triangles, options and terms), it is
    /// read instead of solved; otherwise (no file, empty, damaged, another format version,
    /// another rig) the preparation runs and replaces it, written atomically, and
    /// [`InteractiveCacheUse::replaced`] says why, naming the file. Once prepared, the file is
    /// only written where there is none, never read.
    ///
    /// Fails when the file cannot be written, and, leaving it untouched, when it cannot be
    /// read or is not a morphkit interactive preparation of any version (it does not start
    /// with `MKINTER`): a path given by mistake is never overwritten.
    pub fn prepare_interactive_cached(
        &mut self,
        threads: usize,
        path: &std::path::Path,
    ) -> Result<InteractiveCacheUse, BlendError> {
        self.prepare_interactive_cached_until(threads, path, &|| false)
    }

    /// [`prepare_interactive_cached`](Self::prepare_interactive_cached) that a caller can
    /// stop as [`prepare_interactive_until`](Self::prepare_interactive_until): a stopped
    /// preparation fails with [`BlendError::Stopped`] and writes nothing (a file that was there
    /// stays as it was).
    pub fn prepare_interactive_cached_until(
        &mut self,
        threads: usize,
        path: &std::path::Path,
        stop: &(dyn Fn() -> bool + Sync),
    ) -> Result<InteractiveCacheUse, BlendError> {
        let unused = InteractiveCacheUse {
            loaded: false,
            replaced: None,
        };
        if self.interactive.is_some() {
            if !path.exists() {
                self.write_interactive(path)?;
            }
            return Ok(unused);
        }
        let replaced = match read_cache(path)? {
            Some(bytes) => match self.load_interactive(&bytes) {
                Ok(_) => {
                    return Ok(InteractiveCacheUse {
                        loaded: true,
                        ..unused
                    })
                }
                Err(e) => Some(format!("{}: {e}", path.display())),
            },
            None => None,
        };
        self.prepare_interactive_until(threads, stop)?;
        self.write_interactive(path)?;
        Ok(InteractiveCacheUse { replaced, ..unused })
    }

    fn write_interactive(&self, path: &std::path::Path) -> Result<(), BlendError> {
        let bytes = self.interactive_bytes().expect("prepared");
        crate::io::write_atomic(path, &bytes).map_err(|e| BlendError::InteractiveCache {
            problem: format!("cannot write {}: {e}", path.display()),
        })
    }

    /// The interactive space, where prepared.
    pub fn interactive_space(&self) -> Option<&InteractiveSpace> {
        self.interactive.as_ref()
    }

    /// The interactive shape for `weights` (see [`interactive`](super)),
    /// preparing the space on one thread first where it is not prepared.
    /// `refine` projected-Newton steps with the frame's own factorization follow (each one
    /// costs about a full solve's Newton iteration and brings the shape closer).
    pub fn solve_interactive(
        &mut self,
        weights: &Weights,
        refine: usize,
    ) -> Result<BlendResult, BlendError> {
        let c = weights.coefficients(self.rig.shapes.len())?;
        self.prepare_interactive(1);
        let space = self.interactive.as_ref().expect("prepared above");
        self.rig.solve_interactive(&mut self.ws, space, &c, refine)
    }
}

/// The bytes of an interactive cache file (`None` where there is none), refusing a file that
/// cannot be read or is not a cache: only its first bytes are read to tell.
fn read_cache(path: &std::path::Path) -> Result<Option<Vec<u8>>, BlendError> {
    use std::io::Read;
    let fail = |problem: String| BlendError::InteractiveCache { problem };
    let cannot = |e: std::io::Error| {
        fail(format!(
            "cannot read {} to check that it is a cache: {e}; it was left as it is",
            path.display()
        ))
    };
    let mut file = match std::fs::File::open(path) {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(cannot(e)),
    };
    let mut head = Vec::new();
    (&mut file).take(8).read_to_end(&mut head).map_err(cannot)?;
    if !is_cache_head(&head) {
        let shown: Vec<String> = head.iter().map(|b| format!("{b:02x}")).collect();
        return Err(fail(format!(
            "{} is not a morphkit interactive preparation (it starts with {}, not MKINTER); \
             refusing to replace it: give the cache another path",
            path.display(),
            shown.join(" ")
        )));
    }
    let mut bytes = head;
    file.read_to_end(&mut bytes).map_err(cannot)?;
    Ok(Some(bytes))
}

/// How [`PhysicalBlend::prepare_interactive_cached`] used its file.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct InteractiveCacheUse {
    /// The preparation was read from the file (no solves).
    pub loaded: bool,
    /// Why a file that was there was not used (it was replaced), naming the file.
    pub replaced: Option<String>,
}
