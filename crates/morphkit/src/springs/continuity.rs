//! Jumps between consecutive frames of a sequence: where a physical blend snaps.
//!
//! The canonical equilibrium is a function of the weights alone, but the spring energy of a
//! rig can have two equilibria over a range of weights (two bending states of a joint: distance
//! springs across a fold line fit a fold either way; see docs/performance.md, "Whole
//! sequences on every real rig"). A sequence that crosses such a range *jumps*: between two
//! frames a part moves by many times the linear blend's step. Nothing converges badly there,
//! so the solver's own report cannot tell; this check compares each step with the linear
//! blend's.
//!
//! For frames $k-1, k$ with physical positions $x$ and linear blends $L$ (`#V × 3` each), the
//! *step ratio* is
//!
//! $$\rho_k = \max_v \lVert x^k_v - x^{k-1}_v\rVert \,/\, \max\bigl(\max_v \lVert L^k_v -
//! L^{k-1}_v\rVert,\ \varepsilon\bigr),$$
//!
//! with the floor $\varepsilon = 10^{-6}$ × the base's bounding-box diagonal, the accuracy the
//! canonical equilibrium is defined to (frames of almost equal weights are not compared on
//! round-off). A pair with $\rho_k >$ [`JUMP_BOUND`] is a [`Jump`]; its region is every
//! vertex whose own step exceeds the bound times the same denominator.

use super::BlendError;
use crate::mesh::{norm, sub, Point};

/// Consecutive frames may move a vertex by at most this multiple of the linear blend's
/// largest step between the same weights. A vertex carried along an arc of angle θ ≤ π
/// travels at most θ / (2 sin θ/2) ≤ π/2 times its chord, and the equilibrium may move up to
/// twice as fast in the weights as uniformly (rest lengths are linear in the weights,
/// positions are not): 2 · π/2 ≈ 3.1 < 4. A snap to another equilibrium moves a part by many
/// steps at once (5.8–8.8× on three horse legs, 25× on the ICT jawOpen gums, 36 steps, before
/// the [predictor tether](super::tether) joined those equilibria).
pub const JUMP_BOUND: f64 = 4.0;

/// Two consecutive frames between which a part moved more than [`JUMP_BOUND`] allows.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Jump {
    /// The two frames (indices in the sequence, consecutive).
    pub frames: [usize; 2],
    /// The step ratio $\rho_k$ (module docs).
    pub ratio: f64,
    /// The vertex that moved most.
    pub vertex: u32,
    /// Every vertex whose step exceeds the bound, ascending.
    pub vertices: Vec<u32>,
}

/// What [`ContinuityCheck`] found over a sequence.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Continuity {
    /// The bound the ratios were checked against.
    pub bound: f64,
    /// The largest step ratio over all consecutive pairs (0 for fewer than two frames).
    pub worst_ratio: f64,
    /// The pair where it is.
    pub worst_frames: Option<[usize; 2]>,
    /// Every pair above the bound, in sequence order.
    pub jumps: Vec<Jump>,
}

impl Continuity {
    /// Every vertex of any jump, ascending and without repeats.
    pub fn jump_vertices(&self) -> Vec<u32> {
        let mut v: Vec<u32> = self.jumps.iter().flat_map(|j| j.vertices.clone()).collect();
        v.sort_unstable();
        v.dedup();
        v
    }
}

/// Checks a sequence frame by frame, holding only the previous frame (and its linear blend),
/// so that long sequences are checked as they are written.
#[derive(Clone, Debug)]
pub struct ContinuityCheck {
    floor: f64,
    previous: Option<(Vec<Point>, Vec<Point>)>,
    next_frame: usize,
    found: Continuity,
}

impl ContinuityCheck {
    /// A check against `bound` (usually [`JUMP_BOUND`]) for a mesh whose base has bounding-box
    /// diagonal `diagonal`.
    pub fn new(bound: f64, diagonal: f64) -> Self {
        Self {
            floor: 1e-6 * diagonal,
            previous: None,
            next_frame: 0,
            found: Continuity {
                bound,
                worst_ratio: 0.0,
                worst_frames: None,
                jumps: Vec::new(),
            },
        }
    }

    /// The next frame: its physical positions and its linear blend (`#V` each). Frames of
    /// one sequence share their vertices: a frame whose positions or linear blend have another
    /// count than the first frame's is refused (and not counted).
    pub fn push(&mut self, positions: &[Point], linear: &[Point]) -> Result<(), BlendError> {
        let k = self.next_frame;
        let expected = self
            .previous
            .as_ref()
            .map_or(positions.len(), |p| p.0.len());
        if positions.len() != expected || linear.len() != expected {
            return Err(BlendError::InvalidOption(format!(
                "frame {k} of the sequence has {} positions and {} linear-blend positions; the sequence has {expected} vertices",
                positions.len(),
                linear.len()
            )));
        }
        self.next_frame += 1;
        if let Some((px, pl)) = &self.previous {
            let dist = |a: &Point, b: &Point| norm(sub(*a, *b));
            let lin = pl
                .iter()
                .zip(linear)
                .fold(0.0f64, |m, (a, b)| m.max(dist(a, b)));
            let denominator = lin.max(self.floor).max(f64::MIN_POSITIVE);
            let steps: Vec<f64> = px.iter().zip(positions).map(|(a, b)| dist(a, b)).collect();
            let (vertex, step) =
                steps
                    .iter()
                    .enumerate()
                    .fold((0, 0.0f64), |m, (v, &s)| if s > m.1 { (v, s) } else { m });
            let ratio = step / denominator;
            let found = &mut self.found;
            if ratio > found.worst_ratio {
                found.worst_ratio = ratio;
                found.worst_frames = Some([k - 1, k]);
            }
            if ratio > found.bound {
                let limit = found.bound * denominator;
                found.jumps.push(Jump {
                    frames: [k - 1, k],
                    ratio,
                    vertex: vertex as u32,
                    vertices: (0..steps.len() as u32)
                        .filter(|&v| steps[v as usize] > limit)
                        .collect(),
                });
            }
        }
        self.previous = Some((positions.to_vec(), linear.to_vec()));
        Ok(())
    }

