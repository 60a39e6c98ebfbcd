//! Scribbles and intelligent scribbling (Wang & Lee 2008, Sec. 3.2.1).
//!
//! A scribble is a set of target elements, JSON `{"triangles": [...]}` or
//! `{"vertices": [...]}` with 0-based indices; a vertex scribble covers the triangles whose
//! three vertices are all scribbled (the region the vertices span, not grown). Intelligent
//! scribbling then refines it by the [`Partitions`]: a stiff partition is **selected** when
//! more than half of its triangles are scribbled, and not at all otherwise; flexible
//! (single-triangle) partitions are never selected, their weights come from Eq. 5.

use super::{Partitions, SynthError};
use serde::Deserialize;
use std::path::Path;

/// Scribbled target elements (0-based).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Scribble {
    /// Triangle indices.
    Triangles(Vec<u32>),
    /// Vertex indices.
    Vertices(Vec<u32>),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ScribbleFile {
    triangles: Option<Vec<u32>>,
    vertices: Option<Vec<u32>>,
}

impl Scribble {
    /// Parses `{"triangles": [...]}` or `{"vertices": [...]}`.
    pub fn from_json(text: &str) -> Result<Self, SynthError> {
        let f: ScribbleFile =
            serde_json::from_str(text).map_err(|e| SynthError::ScribbleParse(e.to_string()))?;
        match (f.triangles, f.vertices) {
            (Some(t), None) => Ok(Scribble::Triangles(t)),
            (None, Some(v)) => Ok(Scribble::Vertices(v)),
            _ => Err(SynthError::ScribbleParse(
                "give exactly one of \"triangles\" or \"vertices\"".into(),
            )),
        }
    }

    /// Reads a scribble file.
    pub fn read(path: &Path) -> Result<Self, SynthError> {
        let text = std::fs::read_to_string(path).map_err(|e| {
            SynthError::ScribbleParse(format!("{}: cannot read: {e}", path.display()))
        })?;
        Self::from_json(&text)
            .map_err(|e| SynthError::ScribbleParse(format!("{}: {e}", path.display())))
    }

    /// Writes the scribble as JSON.
    pub fn to_json(&self) -> String {
        match self {
            Scribble::Triangles(t) => serde_json::json!({ "triangles": t }),
            Scribble::Vertices(v) => serde_json::json!({ "vertices": v }),
        }
        .to_string()
    }

    /// The scribbled triangles of a mesh with these `triangles` over `num_vertices`, as a mask.
    /// Errors: an empty scribble, an index out of range, vertices spanning no triangle.
    pub fn triangle_mask(
        &self,
        num_vertices: usize,
        triangles: &[[u32; 3]],
    ) -> Result<Vec<bool>, SynthError> {
        let nf = triangles.len();
        let (list, what, count) = match self {
            Scribble::Triangles(t) => (t, "triangle", nf),
            Scribble::Vertices(v) => (v, "vertex", num_vertices),
        };
        if list.is_empty() {
            return Err(SynthError::EmptyScribble);
        }
        if let Some(&i) = list.iter().find(|&&i| i as usize >= count) {
            return Err(SynthError::ScribbleOutOfRange {
                what,
                index: i,
                count,
            });
        }
        let mut mask = vec![false; nf];
        match self {
            Scribble::Triangles(t) => t.iter().for_each(|&i| mask[i as usize] = true),
            Scribble::Vertices(v) => {
                let mut on = vec![false; num_vertices];
                v.iter().for_each(|&i| on[i as usize] = true);
                for (m, tri) in mask.iter_mut().zip(triangles) {
                    *m = tri.iter().all(|&i| on[i as usize]);
                }
                if !mask.iter().any(|&m| m) {
                    return Err(SynthError::ScribbleCoversNoTriangle { vertices: v.len() });
                }
            }
        }
        Ok(mask)
    }
}

/// The outcome of intelligent scribbling.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Selection {
    /// Per partition: selected (only stiff partitions can be).
    pub partitions: Vec<bool>,
    /// Per triangle: in a selected partition.
    pub triangles: Vec<bool>,
}

