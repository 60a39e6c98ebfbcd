//! Blend weights and rest-length interpolation (Ma et al. 2012, Eq. 1 and Sec. 3.3; math
//! notes §1 for the artist "delta" form).

use super::BlendError;

/// How the shapes of a set are mixed. Shape 0 is the base.
#[derive(Clone, Debug, PartialEq)]
pub enum Weights {
    /// Two shapes, $\bar r = (1 - \alpha) r^0 + \alpha r^1$ (Eq. 1). Needs exactly two shapes.
    Alpha(f64),
    /// Convex weights over all `n` shapes: non-negative, summing to 1 (Sec. 3.3).
    Convex(Vec<f64>),
    /// Artist weights over the `n − 1` targets, as in glTF morph targets and DCC blendshape
    /// nodes: $\bar r = r^0 + \sum_i w_i (r^i - r^0)$, each $w_i$ independent (usually in
    /// `[0, 1]`, any finite value accepted). All zeros gives the base.
    Delta(Vec<f64>),
}

/// The shape that coefficients `c` select alone (`c = e_s`), if any: where the frame and the
/// predictor are that shape's own numbers.
pub(crate) fn one_hot(c: &[f64]) -> Option<usize> {
    let s = c.iter().position(|&x| x == 1.0)?;
    c.iter()
        .enumerate()
        .all(|(k, &x)| k == s || x == 0.0)
        .then_some(s)
}

/// Largest magnitude accepted for any single weight. Weights far outside `[0, 1]` are
/// extrapolations that no spring system follows meaningfully.
pub const MAX_WEIGHT: f64 = 100.0;

impl Weights {
    /// The equivalent affine coefficients `c` over all `n` shapes (`Σ c = 1`), validated:
    /// finite, at most [`MAX_WEIGHT`] in magnitude, and the right count for the form.
    pub fn coefficients(&self, n: usize) -> Result<Vec<f64>, BlendError> {
        let check = |w: &[f64]| -> Result<(), BlendError> {
            if let Some(index) = w.iter().position(|x| !x.is_finite()) {
                return Err(BlendError::NonFiniteWeight {
                    index,
                    value: w[index],
                });
            }
            match w.iter().position(|x| x.abs() > MAX_WEIGHT) {
                Some(index) => Err(BlendError::WeightOutOfRange {
                    index,
                    value: w[index],
                    max: MAX_WEIGHT,
                }),
                None => Ok(()),
            }
        };
        match self {
            Weights::Alpha(a) => {
                check(&[*a])?;
                if n != 2 {
                    return Err(BlendError::WeightCount {
                        kind: "alpha",
                        expected: 1,
                        found: n.saturating_sub(1),
                        shapes: n,
                    });
                }
                Ok(vec![1.0 - a, *a])
            }
            Weights::Convex(w) => {
                check(w)?;
                if w.len() != n {
                    return Err(BlendError::WeightCount {
                        kind: "convex",
                        expected: n,
                        found: w.len(),
                        shapes: n,
                    });
                }
                let sum: f64 = w.iter().sum();
                let min = w.iter().copied().fold(f64::INFINITY, f64::min);
                if (sum - 1.0).abs() > 1e-9 || min < -1e-12 {
                    return Err(BlendError::NotConvex { sum, min });
                }
                Ok(w.clone())
            }
            Weights::Delta(w) => {
                check(w)?;
                if w.len() + 1 != n {
                    return Err(BlendError::WeightCount {
                        kind: "delta",
                        expected: n.saturating_sub(1),
                        found: w.len(),
                        shapes: n,
                    });
                }
                let mut c = Vec::with_capacity(n);
                c.push(1.0 - w.iter().sum::<f64>());
                c.extend_from_slice(w);
                Ok(c)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn forms_agree_and_bad_weights_are_errors() {
        assert_eq!(
            Weights::Alpha(0.25).coefficients(2).unwrap(),
            vec![0.75, 0.25]
        );
        assert_eq!(
            Weights::Delta(vec![0.25, 0.5]).coefficients(3).unwrap(),
            vec![0.25, 0.25, 0.5]
        );
        assert_eq!(
            Weights::Delta(vec![0.0, 0.0]).coefficients(3).unwrap(),
            vec![1.0, 0.0, 0.0]
        );
        assert!(matches!(
            Weights::Alpha(f64::NAN).coefficients(2),
            Err(BlendError::NonFiniteWeight { .. })
        ));
        assert!(matches!(
            Weights::Delta(vec![0.1, f64::INFINITY]).coefficients(3),
            Err(BlendError::NonFiniteWeight { index: 1, .. })
        ));
        assert!(matches!(
            Weights::Convex(vec![0.5, 0.6]).coefficients(2),
            Err(BlendError::NotConvex { .. })
        ));
        assert!(matches!(
            Weights::Convex(vec![1.5, -0.5]).coefficients(2),
            Err(BlendError::NotConvex { .. })
        ));
        assert!(matches!(
            Weights::Alpha(0.5).coefficients(3),
            Err(BlendError::WeightCount { .. })
        ));
        assert!(matches!(
            Weights::Delta(vec![1.0]).coefficients(3),
            Err(BlendError::WeightCount { .. })
        ));
        for w in [1e6, -1e300, 100.5] {
            assert!(matches!(
                Weights::Alpha(w).coefficients(2),
                Err(BlendError::WeightOutOfRange { .. })
            ));
        }
        assert!(Weights::Alpha(-100.0).coefficients(2).is_ok());
    }
}
