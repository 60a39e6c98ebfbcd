//! Marker pairs that tie source vertices to target vertices (Wang & Lee 2008, Sec. 3.1.1–3.1.2).
//!
//! File format: JSON `{"pairs": [[source_vertex, target_vertex], ...]}`, 0-based vertex indices;
//! other keys (a `"comment"`, say) are ignored.

use super::error::{MarkerError, Side};
use crate::mesh::Point;
use serde::{Deserialize, Serialize};

/// The fewest markers accepted. Least-squares meshes interpolate the marker positions
/// smoothly, so the warped meshes lie near the affine hull of the markers: three markers give
/// flat warped meshes whose normals carry no information. Four non-coplanar markers are the
/// least that span 3-D.
pub const MIN_MARKERS: usize = 4;

/// Relative thickness (smallest standard deviation of the target marker positions over the
/// target's bounding-box diagonal) below which the markers count as coplanar.
pub const COPLANAR_TOLERANCE: f64 = 1e-6;

/// Marker pairs `[source_vertex, target_vertex]`, 0-based.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Markers {
    /// The pairs, in file order.
    pub pairs: Vec<[u32; 2]>,
}

impl Markers {
    /// Markers from pairs.
    pub fn new(pairs: Vec<[u32; 2]>) -> Self {
        Self { pairs }
    }

    /// The same pairs with source and target swapped (`[t, s]`), for the way back.
    pub fn reversed(&self) -> Self {
        Self::new(self.pairs.iter().map(|&[s, t]| [t, s]).collect())
    }

    /// Parses the JSON marker format.
    pub fn from_json(text: &str) -> Result<Self, MarkerError> {
        #[derive(Deserialize)]
        struct File {
            pairs: Vec<[i64; 2]>,
        }
        let f: File = serde_json::from_str(crate::io::strip_bom_str(text)).map_err(|e| {
            MarkerError::Parse(format!(
                "expected {{\"pairs\": [[source, target], ...]}}: {e}"
            ))
        })?;
        let mut pairs = Vec::with_capacity(f.pairs.len());
        for (k, [s, t]) in f.pairs.into_iter().enumerate() {
            let conv = |v: i64, side: Side| {
                u32::try_from(v).map_err(|_| MarkerError::OutOfRange {
                    marker: k,
                    side,
                    vertex: if v < 0 { u32::MAX } else { v as u32 },
                    num_vertices: 0,
                })
            };
            if s < 0 || t < 0 {
                return Err(MarkerError::Parse(format!(
                    "marker {k}: negative vertex index [{s}, {t}] (indices are 0-based)"
                )));
            }
            pairs.push([conv(s, Side::Source)?, conv(t, Side::Target)?]);
        }
        Ok(Self { pairs })
    }

