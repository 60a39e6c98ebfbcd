//! Writes the two meshes of `examples/bend-around-cylinder` (the README's scene example), so
//! that the example runs on a fresh clone: an open tube along x (x ∈ [-2, 2], radius 0.5,
//! 20 vertices around, 21 rings: 420 vertices, 800 triangles, like the cragl bending cylinder
//! of the project's real-mesh collection) and the same tube with its right half bent up by 50°
//! (bent over 0.6 ≤ x ≤ 1.2, straight beyond), coordinates rounded to 1e-6.
//!
//! `cargo run --release -p morphkit --example bend_around_cylinder -- examples/bend-around-cylinder`
//! writes `tube-rest.obj` and `tube-bend.obj` there (the committed files; a CLI test checks
//! that they are what this writes).

use morphkit::io::write_mesh;
use morphkit::mesh::{generate, Point, TriMesh};
use std::path::PathBuf;

/// `[x, y, z]` → `[x, z, y]`: [`generate::bend`] bends towards +y, the example bends towards +z.
fn swap_yz(p: &[Point]) -> Vec<Point> {
    p.iter().map(|&[x, y, z]| [x, z, y]).collect()
}

/// Rounded to 1e-6, so the files are short and read back exactly.
fn rounded(p: Vec<Point>) -> Vec<Point> {
    p.into_iter()
        .map(|q| q.map(|x| (x * 1e6).round() / 1e6 + 0.0))
        .collect()
}

/// The rest tube and the bent tube.
pub fn meshes() -> (TriMesh, TriMesh) {
    let tube = generate::tube(0.5, 4.0, 20, 20, false);
    let rest: Vec<Point> = tube
        .positions
        .iter()
        .map(|&[x, y, z]| [x - 2.0, y, z])
        .collect();
    let bent = swap_yz(&generate::bend(
        &swap_yz(&rest),
        0.6,
        0.6,
        50f64.to_radians(),
    ));
    (
        tube.with_positions(rounded(rest)),
        tube.with_positions(rounded(bent)),
    )
}

fn main() {
    let dir = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "examples/bend-around-cylinder".into()),
    );
    let (rest, bent) = meshes();
    for (name, mesh) in [("tube-rest.obj", &rest), ("tube-bend.obj", &bent)] {
        let path = dir.join(name);
        write_mesh(&path, mesh).unwrap_or_else(|e| panic!("{e}"));
        println!("wrote {}", path.display());
    }
}
