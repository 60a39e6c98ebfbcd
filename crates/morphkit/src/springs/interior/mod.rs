//! Internal springs for volume (Ma et al. 2012, Sec. 3.1) and the rigid anchor (Sec. 3.4,
//! steps 1–5), as energy terms over an *extended* shape set.
//!
//! # The extended shape set
//!
//! The blend runs on the surface vertices `0..n` followed by the *extra* vertices: interior
//! points `n..n + m` and anchor vertices `n + m..`. No triangle touches an extra vertex; the
//! surface keeps its springs (structure springs, and bending springs when they are turned on)
//! and its signed hinges, and the extra
//! vertices enter through two more [`SpringTerm`](super::terms::SpringTerm)s:
//!
//! - **internal springs** ([`SpringKind::Internal`](super::SpringKind)), stiffness
//!   $k = k_0 / \bar r$ like every spring (Sec. 3.5): the edges of a body-centred cubic (BCC)
//!   lattice of interior points of each *closed* component, and ties from each surface vertex to
//!   its nearest interior points ([`lattice`], the default); or, with
//!   [`InteriorMode::Tetgen`](super::InteriorMode), the edges of a constrained Delaunay
//!   tetrahedralization made by an external `tetgen` process, surface kept as it is
//!   ([`tetgen`]);
//! - a **volume term** ([`VolumeTerm`](super::terms::VolumeTerm), stiffness
//!   [`InteriorOptions::volume`], default 10, 0 turns it off) on the interior's tetrahedra and,
//!   with the lattice, on the shell between the surface and the lattice ([`shell`]: a cone from
//!   each surface triangle to a tied lattice point, wedges and fans between cones), each held
//!   near its linearly interpolated volume. Interpolated rest lengths of springs oblique to a
//!   large shear are too long, interior and surface alike, so springs alone inflate a twisted
//!   shape (issue 40; docs/fidelity.md, "Volume under twist");
//! - **anchor springs** ([`SpringKind::Anchor`](super::SpringKind)): the anchor's own edges,
//!   [`AnchorOptions::stiffness`] × $k_0$, and ties from each anchor vertex to the nearest body
//!   vertices at $k_0$ ([`anchor`]).
//!
//! Extra vertices exist only in the base (the source). Their positions in every other target
//! come from the **reverse solve** of Sec. 3.4 step 3 ([`reverse`]): that target's surface
//! fixed, the internal and anchor rest lengths copied from the base, equilibrium solved, once
//! per target when the blender is built. After that the extended set is an ordinary shape set:
//! one-hot weights reproduce each target, surface and interior, exactly.
//!
//! # The anchor
//!
//! With an anchor, each target $s$ gets the best rigid motion $T_s = \{R_s | t_s\}$ taking the
//! base anchor onto its reverse-solved anchor (Kabsch, $\det R_s = +1$, step 4). The blend is
//! solved in the anchor's local frame: shape $s$ enters as $T_s^{-1}(x^s)$, the anchor
//! vertices are the boundary conditions (their positions, interpolated linearly across the
//! local shapes, are the base anchor up to the reverse solve's residual), and the result is
//! moved by the blended motion $T(c)$ (step 5): about the base anchor's centroid $a$,
//! $T(c)\,x = R(c)(x - a) + a + d(c)$ with
//!
//! $$R(c) = \exp\Big(\sum_{s \ge 1} c_s \log R_s\Big), \qquad d(c) = \sum_{s \ge 1} c_s d_s,
//! \qquad d_s = R_s a + t_s - a,$$
//!
//! a log-map blend of the rotations (each $\log R_s$ the axis–angle vector, angle in
//! $[0, \pi]$) and a linear blend of the anchor's displacement. For two shapes and
//! $c = (1 - \alpha, \alpha)$ this is exactly the paper's $\{\mathrm{slerp}(I, R, \alpha) |
//! \alpha t\}$ with $t$ measured in the anchor's local frame (origin at $a$), which makes the
//! motion independent of where the world origin lies. At one-hot weights $T(e_s) = T_s$, so
//! endpoints stay exact.
//!
//! # Open meshes
//!
//! Interior points are placed only in closed, consistently oriented components (by the lattice
//! and by `tetgen` alike): the inside
//! test (`parry3d-f64`'s pseudo-normal test on a trimesh built with the `ORIENTED` flag) is not
//! defined for an open surface. Every other component is blended with surface springs alone
//! and listed in [`InteriorReport::skipped`] with the reason; nothing fails. An anchor in an
//! open mesh is still possible: it is placed at the given position, or at the vertex centroid,
//! and tied to the nearest surface vertices without an inside check.
//!
//! # Refinement of long springs
//!
//! The paper optionally inserts vertices to avoid long springs (Sec. 3.1). The lattice makes
//! that unnecessary: every internal spring is $h$ or $\tfrac{\sqrt 3}{2} h$ long, and surface
//! ties are at most [`InteriorOptions::tie_radius`] $\cdot h$. With `tetgen` the volume bound
//! and the radius–edge bound (`-q1.414`) do the refinement; the surface itself is not split.

pub mod anchor;
mod holes;
mod inversion;
pub mod lattice;
mod options;
pub mod reverse;
pub mod shell;
pub mod tetgen;
mod volumetric;

pub use anchor::{Anchor, AnchorMotion};
pub use inversion::{count_inversions, Inversions};
pub use lattice::{Interior, SkippedComponent};
pub use options::{
    AnchorOptions, AnchorPlacement, InteriorMode, InteriorOptions, VOLUME_STIFFNESS_DEFAULT,
};
pub use volumetric::{InteriorReport, SurfacePredictor, VolumeResult, VolumetricBlend};

use super::BlendError;

/// Why a volumetric blend could not be built.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum InteriorError {
    /// The surface blend itself failed (bad shapes, options, a singular system…).
    #[error(transparent)]
    Blend(#[from] BlendError),
    /// The extended shape set could not be formed.
    #[error(transparent)]
    Shapes(#[from] crate::mesh::ShapeSetError),
    /// An option is out of range.
    #[error("invalid interior option: {0}")]
    InvalidOption(String),
    /// `tetgen` was asked for but cannot be used: not on the `PATH`, it failed (its last output
    /// lines quoted), the surface intersects itself, or its output cannot be read.
    #[error("--interior tetgen: {0}")]
    Tetgen(String),
    /// The anchor's given position is not inside any closed component.
    #[error("the anchor at ({:.4}, {:.4}, {:.4}) is not inside a closed component of the base (give a point inside, or --anchor auto)", position[0], position[1], position[2])]
    AnchorOutside {
        /// The given position.
        position: [f64; 3],
    },
    /// The reverse solve of one target did not converge.
    #[error("reverse solve for target '{target}' (Sec. 3.4 step 3) did not converge: gradient {gradient:e} > {tolerance:e} after {iterations} iterations")]
    ReverseSolve {
        /// The target's name.
        target: String,
        /// Final gradient norm.
        gradient: f64,
        /// Tolerance.
        tolerance: f64,
        /// Newton iterations.
        iterations: usize,
    },
}
