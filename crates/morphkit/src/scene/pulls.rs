//! Pulled vertices (Ma et al. 2012, Sec. 4, Fig. 5): a vertex dragged to a keyframed world
//! position during the blend, as a boundary condition (*hard*, the paper's) or a soft spring.
//!
//! Each pull becomes one [`PointTarget`] per frame, $E = \tfrac12 \kappa \lVert x_v - p(f)
//! \rVert^2$ with $p(f)$ the keyed position linearly interpolated at frame $f$ (held before the
//! first and after the last key). Hard: a boundary condition ([`PointTarget::hard`]), the vertex
//! is placed exactly at $p(f)$ and held there while its neighbourhood is solved for.
//! Soft: $\kappa$ = `stiffness` × the mean spring stiffness (`1` pulls like one more edge).

use super::keys::{bracket, first_out_of_order, lerp};
use crate::mesh::Point;
use crate::springs::PointTarget;

/// Why a pull is unusable.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum PullError {
    /// A pull needs at least one key.
    #[error("the pull of vertex {vertex} has no keys")]
    NoKeys {
        /// The vertex.
        vertex: u32,
    },
    /// Keys are not strictly increasing in frame.
    #[error("the pull of vertex {vertex}: key {index} is at frame {frame}, not after the previous key's frame {previous}; keyframes must be in increasing frame order")]
    KeysOutOfOrder {
        /// The vertex.
        vertex: u32,
        /// The offending key.
        index: usize,
        /// Its frame.
        frame: f64,
        /// The previous key's frame.
        previous: f64,
    },
    /// A key has a non-finite frame or position.
    #[error("the pull of vertex {vertex}: key {index} has a non-finite frame or position")]
    NonFinite {
        /// The vertex.
        vertex: u32,
        /// The offending key.
        index: usize,
    },
    /// A soft pull's stiffness is not finite and positive.
    #[error("the pull of vertex {vertex}: stiffness must be finite and positive, got {value}")]
    Stiffness {
        /// The vertex.
        vertex: u32,
        /// The value.
        value: f64,
    },
}

/// How strongly a pull holds its vertex.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum PullKind {
    /// A boundary condition (the paper's pull).
    #[default]
    Hard,
    /// A spring of this stiffness, in units of the mean spring stiffness.
    Soft {
        /// Relative stiffness.
        stiffness: f64,
    },
}

/// A pulled position at one frame number.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PullKey {
    /// Frame number (0 = first frame; fractions allowed).
    pub frame: f64,
    /// World position.
    pub position: Point,
}

/// One pulled vertex with its keyed positions.
#[derive(Clone, Debug, PartialEq)]
pub struct Pull {
    vertex: u32,
    keys: Vec<PullKey>,
    frames: Vec<f64>,
    kind: PullKind,
}

impl Pull {
    /// Checks the keys (at least one, finite, strictly increasing frames) and the stiffness.
    /// The vertex id is checked against the mesh by [`super::SceneBlend::new`].
    pub fn new(vertex: u32, keys: Vec<PullKey>, kind: PullKind) -> Result<Self, PullError> {
        if keys.is_empty() {
            return Err(PullError::NoKeys { vertex });
        }
        if let Some(index) = keys
            .iter()
            .position(|k| !k.frame.is_finite() || k.position.iter().any(|c| !c.is_finite()))
        {
            return Err(PullError::NonFinite { vertex, index });
        }
        if let PullKind::Soft { stiffness } = kind {
            if !(stiffness.is_finite() && stiffness > 0.0) {
                return Err(PullError::Stiffness {
                    vertex,
                    value: stiffness,
                });
            }
        }
        let frames: Vec<f64> = keys.iter().map(|k| k.frame).collect();
        if let Some(index) = first_out_of_order(&frames) {
            return Err(PullError::KeysOutOfOrder {
                vertex,
                index,
                frame: frames[index],
                previous: frames[index - 1],
            });
        }
        Ok(Self {
            vertex,
            keys,
            frames,
            kind,
        })
    }

    /// The pulled vertex.
    pub fn vertex(&self) -> u32 {
        self.vertex
    }
    /// Hard or soft.
    pub fn kind(&self) -> PullKind {
        self.kind
    }
    /// The keys, in frame order.
    pub fn keys(&self) -> &[PullKey] {
        &self.keys
    }

    /// The pulled position at `frame`.
    pub fn position_at(&self, frame: f64) -> Point {
        let (i, j, t) = bracket(&self.frames, frame);
        lerp(self.keys[i].position, self.keys[j].position, t)
    }

    /// The point target of this pull at `frame`.
    pub fn target_at(&self, frame: f64) -> PointTarget {
        let position = self.position_at(frame);
        match self.kind {
            PullKind::Hard => PointTarget::hard(self.vertex, position),
            PullKind::Soft { stiffness } => PointTarget {
                vertex: self.vertex,
                position,
                stiffness,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positions_interpolate_between_keys_and_hold_outside() {
        let k = |frame, x| PullKey {
            frame,
            position: [x, 0.0, 0.0],
        };
        let p = Pull::new(3, vec![k(2.0, 1.0), k(6.0, 3.0)], PullKind::Hard).unwrap();
        assert_eq!(p.position_at(0.0), [1.0, 0.0, 0.0]);
        assert_eq!(p.position_at(4.0), [2.0, 0.0, 0.0]);
        assert_eq!(p.position_at(10.0), [3.0, 0.0, 0.0]);
        assert_eq!(p.target_at(4.0).stiffness, PointTarget::HARD_STIFFNESS);
        let soft = Pull::new(3, vec![k(0.0, 0.0)], PullKind::Soft { stiffness: 5.0 }).unwrap();
        assert_eq!(soft.target_at(1.0).stiffness, 5.0);
    }

    #[test]
    fn bad_pulls_are_refused() {
        let k = |frame| PullKey {
            frame,
            position: [0.0; 3],
        };
        assert!(matches!(
            Pull::new(1, vec![k(3.0), k(1.0)], PullKind::Hard),
            Err(PullError::KeysOutOfOrder { index: 1, .. })
        ));
        assert!(matches!(
            Pull::new(1, vec![], PullKind::Hard),
            Err(PullError::NoKeys { .. })
        ));
        assert!(matches!(
            Pull::new(1, vec![k(0.0)], PullKind::Soft { stiffness: 0.0 }),
            Err(PullError::Stiffness { .. })
        ));
    }
}