    /// The result so far.
    pub fn finish(self) -> Continuity {
        self.found
    }
}

/// [`ContinuityCheck`] over whole sequences: `frames[k]` and its linear blend `linear[k]`.
/// Refuses sequences whose two lists differ in length or whose frames differ in vertex count.
pub fn sequence_continuity(
    frames: &[Vec<Point>],
    linear: &[Vec<Point>],
    bound: f64,
    diagonal: f64,
) -> Result<Continuity, BlendError> {
    if frames.len() != linear.len() {
        return Err(BlendError::InvalidOption(format!(
            "{} frames but {} linear blends",
            frames.len(),
            linear.len()
        )));
    }
    let mut check = ContinuityCheck::new(bound, diagonal);
    for (x, l) in frames.iter().zip(linear) {
        check.push(x, l)?;
    }
    Ok(check.finish())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ten vertices on a line, moved along x by `t` (uniformly, like a linear blend).
    fn line(t: f64) -> Vec<Point> {
        (0..10).map(|i| [i as f64 + t, 0.0, 0.0]).collect()
    }

    #[test]
    fn a_uniform_sequence_has_ratio_one_and_no_jump() {
        let lin: Vec<_> = (0..5).map(|k| line(0.1 * k as f64)).collect();
        let c = sequence_continuity(&lin, &lin, JUMP_BOUND, 10.0).unwrap();
        assert!((c.worst_ratio - 1.0).abs() < 1e-12, "{c:?}");
        assert!(c.jumps.is_empty());
        assert!(c.jump_vertices().is_empty());
    }

    #[test]
    fn a_part_that_snaps_is_found_with_its_vertices() {
        let lin: Vec<_> = (0..6).map(|k| line(0.1 * k as f64)).collect();
        let mut phys = lin.clone();
        // Vertices 3 and 4 swing out by 1.0 between frames 2 and 3 and stay there; vertex 5
        // follows at 0.35 (3.5 steps: under the bound).
        for frame in phys.iter_mut().skip(3) {
            frame[3][1] += 1.0;
            frame[4][1] += 1.0;
            frame[5][1] += 0.35;
        }
        let c = sequence_continuity(&phys, &lin, JUMP_BOUND, 10.0).unwrap();
        assert_eq!(c.jumps.len(), 1, "{c:?}");
        let j = &c.jumps[0];
        assert_eq!(j.frames, [2, 3]);
        assert_eq!(j.vertices, vec![3, 4]);
        assert!(j.vertex == 3 || j.vertex == 4);
        let expected = (1.0f64 + 0.01).sqrt() / 0.1;
        assert!((j.ratio - expected).abs() < 1e-9, "{}", j.ratio);
        assert_eq!(c.worst_frames, Some([2, 3]));
        assert_eq!(c.jump_vertices(), vec![3, 4]);
    }

    #[test]
    fn equal_weights_compare_against_the_floor_not_round_off() {
        // The linear blend does not move; the physical frames differ by round-off-sized
        // amounts (1e-9 of a diagonal of 10): no jump.
        let lin = vec![line(0.0); 3];
        let mut phys = lin.clone();
        phys[1][7][2] += 1e-8;
        let c = sequence_continuity(&phys, &lin, JUMP_BOUND, 10.0).unwrap();
        assert!(c.jumps.is_empty(), "{c:?}");
        assert!(c.worst_ratio <= 1.0 + 1e-12, "{}", c.worst_ratio);
        // A real move while the weights stand still is a jump.
        phys[2][7][2] += 1.0;
        let c = sequence_continuity(&phys, &lin, JUMP_BOUND, 10.0).unwrap();
        assert_eq!(c.jumps.len(), 1);
        assert_eq!(c.jumps[0].vertices, vec![7]);
    }

    #[test]
    fn one_frame_or_none_has_nothing_to_compare() {
        let c = sequence_continuity(&[], &[], JUMP_BOUND, 1.0).unwrap();
        assert_eq!(c.worst_ratio, 0.0);
        assert_eq!(c.worst_frames, None);
        let c = sequence_continuity(&[line(0.0)], &[line(0.0)], JUMP_BOUND, 1.0).unwrap();
        assert!(c.jumps.is_empty() && c.worst_frames.is_none());
    }

    #[test]
    fn mismatched_frames_are_refused() {
        let short: Vec<Point> = line(0.0)[..4].to_vec();
        assert!(sequence_continuity(&[line(0.0)], &[], JUMP_BOUND, 1.0).is_err());
        let e = sequence_continuity(
            &[line(0.0), short.clone()],
            &[line(0.0), line(0.1)],
            JUMP_BOUND,
            1.0,
        )
        .unwrap_err();
        assert!(e.to_string().contains("frame 1"), "{e}");
        let mut check = ContinuityCheck::new(JUMP_BOUND, 1.0);
        assert!(check.push(&line(0.0), &short).is_err());
        check.push(&line(0.0), &line(0.0)).unwrap();
        assert!(check.push(&short, &short).is_err());
        check.push(&line(0.1), &line(0.1)).unwrap();
        assert_eq!(check.finish().worst_frames, Some([0, 1]));
    }
}
