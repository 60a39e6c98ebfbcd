//! Compact clips: a sequence of `F` frames of `#V` displacements written as `K ≪ F` shapes and
//! an `F × K` table of coefficients, within a tolerance on every vertex of every frame
//! (issue 56).
//!
//! A physical clip differs from the linear blend of its own weights by a residual that is
//! smooth in time and in space (Ma et al. 2012 §4: the equilibrium moves continuously with the
//! rest lengths), so a few shapes span it. A glTF viewer then plays the clip as the asset's own
//! targets at the clip's weights plus these shapes, as ordinary morph targets, at their
//! coefficients; no extension is needed. [`residual_basis`] finds the shapes:
//!
//! 1. The principal directions of the residuals, from the eigenvectors of the smaller of the
//!    two Gram matrices `R Rᵀ` (`F × F`) and `Rᵀ R` (`3V × 3V`) — `R` is the `F × 3V` matrix
//!    of residuals — in order of decreasing eigenvalue: the truncated SVD, which minimises the
//!    summed squared error for each `K`.
//! 2. The tolerance is on the *largest* vertex error of any frame, which the SVD does not
//!    minimise: shapes are taken in that order until every frame is within it. When the
//!    directions run out before that (rounding), the worst frame's own remainder is the next
//!    shape (a pivoted Gram–Schmidt step), which brings that frame to zero.
//! 3. Each shape is rounded to the grid it will be stored on before anything is projected on
//!    it: `f32` (what a plain glTF target holds; [`residual_basis`], scaled so that its
//!    largest coefficient over the clip is 1, an ordinary slider range), or a [`Grid`] and a
//!    scale that a caller chooses per shape ([`residual_basis_on`]: 16-bit integers, as
//!    `KHR_mesh_quantization` stores a target). The coefficients are the projections of what
//!    remains onto the stored shape, rounded to `f32`, so later shapes absorb the rounding of
//!    earlier ones, and the error reported is that of the stored numbers, not of the exact
//!    SVD.
//!
//! Where the Gram matrix would cost more than [`EXACT_FLOPS`] (1 800 frames of a 26 719-vertex
//! face: 2.6e11), the directions of step 1 come in blocks of 16 from a randomized range finder
//! run on what the shapes chosen so far leave (`randomized.rs`), so the work grows with the
//! shapes the tolerance needs; steps 2 and 3 are the same.
//!
//! The computation is sequential (faer without threads; the range finder's test matrix from a
//! fixed seed), so the same frames give the same shapes, bytes included, on any machine load.

use crate::mesh::Point;
use faer::{Mat, Side};

mod randomized;
#[cfg(test)]
mod tests;

pub use randomized::{block_flops, exact_flops, EXACT_FLOPS};

/// The default tolerance of a compact clip, as a fraction of the base's bounding-box diagonal:
/// the largest vertex error of any frame (issue 56: within a viewer's pixel at any usual
/// framing, and well under the physical correction, 1–5 % of the diagonal on a face clip).
pub const DEFAULT_TOLERANCE: f64 = 1e-3;

/// Why [`residual_basis`] refused its input.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ClipError {
    /// No frame, or frames of no vertex.
    #[error("no frames to compress")]
    Empty,
    /// Frame `frame` has another vertex count than frame 0.
    #[error("frame {frame} has {found} vertices, frame 0 has {expected}")]
    VertexCount {
        /// The frame.
        frame: usize,
        /// Frame 0's vertex count.
        expected: usize,
        /// This frame's.
        found: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("frame {frame}, vertex {vertex}: a coordinate is not finite")]
    NotFinite {
        /// The frame.
        frame: usize,
        /// The vertex.
        vertex: usize,
    },
    /// The tolerance is not a finite positive number.
    #[error("the tolerance {0} is not a finite positive distance")]
    Tolerance(f64),
    /// `max_shapes` shapes leave a frame further than the tolerance.
    #[error(
        "{max_shapes} shapes leave frame {frame} {error:.3e} from its residual, more than the \
         tolerance {tolerance:.3e}"
    )]
    TooManyShapes {
        /// The most shapes allowed.
        max_shapes: usize,
        /// The worst frame with that many.
        frame: usize,
        /// Its largest vertex error.
        error: f64,
        /// The tolerance asked for.
        tolerance: f64,
    },
}

