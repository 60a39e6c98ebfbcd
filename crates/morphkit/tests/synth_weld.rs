//! Issue 37: `synth` welds like every solving command. A seam-split copy of a generated mesh
//! (target and source, split along a line of vertices, copies appended) synthesizes equal to the
//! unsplit mesh within 1e-9 of the diagonal, results in the split mesh's own layout; copies
//! that part in one of the target's shapes are not welded.

use morphkit::io::write_mesh;
use morphkit::mesh::{generate, Point, TriMesh};
use morphkit::synth::{BuiltRecipe, RecipeFile};
use std::path::{Path, PathBuf};

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("morphkit-synth-weld-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `m` cut open along the lengthwise line of vertices at y = 0.25, z = 0: triangles on the
/// z > 0 side use copies of those vertices, appended in order. Returns the split mesh and the
/// original of every vertex.
fn split(m: &TriMesh) -> (TriMesh, Vec<usize>) {
    let n = m.num_vertices();
    let seam = |p: &Point| (p[1] - 0.25).abs() < 1e-12 && p[2].abs() < 1e-12;
    let mut original: Vec<usize> = (0..n).collect();
    let mut copy = vec![usize::MAX; n];
    for v in 0..n {
        if seam(&m.positions[v]) {
            copy[v] = original.len();
            original.push(v);
        }
    }
    assert_eq!(original.len() - n, 25, "a copy per ring");
    let triangles = m
        .triangles
        .iter()
        .map(|t| {
            let z: f64 = t.iter().map(|&v| m.positions[v as usize][2]).sum();
            if z > 0.0 {
                t.map(|v| {
                    let c = copy[v as usize];
                    if c == usize::MAX {
                        v
                    } else {
                        c as u32
                    }
                })
            } else {
                *t
            }
        })
        .collect();
    let positions = original.iter().map(|&v| m.positions[v]).collect();
    (TriMesh::new(positions, triangles), original)
}

/// Writes the target, its own bends, a source with twists, markers and scribbles into `d`
/// (split or not), and the recipe; `part` moves the copies of the target's second bend.
fn write_case(d: &Path, split_it: bool, part: bool) -> Vec<usize> {
    let bar = generate::bar(4.0, 0.5, 2, 24);
    let (target, original) = if split_it {
        split(&bar)
    } else {
        (bar.clone(), (0..bar.num_vertices()).collect())
    };
    let n = bar.num_vertices();
    let at = |p: Vec<Point>| -> Vec<Point> { original.iter().map(|&v| p[v]).collect() };
    write_mesh(&d.join("target.obj"), &target).unwrap();
    std::fs::create_dir_all(d.join("bends")).unwrap();
    std::fs::create_dir_all(d.join("twists")).unwrap();
    for k in 0..3 {
        let a = (k as f64 + 1.0) * 25f64.to_radians();
        let mut p = at(generate::bend(&bar.positions, 1.8, 0.6, a));
        if part && k == 1 {
            // The seam opens in this shape: its copies are no longer where their originals are.
            for q in &mut p[n..] {
                q[2] += 0.01;
            }
        }
        write_mesh(
            &d.join(format!("bends/b{k}.obj")),
            &target.with_positions(p),
        )
        .unwrap();
        // A source whose near half twists about the bar's axis.
        let t = (k as f64 + 1.0) * 0.3;
        let tw: Vec<Point> = bar
            .positions
            .iter()
            .map(|q| {
                let a = t * (1.8 - q[0]).max(0.0) / 1.8;
                let (s, c) = a.sin_cos();
                [q[0], c * q[1] - s * q[2], s * q[1] + c * q[2]]
            })
            .collect();
        write_mesh(
            &d.join(format!("twists/t{k}.obj")),
            &target.with_positions(at(tw)),
        )
        .unwrap();
    }
    write_mesh(&d.join("source.obj"), &target).unwrap();
    // Markers at both ends and on the seam (ids of originals: the same in both layouts).
    let seam = (0..n)
        .find(|&v| {
            let p = bar.positions[v];
            (p[1] - 0.25).abs() < 1e-12 && p[2].abs() < 1e-12 && p[0] > 1.0
        })
        .unwrap();
    let pairs: Vec<[usize; 2]> = [0, 7, n / 2, n - 1, seam].iter().map(|&v| [v, v]).collect();
    std::fs::write(
        d.join("markers.json"),
        serde_json::json!({ "pairs": pairs }).to_string(),
    )
    .unwrap();
    // A vertex scribble (every vertex with x ≥ 2, copies included) and a triangle scribble.
    let far: Vec<usize> = (0..target.num_vertices())
        .filter(|&v| target.positions[v][0] >= 2.0)
        .collect();
    std::fs::write(
        d.join("far.json"),
        serde_json::json!({ "vertices": far }).to_string(),
    )
    .unwrap();
    let near: Vec<usize> = (0..target.num_triangles())
        .filter(|&t| target.positions[target.triangles[t][0] as usize][0] < 1.5)
        .collect();
    std::fs::write(
        d.join("near.json"),
        serde_json::json!({ "triangles": near }).to_string(),
    )
    .unwrap();
    std::fs::write(
        d.join("r.toml"),
        "target = \"target.obj\"\nframes = 5\n\n[[layer]]\nname = \"bend\"\n\
         source_frames = \"bends/b*.obj\"\nscribble = \"far.json\"\nloop = true\n\n\
         [[layer]]\nname = \"twist\"\nsource_reference = \"source.obj\"\n\
         source_frames = \"twists/t*.obj\"\nmarkers = \"markers.json\"\nscribble = \"near.json\"\n\
         mode = \"compound\"\nloop = true\nblend_region = \"geodesic\"\nblend_width = 0.1\n",
    )
    .unwrap();
    original
}

fn build(d: &Path) -> BuiltRecipe {
    RecipeFile::read(&d.join("r.toml"))
        .unwrap()
        .build()
        .unwrap()
}

#[test]
fn a_seam_split_copy_synthesizes_like_the_unsplit_mesh() {
    let (du, ds) = (dir("unsplit"), dir("split"));
    write_case(&du, false, false);
    let original = write_case(&ds, true, false);
    let (unsplit, split) = (build(&du), build(&ds));
    let n = unsplit.target.num_vertices();
    let copies = original.len() - n;
    assert_eq!(unsplit.weld.merged(), 0);
    assert_eq!(split.weld.merged(), copies);
    assert_eq!(split.source_welded_vertices, [copies, copies]);
    let diag = unsplit.target.bbox_diagonal();
    let mut moved: f64 = 0.0;
    for f in 0..5 {
        let a = unsplit.frame(f).unwrap().positions;
        let b = split.frame(f).unwrap().positions;
        assert_eq!(b.len(), original.len(), "the split mesh's own layout");
        for (v, &o) in original.iter().enumerate() {
            let d = (0..3)
                .map(|k| (a[o][k] - b[v][k]).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!(d <= 1e-9 * diag, "frame {f}, vertex {v}: {d:e}");
            moved = moved.max(
                (0..3)
                    .map(|k| (a[o][k] - unsplit.target.positions[o][k]).abs())
                    .fold(0.0, f64::max),
            );
        }
        let fr = split.frame(f).unwrap();
        assert_eq!(
            split.flipped_triangles(&fr).len(),
            unsplit.flipped_triangles(&unsplit.frame(f).unwrap()).len()
        );
    }
    assert!(moved > 0.1 * diag, "the frames move ({moved})");
    // Without the weld the cut bar solves differently: the seam is not one vertex there.
    let plain = split.synthesizer.frame(4).unwrap().positions;
    assert_eq!(plain.len(), n, "the synthesizer works on the welded target");
    let _ = std::fs::remove_dir_all(&du);
    let _ = std::fs::remove_dir_all(&ds);
}

#[test]
fn copies_that_part_in_a_shape_are_not_welded() {
    let d = dir("parted");
    let original = write_case(&d, true, true);
    let built = build(&d);
    assert_eq!(built.weld.merged(), 0, "the target's copies part in bend 1");
    assert_eq!(built.weld.num_input(), original.len());
    // The source's copies never part: welded.
    assert!(built.source_welded_vertices[1] > 0);
    // Its frames keep the split layout, and the seam, free to open, does.
    let bar_n = generate::bar(4.0, 0.5, 2, 24).num_vertices();
    let mut open: f64 = 0.0;
    for f in 0..5 {
        let p = built.frame(f).unwrap().positions;
        assert_eq!(p.len(), original.len());
        for v in bar_n..p.len() {
            let o = original[v];
            open = open.max(
                (0..3)
                    .map(|k| (p[v][k] - p[o][k]).abs())
                    .fold(0.0, f64::max),
            );
        }
    }
    assert!(open > 1e-4, "the seam stays shut ({open:e})");
    let _ = std::fs::remove_dir_all(&d);
}
