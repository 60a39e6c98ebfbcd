//! Seam-split meshes as exporters write them (issue 37's weld tests): OBJ text read and
//! written as plain vertex and face lists, and a split of a rig along the plane y = 0.

use std::path::{Path, PathBuf};

/// The positions and faces (0-based) of an OBJ file.
pub type Mesh = (Vec<[f64; 3]>, Vec<Vec<usize>>);

/// Reads `p`'s `v` and `f` records.
pub fn read(p: &Path) -> Mesh {
    let text = std::fs::read_to_string(p).unwrap();
    let (mut v, mut f) = (Vec::new(), Vec::new());
    for l in text.lines() {
        let t: Vec<&str> = l.split_whitespace().collect();
        match t.first() {
            Some(&"v") => v.push([t[1], t[2], t[3]].map(|x| x.parse().unwrap())),
            Some(&"f") => f.push(
                t[1..]
                    .iter()
                    .map(|x| x.split('/').next().unwrap().parse::<usize>().unwrap() - 1)
                    .collect(),
            ),
            _ => {}
        }
    }
    (v, f)
}

/// Writes `v` and `f` records to `p`.
pub fn write(p: &Path, (v, f): &Mesh) {
    let mut s = String::new();
    for q in v {
        s += &format!("v {} {} {}\n", q[0], q[1], q[2]);
    }
    for t in f {
        s += "f";
        for i in t {
            s += &format!(" {}", i + 1);
        }
        s += "\n";
    }
    std::fs::write(p, s).unwrap();
}

/// A split of meshes of one connectivity as an exporter writes a UV seam: the faces whose
/// base centroid has y > 0 use copies of the vertices they share with the others (faces keep
/// their order); with `shuffle`, the vertices are also reordered.
pub struct Split {
    /// The split meshes.
    pub meshes: Vec<Mesh>,
    /// The unsplit vertex of each split vertex.
    pub origin: Vec<usize>,
}

impl Split {
    pub fn new(shapes: &[Mesh], shuffle: bool) -> Self {
        let (v0, f) = &shapes[0];
        let upper: Vec<bool> = f
            .iter()
            .map(|t| t.iter().map(|&i| v0[i][1]).sum::<f64>() > 0.0)
            .collect();
        let n = v0.len();
        let (mut a, mut b) = (vec![false; n], vec![false; n]);
        for (t, &u) in f.iter().zip(&upper) {
            for &i in t {
                if u {
                    a[i] = true
                } else {
                    b[i] = true
                }
            }
        }
        let seam: Vec<usize> = (0..n).filter(|&i| a[i] && b[i]).collect();
        assert!(seam.len() > 10, "the split must cut a seam");
        let mut copy = vec![usize::MAX; n];
        for (k, &v) in seam.iter().enumerate() {
            copy[v] = n + k;
        }
        let origin: Vec<usize> = (0..n).chain(seam.iter().copied()).collect();
        let mut order: Vec<usize> = (0..origin.len()).collect();
        if shuffle {
            let mut x: u64 = 987654321;
            for i in (1..order.len()).rev() {
                x = x
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                order.swap(i, (x >> 33) as usize % (i + 1));
            }
        }
        let mut new_index = vec![0; order.len()];
        for (k, &o) in order.iter().enumerate() {
            new_index[o] = k;
        }
        let faces: Vec<Vec<usize>> = f
            .iter()
            .zip(&upper)
            .map(|(t, &u)| {
                t.iter()
                    .map(|&i| {
                        new_index[if u && copy[i] != usize::MAX {
                            copy[i]
                        } else {
                            i
                        }]
                    })
                    .collect()
            })
            .collect();
        let meshes = shapes
            .iter()
            .map(|(v, _)| {
                let all: Vec<[f64; 3]> = origin.iter().map(|&o| v[o]).collect();
                (order.iter().map(|&o| all[o]).collect(), faces.clone())
            })
            .collect();
        let origin = order.iter().map(|&o| origin[o]).collect();
        Self { meshes, origin }
    }

    /// Splits the mesh files `inputs` (one connectivity) into `outputs`.
    pub fn files(inputs: &[PathBuf], outputs: &[PathBuf], shuffle: bool) -> Self {
        let shapes: Vec<Mesh> = inputs.iter().map(|p| read(p)).collect();
        let s = Self::new(&shapes, shuffle);
        for (m, p) in s.meshes.iter().zip(outputs) {
            write(p, m);
        }
        s
    }

    /// Copies of seam vertices.
    pub fn copies(&self) -> usize {
        let n = self.origin.iter().max().unwrap() + 1;
        self.origin.len() - n
    }

    /// A split vertex of unsplit vertex `v`: the last one (a copy, where `v` has one).
    pub fn id(&self, v: usize) -> usize {
        self.origin.iter().rposition(|&o| o == v).unwrap()
    }
}

/// The bounding-box diagonal of `v`.
pub fn diagonal(v: &[[f64; 3]]) -> f64 {
    let mut d = 0.0;
    for k in 0..3 {
        let lo = v.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min);
        let hi = v.iter().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max);
        d += (hi - lo) * (hi - lo);
    }
    f64::sqrt(d)
}

/// `plain` with a material library, a group, smoothing, a texture coordinate and a normal per
/// vertex, and faces that use them (`v/vt/vn`).
pub fn dress(plain: &Path, dressed: &Path) {
    let (v, f) = read(plain);
    let mut s = String::from("# exported by a DCC tool\nmtllib tube.mtl\no Tube\n");
    for p in &v {
        s += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    for (k, _) in v.iter().enumerate() {
        s += &format!("vt {} 0.5\n", k as f64 / v.len() as f64);
    }
    for _ in &v {
        s += "vn 0 0 1\n";
    }
    s += "g body\nusemtl skin\ns 1\n";
    for t in &f {
        s += "f";
        for &i in t {
            s += &format!(" {0}/{0}/{0}", i + 1);
        }
        s += "\n";
    }
    std::fs::write(dressed, s).unwrap();
}

/// The lines of `p` that `keep` keeps.
pub fn records(p: &Path, keep: impl Fn(&str) -> bool) -> Vec<String> {
    std::fs::read_to_string(p)
        .unwrap()
        .lines()
        .filter(|l| keep(l))
        .map(String::from)
        .collect()
}