/// The numbers a shape's coordinates are rounded to before it is used (glTF 2.0 §3.6.2.2 and
/// `KHR_mesh_quantization`: the component types a morph target's `POSITION` may have).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Grid {
    /// `f32` values (`FLOAT`).
    F32,
    /// `q / 32767` for an integer `q` in `[−32767, 32767]`: a normalized `SHORT`, decoded as
    /// glTF decodes it (§3.11), so in `[−1, 1]`.
    I16Normalized,
    /// An integer in `[−32767, 32767]`: an unnormalized `SHORT`.
    I16,
}

impl Grid {
    /// `x` rounded to the grid (to nearest; integer grids clamp to their range).
    pub fn round(self, x: f64) -> f64 {
        match self {
            Grid::F32 => x as f32 as f64,
            Grid::I16Normalized => (x * 32767.0).round().clamp(-32767.0, 32767.0) / 32767.0,
            Grid::I16 => x.round().clamp(-32767.0, 32767.0),
        }
    }

    /// The stored integer of a value on an integer grid (`x` as [`Grid::round`] gives it).
    pub fn integer(self, x: f64) -> i16 {
        match self {
            Grid::I16Normalized => (x * 32767.0).round().clamp(-32767.0, 32767.0) as i16,
            _ => x.round().clamp(-32767.0, 32767.0) as i16,
        }
    }
}

/// `K` shapes and their coefficients: frame `f` is `Σₖ coefficients[f][k] · shapes[k]` within
/// [`ClipBasis::max_error`] at every vertex.
#[derive(Clone, Debug)]
pub struct ClipBasis {
    /// `K` shapes of `#V` displacements, each coordinate a value of its grid
    /// ([`ClipBasis::grids`]). With [`residual_basis`], each is scaled so that its largest
    /// coefficient magnitude over the frames is 1 (and that coefficient positive); with
    /// [`residual_basis_on`], that coefficient is the scale the caller chose (see there).
    pub shapes: Vec<Vec<Point>>,
    /// Per shape: the grid its coordinates are on.
    pub grids: Vec<Grid>,
    /// `F` rows of `K` coefficients, each an `f32` value.
    pub coefficients: Vec<Vec<f64>>,
    /// The largest distance, over every vertex of every frame, between a frame and its
    /// reconstruction from the stored (rounded) shapes and coefficients.
    pub max_error: f64,
    /// The frame where [`ClipBasis::max_error`] is reached.
    pub worst_frame: usize,
}

impl ClipBasis {
    /// Frame `f` rebuilt from the shapes: `#V` displacements.
    pub fn frame(&self, f: usize) -> Vec<Point> {
        let n = self.shapes.first().map_or(0, Vec::len);
        let mut out = vec![[0.0; 3]; n];
        for (c, s) in self.coefficients[f].iter().zip(&self.shapes) {
            for (o, p) in out.iter_mut().zip(s) {
                for a in 0..3 {
                    o[a] += c * p[a];
                }
            }
        }
        out
    }
}

