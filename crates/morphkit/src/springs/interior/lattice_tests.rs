use super::*;
use crate::mesh::generate;

#[test]
fn a_sphere_gets_a_connected_lattice_strictly_inside() {
    let m = generate::uv_sphere(1.0, 16, 24);
    let i = build(&m.positions, &m.triangles, &InteriorOptions::default());
    assert!(i.skipped.is_empty(), "{:?}", i.skipped);
    assert!(i.points.len() > 20, "{}", i.points.len());
    let h = i.spacing[0].1;
    for p in &i.points {
        assert!(norm(*p) <= 1.0 - 0.3 * h, "{p:?}");
    }
    // Every tet is positive and has only lattice springs as edges.
    let n = m.num_vertices() as u32;
    assert!(!i.tets.is_empty());
    for t in &i.tets {
        assert!(tet_volume6(|v| out_pos(&m.positions, &i.points, v), *t) > 0.0);
        assert!(t.iter().all(|&v| v >= n));
    }
    // Lattice-tet volume is a good part of the ball.
    let vol: f64 = i
        .tets
        .iter()
        .map(|t| tet_volume6(|v| out_pos(&m.positions, &i.points, v), *t) / 6.0)
        .sum();
    assert!(vol > 0.2 * 4.19, "{vol}");
    // Every surface vertex has a tie.
    let mut tied = vec![false; n as usize];
    for s in &i.springs {
        if s[0] < n {
            tied[s[0] as usize] = true;
        }
    }
    assert!(tied.iter().filter(|t| **t).count() > (n as usize) * 9 / 10);
}

#[test]
fn open_and_misoriented_components_are_skipped() {
    let open = generate::tube(0.5, 2.0, 12, 8, false);
    let i = build(
        &open.positions,
        &open.triangles,
        &InteriorOptions::default(),
    );
    assert!(i.points.is_empty());
    assert_eq!(i.skipped.len(), 1);
    assert_eq!(i.skipped[0].reason, "open");
    let mut bad = generate::uv_sphere(1.0, 8, 12);
    bad.triangles[3].swap(1, 2);
    let i = build(&bad.positions, &bad.triangles, &InteriorOptions::default());
    assert!(i.points.is_empty());
    assert_eq!(i.skipped[0].reason, "not consistently oriented");
    // An inward-oriented sphere is flipped, not skipped.
    let mut inward = generate::uv_sphere(1.0, 8, 12);
    inward.triangles.iter_mut().for_each(|t| t.swap(1, 2));
    let i = build(
        &inward.positions,
        &inward.triangles,
        &InteriorOptions::default(),
    );
    assert!(!i.points.is_empty());
}
