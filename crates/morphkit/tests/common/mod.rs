//! Shared helpers for integration tests: access to the real meshes under `MORPHKIT_DATA`.
#![allow(dead_code)]

pub mod defaults;
pub mod sequence;
pub mod tail;

use std::path::PathBuf;

/// The data directory, or `None` when `MORPHKIT_DATA` is unset (real-data tests then skip).
pub fn data_dir() -> Option<PathBuf> {
    let dir = std::env::var_os("MORPHKIT_DATA")?;
    let dir = PathBuf::from(dir);
    assert!(
        dir.is_dir(),
        "MORPHKIT_DATA={} is set but is not a directory",
        dir.display()
    );
    Some(dir)
}

/// A file under `MORPHKIT_DATA`: `None` when the variable is unset; a test failure when it is
/// set but the file is missing.
pub fn data_file(rel: &str) -> Option<PathBuf> {
    let p = data_dir()?.join(rel);
    assert!(
        p.is_file(),
        "MORPHKIT_DATA is set but {} is missing",
        p.display()
    );
    Some(p)
}

/// The ten ICT FaceKit expressions under `ict-facekit/`, in the rigs' target order.
pub const ICT_EXPRESSIONS: [&str; 10] = [
    "browInnerUp_L",
    "cheekPuff_L",
    "eyeBlink_L",
    "eyeBlink_R",
    "jawLeft",
    "jawOpen",
    "mouthFunnel",
    "mouthPucker",
    "mouthSmile_L",
    "mouthSmile_R",
];

/// The ICT rig's files: the neutral head, then [`ICT_EXPRESSIONS`]; `None` when
/// `MORPHKIT_DATA` is unset.
pub fn ict_rig_paths() -> Option<Vec<PathBuf>> {
    std::iter::once("generic_neutral_mesh")
        .chain(ICT_EXPRESSIONS)
        .map(|n| data_file(&format!("ict-facekit/{n}.obj.gz")))
        .collect()
}

/// Prints why a real-data test did nothing.
pub fn skip(test: &str) {
    eprintln!("{test}: MORPHKIT_DATA is unset; skipping the real-data test");
}

/// Asserts that two solves of the same frame are the same bits. (They once differed in the
/// last bits: METIS orderings computed on two threads at once interleaved the draws of its
/// process-wide random generator; METIS calls are now serialized.)
pub fn assert_same_frame(a: &[[f64; 3]], b: &[[f64; 3]], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: vertex counts differ");
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in b {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let diag = ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2) + (hi[2] - lo[2]).powi(2)).sqrt();
    let worst = a
        .iter()
        .zip(b)
        .map(|(p, q)| {
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max);
    assert!(
        worst == 0.0 && a == b,
        "{what}: frames differ by {worst:e} (diagonal {diag:e})"
    );
}

/// The largest distance between corresponding points of `a` and `b`.
pub fn max_dist(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| {
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max)
}

/// A closed bar (4 × 0.6 × 0.6, 16 segments) and the same bar bent by 90° over its second
/// half: its first half moves in no shape, so `FixedVertices::Auto` fixes it.
pub fn bent_bar() -> morphkit::mesh::ShapeSet {
    use morphkit::mesh::generate;
    let bar = generate::bar(4.0, 0.6, 2, 16);
    let bent = generate::bend(&bar.positions, 2.0, 2.0, std::f64::consts::FRAC_PI_2);
    two_shapes(&bar, "straight", ("bent", bent))
}

/// A closed tube (radius 0.5, length 4, `around` × `along` vertices) and the same tube bent
/// by `degrees` over its whole length.
pub fn bent_tube(around: usize, along: usize, degrees: f64) -> morphkit::mesh::ShapeSet {
    use morphkit::mesh::generate;
    let m = generate::tube(0.5, 4.0, around, along, true);
    let bent = generate::bend(&m.positions, 0.0, 4.0, degrees.to_radians());
    two_shapes(&m, "straight", ("bent", bent))
}

/// `mesh` as the base shape named `base`, and one target on its connectivity.
pub fn two_shapes(
    mesh: &morphkit::mesh::TriMesh,
    base: &str,
    (name, target): (&str, Vec<morphkit::mesh::Point>),
) -> morphkit::mesh::ShapeSet {
    morphkit::mesh::ShapeSet::new(
        mesh.clone(),
        vec![(base.into(), mesh.positions.clone()), (name.into(), target)],
    )
    .unwrap()
}

/// A source with frames and a target, for transfer quality (issue 9): the correspondence is
/// computed on `a_corr`, the frames are measured from `a_ref` (same connectivity).
pub struct Pair {
    pub name: &'static str,
    pub a_corr: morphkit::mesh::TriMesh,
    pub a_ref: morphkit::mesh::TriMesh,
    pub frames: Vec<Vec<morphkit::mesh::Point>>,
    pub b: morphkit::mesh::TriMesh,
    pub markers: morphkit::transfer::Markers,
}

/// Horse → camel with the ten horse poses; `None` when `MORPHKIT_DATA` is unset.
pub fn horse_camel() -> Option<Pair> {
    use morphkit::io::{read_mesh, read_shape_set};
    let h = data_file("sumner-horse-camel/horse-reference.obj.gz")?;
    let c = data_file("sumner-horse-camel/camel-reference.obj.gz")?;
    let mk = data_file("sumner-horse-camel/markers-horse-camel.json")?;
    let horse = read_mesh(&h).unwrap();
    let dir = data_dir().unwrap().join("sumner-horse-camel");
    let paths: Vec<PathBuf> = (1..=10)
        .map(|i| dir.join(format!("horse-{i:02}.obj.gz")))
        .collect();
    let poses = read_shape_set(&paths).unwrap();
    Some(Pair {
        name: "horse↔camel",
        a_corr: horse.clone(),
        a_ref: horse,
        frames: poses.all_positions().to_vec(),
        b: read_mesh(&c).unwrap(),
        markers: morphkit::transfer::Markers::read(&mk).unwrap(),
    })
}