impl Selection {
    /// Refines the scribbled `mask` (one entry per triangle) by `partitions`. Selecting
    /// nothing is an error ([`SynthError::NothingSelected`]).
    pub fn refine(partitions: &Partitions, mask: &[bool]) -> Result<Self, SynthError> {
        let nf = partitions.num_triangles();
        if mask.len() != nf {
            return Err(SynthError::Length {
                what: "scribble mask",
                expected: nf,
                found: mask.len(),
            });
        }
        let mut hits = vec![0usize; partitions.num_partitions()];
        for (t, _) in mask.iter().enumerate().filter(|(_, &m)| m) {
            hits[partitions.label(t)] += 1;
        }
        let selected: Vec<bool> = (0..partitions.num_partitions())
            .map(|p| partitions.is_stiff(p) && 2 * hits[p] > partitions.size(p))
            .collect();
        if !selected.iter().any(|&s| s) {
            return Err(SynthError::NothingSelected {
                scribbled: mask.iter().filter(|&&m| m).count(),
                stiff: partitions.num_stiff(),
            });
        }
        let triangles = (0..nf).map(|t| selected[partitions.label(t)]).collect();
        Ok(Self {
            partitions: selected,
            triangles,
        })
    }

    /// Number of selected triangles.
    pub fn num_triangles(&self) -> usize {
        self.triangles.iter().filter(|&&s| s).count()
    }
}

/// One-shot intelligent scribbling: the scribble's triangles refined by `partitions`.
pub fn refine_scribble(
    scribble: &Scribble,
    partitions: &Partitions,
    num_vertices: usize,
    triangles: &[[u32; 3]],
) -> Result<Selection, SynthError> {
    Selection::refine(
        partitions,
        &scribble.triangle_mask(num_vertices, triangles)?,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;
    use crate::synth::partitions::partitions_of;

    #[test]
    fn more_than_half_selects_a_partition() {
        let g = generate::grid(10, 1, 10.0, 1.0);
        let values = (0..20)
            .map(|t| if (8..12).contains(&t) { 0.5 } else { 0.01 })
            .collect();
        let p = partitions_of(&g, values);
        // 5 of the left part's 8 and 4 of the right part's 8, plus a flexible one.
        let s = Scribble::Triangles(vec![0, 1, 2, 3, 4, 9, 12, 13, 14, 15]);
        let sel = refine_scribble(&s, &p, g.num_vertices(), &g.triangles).unwrap();
        assert_eq!(sel.num_triangles(), 8);
        assert!(sel.triangles[7] && !sel.triangles[9] && !sel.triangles[12]);
        let none = Scribble::Triangles(vec![0, 1, 2, 3]);
        assert!(matches!(
            refine_scribble(&none, &p, g.num_vertices(), &g.triangles),
            Err(SynthError::NothingSelected { scribbled: 4, .. })
        ));
    }

    #[test]
    fn files_and_bad_input() {
        let g = generate::grid(2, 2, 1.0, 1.0);
        assert_eq!(
            Scribble::from_json(r#"{"vertices": [0, 1, 4]}"#).unwrap(),
            Scribble::Vertices(vec![0, 1, 4])
        );
        let s = Scribble::from_json(&Scribble::Vertices(vec![0, 1, 4]).to_json()).unwrap();
        let m = s.triangle_mask(g.num_vertices(), &g.triangles).unwrap();
        assert_eq!(m.iter().filter(|&&x| x).count(), 1);
        let e = Scribble::Triangles(vec![8])
            .triangle_mask(g.num_vertices(), &g.triangles)
            .unwrap_err();
        assert!(e.to_string().contains("triangle 8 is out of range"), "{e}");
        assert!(matches!(
            Scribble::Triangles(vec![]).triangle_mask(9, &g.triangles),
            Err(SynthError::EmptyScribble)
        ));
        assert!(Scribble::from_json(r#"{"triangle": [1]}"#).is_err());
        assert!(Scribble::from_json(r#"{"triangles": [1], "vertices": [2]}"#).is_err());
    }
}