/// The largest vertex norm of row `r` (`3V` values) and where it is.
fn row_max(r: &[f64]) -> f64 {
    r.chunks_exact(3)
        .map(|v| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt())
        .fold(0.0, f64::max)
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Shapes for `frames` (`F` frames of `#V` displacements, e.g. a physical clip minus the linear
/// blend of its weights), as few as bring every vertex of every frame within `tolerance` (a
/// distance, in the frames' units), at most `max_shapes`. See the
/// [module documentation](self) for the method; frames that are all zero give no shape.
///
/// Errors: no frame or no vertex, frames of different vertex counts, a non-finite coordinate
/// (naming frame and vertex), a tolerance that is not a finite positive number, and more than
/// `max_shapes` shapes needed ([`ClipError::TooManyShapes`], with the error that many leave).
pub fn residual_basis(
    frames: &[Vec<Point>],
    tolerance: f64,
    max_shapes: usize,
) -> Result<ClipBasis, ClipError> {
    residual_basis_on(frames, tolerance, max_shapes, |_| (1.0, Grid::F32))
}

/// [`residual_basis`] with shapes stored on a grid that `grid` chooses per shape: given the
/// shape as it would be at coefficient 1 (its largest coefficient over the frames, `#V`
/// displacements, not yet rounded), it returns `(scale, grid)`, and the shape stored is that
/// shape divided by `scale` (a positive finite number; others are taken as 1) and rounded to
/// `grid`. Its largest coefficient is then about `scale`. The coefficients are projected on
/// the stored shape, so the error reported is that of the stored numbers.
///
/// Errors: those of [`residual_basis`].
pub fn residual_basis_on(
    frames: &[Vec<Point>],
    tolerance: f64,
    max_shapes: usize,
    grid: impl FnMut(&[Point]) -> (f64, Grid),
) -> Result<ClipBasis, ClipError> {
    basis_by_route(frames, tolerance, max_shapes, grid, false)
}

/// [`residual_basis_on`], with the directions in blocks whatever the size when `blocks`.
pub(crate) fn basis_by_route(
    frames: &[Vec<Point>],
    tolerance: f64,
    max_shapes: usize,
    mut grid: impl FnMut(&[Point]) -> (f64, Grid),
    blocks: bool,
) -> Result<ClipBasis, ClipError> {
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(ClipError::Tolerance(tolerance));
    }
    let nf = frames.len();
    let nv = frames.first().map_or(0, Vec::len);
    if nf == 0 || nv == 0 {
        return Err(ClipError::Empty);
    }
    let d = 3 * nv;
    // The remainders, frame-major: what the shapes chosen so far leave.
    let mut rest: Vec<Vec<f64>> = Vec::with_capacity(nf);
    for (f, fr) in frames.iter().enumerate() {
        if fr.len() != nv {
            return Err(ClipError::VertexCount {
                frame: f,
                expected: nv,
                found: fr.len(),
            });
        }
        if let Some(v) = fr.iter().position(|p| p.iter().any(|x| !x.is_finite())) {
            return Err(ClipError::NotFinite {
                frame: f,
                vertex: v,
            });
        }
        rest.push(fr.iter().flatten().copied().collect());
    }
    // The exact directions where the Gram matrix is cheap, else blocks drawn as they are used.
    let blocks = blocks || exact_flops(nf, d) > EXACT_FLOPS;
    let mut queue: std::collections::VecDeque<Vec<f64>> = if blocks {
        Default::default()
    } else {
        principal_directions(&rest, d).into()
    };
    let mut signs = randomized::Signs::new();
    let mut shapes: Vec<Vec<f64>> = Vec::new();
    let mut grids: Vec<Grid> = Vec::new();
    let mut coefficients: Vec<Vec<f64>> = vec![Vec::new(); nf];
    let mut errors: Vec<f64> = rest.iter().map(|r| row_max(r)).collect();
    loop {
        let (worst, &error) = errors
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1).then(b.0.cmp(&a.0)))
            .expect("a frame");
        if error <= tolerance {
            break;
        }
        if shapes.len() == max_shapes {
            return Err(ClipError::TooManyShapes {
                max_shapes,
                frame: worst,
                error,
                tolerance,
            });
        }
        // The next principal direction (a new block of them from what remains, when they come
        // in blocks), or the worst frame's own remainder.
        if queue.is_empty() && blocks {
            queue = randomized::block_directions(&rest, d, &mut signs).into();
        }
        let dir = queue.pop_front().unwrap_or_else(|| rest[worst].clone());
        let shape = match stored_shape(&rest, &dir, &mut grid) {
            Some(s) => s,
            // A direction nothing projects on (rounded to zero): take the pivot instead.
            None => match stored_shape(&rest, &rest[worst].clone(), &mut grid) {
                Some(s) => s,
                None => break,
            },
        };
        grids.push(shape.1);
        add_shape(shape.0, &mut rest, &mut coefficients, &mut shapes);
        errors = rest.iter().map(|r| row_max(r)).collect();
    }
    let (worst_frame, max_error) = errors
        .iter()
        .copied()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)))
        .expect("a frame");
    Ok(ClipBasis {
        shapes: shapes
            .into_iter()
            .map(|s| s.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect())
            .collect(),
        grids,
        coefficients,
        max_error,
        worst_frame,
    })
}