/// Horse gallop → camel (an animation the issue-9 settings were not chosen on): all 48
/// gallop frames, divided by their 1.6768815 scale (the gallop's SOURCE.md) to the
/// horse-camel reference's, with the horse ↔ camel markers.
pub fn gallop_camel() -> Option<Pair> {
    let mut p = horse_camel()?;
    let dir = data_dir().unwrap().join("sumner-horse-gallop");
    p.name = "gallop→camel";
    p.frames = (1..=48)
        .map(|i| {
            let path = dir.join(format!("horse-gallop-{i:02}.obj.gz"));
            assert!(
                path.is_file(),
                "MORPHKIT_DATA is set but {} is missing",
                path.display()
            );
            let m = morphkit::io::read_mesh(&path).unwrap();
            assert_eq!(m.triangles, p.a_ref.triangles, "{}", path.display());
            m.positions
                .iter()
                .map(|q| q.map(|x| x / 1.6768815))
                .collect()
        })
        .collect();
    Some(p)
}

/// Horse collapse → camel (Sumner's cloth-simulated collapse, 27 of its 53 frames): vertices
/// put into the standard horse order by `collapse_to_standard_vertex_map.json`, divided by
/// the 1.6768815 scale, with the horse ↔ camel markers.
pub fn collapse_camel() -> Option<Pair> {
    let mut p = horse_camel()?;
    let map = data_file("sumner-horse-collapse/collapse_to_standard_vertex_map.json")?;
    let map: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(map).unwrap()).unwrap();
    let map: Vec<usize> = map["collapse_to_standard"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap() as usize)
        .collect();
    p.name = "collapse→camel";
    p.frames = (1..=53)
        .step_by(2)
        .map(|i| {
            let path = data_file(&format!(
                "sumner-horse-collapse/horse-collapse-{i:02}.obj.gz"
            ))
            .unwrap();
            let m = morphkit::io::read_mesh(&path).unwrap();
            assert_eq!(m.num_vertices(), map.len(), "{}", path.display());
            let mut out = vec![[0.0; 3]; m.num_vertices()];
            for (i, q) in m.positions.iter().enumerate() {
                out[map[i]] = q.map(|x| x / 1.6768815);
            }
            out
        })
        .collect();
    Some(p)
}

/// Cat → dog with the 36 frames of the cat's run; `None` when `MORPHKIT_DATA` is unset. The
/// run frames are at 0.1× the reference scale: frame 0 is the gradients' reference.
pub fn cat_dog() -> Option<Pair> {
    use morphkit::io::{read_mesh, read_shape_set};
    let cat = data_file("lowpoly-cat-dog/cat-reference.obj")?;
    let dog = data_file("lowpoly-cat-dog/dog-reference.obj")?;
    let mk = data_file("lowpoly-cat-dog/markers-cat-dog.json")?;
    let dir = data_dir().unwrap().join("lowpoly-cat-dog/cat-run");
    let paths: Vec<PathBuf> = (1..=36)
        .map(|i| dir.join(format!("cat-run-{i:02}.obj.gz")))
        .collect();
    let run = read_shape_set(&paths).unwrap();
    Some(Pair {
        name: "cat↔dog",
        a_corr: read_mesh(&cat).unwrap(),
        a_ref: run.mesh(0),
        frames: run.all_positions().to_vec(),
        b: read_mesh(&dog).unwrap(),
        markers: morphkit::transfer::Markers::read(&mk).unwrap(),
    })
}

/// The quality measures of one correspondence and transfer setting on a [`Pair`].
#[derive(Debug)]
pub struct Measured {
    pub cycle_mean: f64,
    pub cycle_max: f64,
    pub folds: usize,
    pub flipped: usize,
    pub correspond_s: f64,
    pub normal_pass: f64,
    pub coverage: f64,
}

/// Correspondence both ways with `copts`, then the cycle consistency with `topts`; printed.
pub fn measure_with(
    p: &Pair,
    copts: &morphkit::transfer::CorrespondenceOptions,
    topts: morphkit::transfer::TransferOptions,
) -> Measured {
    use morphkit::transfer::{correspond, correspondence_quality, cycle_consistency};
    let t0 = std::time::Instant::now();
    let fwd = correspond(&p.a_corr, &p.b, &p.markers, copts).unwrap();
    let correspond_s = t0.elapsed().as_secs_f64();
    let bwd = correspond(&p.b, &p.a_corr, &p.markers.reversed(), copts).unwrap();
    let c = cycle_consistency(
        &p.a_ref,
        &p.frames,
        &p.b,
        &fwd.correspondence,
        &bwd.correspondence,
        &topts,
    )
    .unwrap();
    let q = correspondence_quality(&fwd.correspondence);
    let m = Measured {
        cycle_mean: c.mean,
        cycle_max: c.max,
        folds: c.forward_sharp_folds.iter().sum(),
        flipped: c.forward_flipped.iter().sum(),
        correspond_s,
        normal_pass: q.normal_pass_fraction,
        coverage: q.source_coverage,
    };
    eprintln!("{}: {m:?}", p.name);
    m
}
