//! The generated curled tail of `tests/springs_twist.rs` (issue 40, "thin parts that turn
//! far") at α = ½, written as OBJs for pictures: per case the rest and curled shapes, the
//! linear blend, the predictor and the solve.
//!
//! `cargo run --release -p morphkit --example tail_twist -- OUT_DIR`; render with
//! `python3 tools/render_tail.py OUT_DIR PNG`.

#[path = "../tests/common/tail.rs"]
#[allow(dead_code)]
mod tail;

use morphkit::io::write_mesh;
use morphkit::mesh::{Point, ShapeSet, TriMesh};
use morphkit::springs::{linear_blend, BlendOptions, FixedVertices, PhysicalBlend, Weights};
use std::path::PathBuf;
use tail::Tail;

/// `mesh` as the base shape named `base`, and one target (what `tail` expects of its parent).
fn two_shapes(mesh: &TriMesh, base: &str, (name, target): (&str, Vec<Point>)) -> ShapeSet {
    ShapeSet::new(
        mesh.clone(),
        vec![(base.into(), mesh.positions.clone()), (name.into(), target)],
    )
    .unwrap()
}

fn main() {
    let out = PathBuf::from(std::env::args().nth(1).expect("usage: tail_twist OUT_DIR"));
    std::fs::create_dir_all(&out).unwrap();
    let cases = [
        (
            "auto-180-roll90",
            Tail::new(180.0, 90.0),
            FixedVertices::Auto,
        ),
        (
            "free-190-roll90",
            Tail::new(190.0, 90.0),
            FixedVertices::None,
        ),
    ];
    for (name, tail, fixed) in cases {
        let s = tail.shapes();
        let opts = BlendOptions {
            fixed,
            ..Default::default()
        };
        let mut b = PhysicalBlend::new(&s, &opts).unwrap();
        let w = Weights::Alpha(0.5);
        let solved = b.solve(&w).unwrap().positions;
        let shapes = [
            ("rest", s.positions(0).to_vec()),
            ("curled", s.positions(1).to_vec()),
            ("linear", linear_blend(&s, &w).unwrap()),
            ("predictor", b.predict(&w).unwrap()),
            ("solve", solved),
        ];
        for (what, p) in shapes {
            let m = TriMesh::new(p, s.triangles().to_vec());
            write_mesh(&out.join(format!("{name}-{what}.obj")), &m).unwrap();
        }
        println!("{name}: written to {}", out.display());
    }
}