/// The shape along `dir` as stored, and its grid: scaled so that the largest projection of a
/// remainder on it is +1, then divided by the scale `grid` chooses and rounded to its grid.
/// `None` when nothing projects on it (or it rounds to zero).
fn stored_shape(
    rest: &[Vec<f64>],
    dir: &[f64],
    grid: &mut impl FnMut(&[Point]) -> (f64, Grid),
) -> Option<(Vec<f64>, Grid)> {
    let norm2 = dot(dir, dir);
    if !(norm2 > 0.0 && norm2.is_finite()) {
        return None;
    }
    // Projections on the unit direction; the one of largest magnitude sets scale and sign.
    let unit: Vec<f64> = dir.iter().map(|x| x / norm2.sqrt()).collect();
    let c = rest
        .iter()
        .map(|r| dot(r, &unit))
        .max_by(|a, b| a.abs().total_cmp(&b.abs()))?;
    if c == 0.0 || !c.is_finite() {
        return None;
    }
    let peak: Vec<Point> = unit
        .chunks_exact(3)
        .map(|u| [u[0] * c, u[1] * c, u[2] * c])
        .collect();
    let (scale, g) = grid(&peak);
    let scale = if scale.is_finite() && scale > 0.0 {
        scale
    } else {
        1.0
    };
    let shape: Vec<f64> = unit.iter().map(|x| g.round(x * c / scale)).collect();
    (dot(&shape, &shape) > 0.0).then_some((shape, g))
}

/// Appends `shape`: each remainder's projection on it, rounded to `f32`, becomes its
/// coefficient and is subtracted.
fn add_shape(
    shape: Vec<f64>,
    rest: &mut [Vec<f64>],
    coefficients: &mut [Vec<f64>],
    shapes: &mut Vec<Vec<f64>>,
) {
    let s2 = dot(&shape, &shape);
    for (r, c) in rest.iter_mut().zip(coefficients.iter_mut()) {
        let k = (dot(r, &shape) / s2) as f32 as f64;
        if k != 0.0 {
            for (x, s) in r.iter_mut().zip(&shape) {
                *x -= k * s;
            }
        }
        c.push(k);
    }
    shapes.push(shape);
}

/// The principal directions of the rows of `rows` (`F` rows of `d` values), unnormalised, in
/// order of decreasing eigenvalue, those with an eigenvalue above rounding only.
fn principal_directions(rows: &[Vec<f64>], d: usize) -> Vec<Vec<f64>> {
    let nf = rows.len();
    let r = Mat::<f64>::from_fn(nf, d, |i, j| rows[i][j]);
    let small_side = nf <= d;
    let gram = if small_side {
        &r * r.transpose()
    } else {
        r.transpose() * &r
    };
    let Ok(eig) = gram.self_adjoint_eigen(Side::Lower) else {
        return Vec::new();
    };
    let n = gram.nrows();
    let s = eig.S().column_vector();
    let u = eig.U();
    let largest = (0..n).map(|i| s[i]).fold(0.0, f64::max);
    // Ascending order from faer: walk it backwards; drop what is rounding.
    let floor = largest * 1e-24 + f64::MIN_POSITIVE;
    (0..n)
        .rev()
        .filter(|&i| s[i] > floor)
        .map(|i| {
            if small_side {
                // Rᵀ u: the row-space direction of the left singular vector u.
                (0..d)
                    .map(|j| (0..nf).map(|f| r[(f, j)] * u[(f, i)]).sum())
                    .collect()
            } else {
                (0..d).map(|j| u[(j, i)]).collect()
            }
        })
        .collect()
}