    /// Reads a marker file.
    pub fn read(path: &std::path::Path) -> Result<Self, MarkerError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| MarkerError::Parse(format!("{}: {e}", path.display())))?;
        Self::from_json(&text).map_err(|e| match e {
            MarkerError::Parse(m) => MarkerError::Parse(format!("{}: {m}", path.display())),
            other => other,
        })
    }

    /// The JSON marker format.
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).expect("markers serialise")
    }

    /// Number of pairs.
    pub fn len(&self) -> usize {
        self.pairs.len()
    }

    /// True when there are no pairs.
    pub fn is_empty(&self) -> bool {
        self.pairs.is_empty()
    }

    /// Source vertex of each pair.
    pub fn source_vertices(&self) -> Vec<u32> {
        self.pairs.iter().map(|p| p[0]).collect()
    }

    /// Target vertex of each pair.
    pub fn target_vertices(&self) -> Vec<u32> {
        self.pairs.iter().map(|p| p[1]).collect()
    }

    /// Checks indices against the vertex counts, rejects a vertex used twice on one side and
    /// lists shorter than [`MIN_MARKERS`].
    pub fn validate(
        &self,
        source_vertices: usize,
        target_vertices: usize,
    ) -> Result<(), MarkerError> {
        for (k, p) in self.pairs.iter().enumerate() {
            for (side, v, n) in [
                (Side::Source, p[0], source_vertices),
                (Side::Target, p[1], target_vertices),
            ] {
                if v as usize >= n {
                    return Err(MarkerError::OutOfRange {
                        marker: k,
                        side,
                        vertex: v,
                        num_vertices: n,
                    });
                }
            }
        }
        for (side, col) in [(Side::Source, 0), (Side::Target, 1)] {
            let mut seen = std::collections::HashMap::with_capacity(self.pairs.len());
            for (k, p) in self.pairs.iter().enumerate() {
                if let Some(&first) = seen.get(&p[col]) {
                    return Err(MarkerError::Duplicate {
                        first,
                        second: k,
                        side,
                        vertex: p[col],
                    });
                }
                seen.insert(p[col], k);
            }
        }
        if self.pairs.len() < MIN_MARKERS {
            return Err(MarkerError::TooFew {
                found: self.pairs.len(),
                minimum: MIN_MARKERS,
            });
        }
        Ok(())
    }

    /// Rejects target markers that are coplanar within [`COPLANAR_TOLERANCE`] of `diagonal`.
    /// Indices must be valid (see [`Markers::validate`]).
    pub fn check_spread(&self, target: &[Point], diagonal: f64) -> Result<(), MarkerError> {
        let pts: Vec<Point> = self.pairs.iter().map(|p| target[p[1] as usize]).collect();
        let n = pts.len().max(1) as f64;
        let mut c = [0.0; 3];
        for p in &pts {
            for k in 0..3 {
                c[k] += p[k] / n;
            }
        }
        let mut cov = nalgebra::Matrix3::<f64>::zeros();
        for p in &pts {
            let d = nalgebra::Vector3::new(p[0] - c[0], p[1] - c[1], p[2] - c[2]);
            cov += d * d.transpose() / n;
        }
        let smallest = cov
            .symmetric_eigenvalues()
            .iter()
            .cloned()
            .fold(f64::INFINITY, f64::min)
            .max(0.0);
        let thickness = smallest.sqrt() / diagonal.max(f64::MIN_POSITIVE);
        if thickness < COPLANAR_TOLERANCE {
            return Err(MarkerError::Coplanar { thickness });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_pairs_and_ignores_comments() {
        let m = Markers::from_json(r#"{"comment": "x", "pairs": [[1, 2], [3, 4]]}"#).unwrap();
        assert_eq!(m.pairs, vec![[1, 2], [3, 4]]);
        assert_eq!(Markers::from_json(&m.to_json()).unwrap(), m);
        assert!(matches!(
            Markers::from_json(r#"{"pairs": [[1]]}"#),
            Err(MarkerError::Parse(_))
        ));
        assert!(matches!(
            Markers::from_json(r#"{"pairs": [[-1, 2]]}"#),
            Err(MarkerError::Parse(_))
        ));
    }

    #[test]
    fn validation_names_the_offending_marker() {
        let ok = Markers::new(vec![[0, 0], [1, 1], [2, 2], [3, 3]]);
        assert!(ok.validate(4, 4).is_ok());
        let e = ok.validate(4, 3).unwrap_err();
        assert_eq!(
            e,
            MarkerError::OutOfRange {
                marker: 3,
                side: Side::Target,
                vertex: 3,
                num_vertices: 3
            }
        );
        assert!(e.to_string().contains("marker 3: target vertex 3"));
        let dup = Markers::new(vec![[0, 0], [1, 1], [0, 2], [3, 3]]);
        assert_eq!(
            dup.validate(4, 4).unwrap_err(),
            MarkerError::Duplicate {
                first: 0,
                second: 2,
                side: Side::Source,
                vertex: 0
            }
        );
        let few = Markers::new(vec![[0, 0], [1, 1], [2, 2]]);
        assert!(matches!(
            few.validate(4, 4),
            Err(MarkerError::TooFew {
                found: 3,
                minimum: 4
            })
        ));
    }

    #[test]
    fn coplanar_markers_are_rejected() {
        let m = Markers::new(vec![[0, 0], [1, 1], [2, 2], [3, 3]]);
        let flat = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
        ];
        assert!(matches!(
            m.check_spread(&flat, 1.5),
            Err(MarkerError::Coplanar { .. })
        ));
        let tet = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        assert!(m.check_spread(&tet, 1.5).is_ok());
    }
}
