//! The predictor tether: a weak zero-length spring from every solved vertex to its place in
//! the predictor $P(w)$ (not in the paper; [`BlendOptions::tether`](super::BlendOptions)).
//!
//! $$E_{\text{tether}}(x) = \tfrac12\, \mu \bar k \sum_{v\ \text{free}} \lVert x_v - P_v(w) \rVert^2,$$
//!
//! with $\bar k$ the mean spring stiffness and $\mu$ the option (default `1e-5`). It is added
//! to the blend energy as point targets ([`PointTarget`]): a diagonal Hessian block per vertex,
//! so the pattern and the symbolic analysis do not change.
//!
//! Why. Rest-length blending leaves *soft modes*: a part that turns about a line of vertices
//! (a hoof about the hock, the ICT gums about the jaw's hinge line) changes no spring's length
//! to first order, and only the weak hinge resists it. Where the blended lengths fit that
//! part turned either way, the energy has two equilibria over a range of weights, and a
//! sequence snaps from one to the other between two frames (issue 7's continuity property:
//! horse-02, 04 and 06 moved a lower leg by 4.6–6.8× the linear blend's step, ICT jawOpen its
//! gums by 4.1×). $P(w)$ is continuous in $w$, so tying every vertex to it, however weakly,
//! breaks the tie between the two branches towards the one $P$ follows. A part of $N$
//! vertices turned by $\delta$ pays about $\mu \bar k N \delta^2$, large for a whole leg and
//! negligible against the springs for any strain: $\mu$ is five orders of magnitude below a
//! spring.
//!
//! Properties kept: at one-hot weights $P = x^s$, so the tether has zero energy and gradient
//! there and endpoints stay exact; $P$ depends on the weights alone, so the frame does too.

use super::PointTarget;

/// The tether's point targets: every vertex `v` with `free(v)`, pulled towards its place in
/// `predicted` (solver coordinates, flattened, `3 #V`) with relative stiffness `mu` (in units
/// of the mean spring stiffness, as every [`PointTarget`]).
pub(crate) fn targets<'a>(
    predicted: &'a [f64],
    free: impl Fn(usize) -> bool + 'a,
    mu: f64,
) -> impl Iterator<Item = PointTarget> + 'a {
    let n = if mu > 0.0 { predicted.len() / 3 } else { 0 };
    (0..n).filter(move |&v| free(v)).map(move |v| PointTarget {
        vertex: v as u32,
        position: [predicted[3 * v], predicted[3 * v + 1], predicted[3 * v + 2]],
        stiffness: mu,
    })
}
