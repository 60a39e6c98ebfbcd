//! Unit tests of [`super::Weld`]: seams weld back, touching shells stay apart.
use super::*;
use crate::mesh::generate;

/// `m` with the vertices of `split` duplicated at the end, the triangles in `uses` using
/// the copies: a seam as exporters write it.
fn split(m: &TriMesh, split: &[u32]) -> TriMesh {
    let mut p = m.positions.clone();
    let mut tris = m.triangles.clone();
    for &v in split {
        p.push(m.positions[v as usize]);
        let copy = (p.len() - 1) as u32;
        // Every other triangle around v takes the copy.
        let mut k = 0;
        for t in tris.iter_mut() {
            if let Some(c) = t.iter().position(|&x| x == v) {
                if k % 2 == 1 {
                    t[c] = copy;
                }
                k += 1;
            }
        }
    }
    TriMesh::new(p, tris)
}

#[test]
fn split_vertices_weld_back_to_the_unsplit_mesh() {
    let m = generate::grid(6, 5, 1.0, 1.0);
    let seam: Vec<u32> = (7..12).collect();
    let s = split(&m, &seam);
    let bent = generate::bend(&s.positions, 0.5, 0.5, 1.0);
    let shapes = ShapeSet::new(
        s.clone(),
        vec![("a".into(), s.positions.clone()), ("b".into(), bent)],
    )
    .unwrap();
    let w = Weld::of_shapes(&shapes, WELD_TOLERANCE);
    assert_eq!(w.merged(), seam.len());
    let welded = w.shapes(&shapes).unwrap();
    assert_eq!(welded.base().positions, m.positions);
    assert_eq!(welded.triangles(), &m.triangles[..]);
    // Scatter puts every copy where its original is.
    let back = w.scatter(welded.positions(1));
    assert_eq!(back, shapes.positions(1));
    // Ids map both ways: input 7 and its copy (appended first, at 42) are welded 7.
    assert_eq!(w.to_welded()[42], 7);
    assert_eq!(w.welded_ids(&[42, 7, 99]), [7, 99]);
    assert_eq!(w.input_vertices(&[7]), [7, 42]);
}

/// `m` with a second shell appended: copies of the triangles `tris` of `m` on fresh
/// vertices at the same places (a shell lying on the first, as eyelashes on skin).
fn with_shell_on(m: &TriMesh, tris: std::ops::Range<usize>) -> TriMesh {
    let mut p = m.positions.clone();
    let mut t = m.triangles.clone();
    let mut fresh: FastMap<u32, u32> = FastMap::default();
    for k in tris {
        let tri = m.triangles[k].map(|v| {
            *fresh.entry(v).or_insert_with(|| {
                p.push(m.positions[v as usize]);
                (p.len() - 1) as u32
            })
        });
        t.push(tri);
    }
    TriMesh::new(p, t)
}

/// How many edges of `triangles` three or more triangles use.
fn non_manifold_edges(triangles: &[[u32; 3]]) -> usize {
    let mut uses: FastMap<(u32, u32), usize> = FastMap::default();
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *uses.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    uses.values().filter(|&&u| u > 2).count()
}

#[test]
fn shells_that_only_touch_stay_apart_while_seams_weld() {
    // A strip of triangles lying on the grid, vertex on vertex and edge on edge: every
    // one of its vertices coincides with a grid vertex in both shapes, but joining it would
    // give its border edges three triangles and its inner edges four.
    let m = generate::grid(6, 5, 1.0, 1.0);
    let shell = with_shell_on(&m, 0..8);
    let shapes = |mesh: &TriMesh| {
        let bent = generate::bend(&mesh.positions, 0.5, 0.5, 1.0);
        ShapeSet::new(
            mesh.clone(),
            vec![("a".into(), mesh.positions.clone()), ("b".into(), bent)],
        )
        .unwrap()
    };
    let w = Weld::of_shapes(&shapes(&shell), WELD_TOLERANCE);
    assert!(w.is_identity(), "{} shell vertices welded", w.merged());
    // The same rig with a seam split elsewhere welds the seam alone.
    let seam: Vec<u32> = (19..23).collect();
    let both = with_shell_on(&split(&m, &seam), 0..8);
    let w = Weld::of_shapes(&shapes(&both), WELD_TOLERANCE);
    assert_eq!(w.merged(), seam.len());
    assert_eq!(non_manifold_edges(&w.triangles(&both.triangles)), 0);
    // Coincidence alone (the old rule) fuses the shell: edges of three and four triangles.
    let fused = Weld::coincident(&[&both.positions], WELD_TOLERANCE);
    assert!(non_manifold_edges(&fused.triangles(&both.triangles)) > 0);
}

#[test]
fn a_frame_that_is_a_shape_gives_every_copy_its_own_numbers() {
    // Copies a hair apart (within the tolerance) in both shapes: welded, and at each
    // shape's one-hot coefficients scattered back to their own positions exactly.
    let m = generate::grid(6, 5, 1.0, 1.0);
    let mut s = split(&m, &[9, 10]);
    let last = s.positions.len() - 1;
    s.positions[last][0] += 3e-8;
    let mut bent = generate::bend(&s.positions, 0.5, 0.5, 1.0);
    bent[last][1] -= 2e-8;
    let shapes = ShapeSet::new(
        s.clone(),
        vec![
            ("a".into(), s.positions.clone()),
            ("b".into(), bent.clone()),
        ],
    )
    .unwrap();
    let w = Weld::of_shapes(&shapes, WELD_TOLERANCE);
    assert_eq!(w.merged(), 2);
    let welded = w.shapes(&shapes).unwrap();
    for (k, own) in [&s.positions, &bent].into_iter().enumerate() {
        let c = if k == 0 { [1.0, 0.0] } else { [0.0, 1.0] };
        assert_eq!(&w.scatter_frame(welded.positions(k), &c), own);
        assert_ne!(&w.scatter(welded.positions(k)), own);
    }
    // Between the shapes, copies share their welded vertex's position.
    let mid = w.scatter_frame(welded.positions(1), &[0.5, 0.5]);
    assert_eq!(mid, w.scatter(welded.positions(1)));
}

#[test]
fn a_seam_split_three_ways_welds_to_one_vertex() {
    // Every triangle on its own vertices (a flat-shaded export): all copies weld back.
    let m = generate::grid(4, 3, 1.0, 1.0);
    let mut p = Vec::new();
    let mut t = Vec::new();
    for tri in &m.triangles {
        t.push(tri.map(|v| {
            p.push(m.positions[v as usize]);
            (p.len() - 1) as u32
        }));
    }
    let flat = TriMesh::new(p, t);
    let w = Weld::of_mesh(&flat, WELD_TOLERANCE);
    assert_eq!(w.num_welded(), m.num_vertices());
    assert_eq!(non_manifold_edges(&w.triangles(&flat.triangles)), 0);
}

#[test]
fn triangles_that_use_a_vertex_twice_are_left_out_of_the_solve_only() {
    let mut m = generate::grid(3, 3, 1.0, 1.0);
    m.triangles.push([0, 0, 1]);
    let shapes = ShapeSet::new(
        m.clone(),
        vec![
            ("a".into(), m.positions.clone()),
            ("b".into(), m.positions.clone()),
        ],
    )
    .unwrap();
    let w = Weld::of_shapes(&shapes, WELD_TOLERANCE);
    assert!(w.is_identity());
    let solved = w.shapes(&shapes).unwrap();
    assert_eq!(solved.triangles().len(), m.triangles.len() - 1);
    assert_eq!(shapes.triangles().len(), m.triangles.len());
}

#[test]
fn pairs_across_cell_sides_are_found() {
    // Points a tenth of the tolerance apart, placed on both sides of every cell side the
    // grid could have, weld; points two tolerances apart do not.
    let d = 1.0;
    let tol = WELD_TOLERANCE * d;
    let mut p = vec![[0.0, 0.0, 0.0], [d / 3f64.sqrt(); 3]];
    for k in 0..200 {
        let x = 0.3 + k as f64 * 0.37 * tol;
        let y = 0.001 * k as f64;
        p.push([x, 0.5 + y, 0.5]);
        p.push([x + 0.1 * tol, 0.5 + y, 0.5 - 0.05 * tol]);
        p.push([x, 0.9 + y, 0.9]);
        p.push([x + 2.0 * tol, 0.9 + y, 0.9]);
    }
    let w = Weld::coincident(&[&p], WELD_TOLERANCE);
    for k in 0..200 {
        let v = 2 + 4 * k;
        assert_eq!(w.to_welded()[v], w.to_welded()[v + 1], "pair {k}");
        assert_ne!(w.to_welded()[v + 2], w.to_welded()[v + 3], "far pair {k}");
    }
}

#[test]
fn vertices_that_part_in_one_shape_stay_apart() {
    let m = generate::grid(4, 4, 1.0, 1.0);
    let s = split(&m, &[5]);
    let mut parted = s.positions.clone();
    let last = parted.len() - 1;
    parted[last][2] += 0.1;
    let shapes = ShapeSet::new(
        s.clone(),
        vec![("a".into(), s.positions.clone()), ("b".into(), parted)],
    )
    .unwrap();
    let w = Weld::of_shapes(&shapes, WELD_TOLERANCE);
    assert!(w.is_identity());
    assert_eq!(w.shapes(&shapes).unwrap().num_vertices(), s.num_vertices());
}

#[test]
fn a_single_mesh_welds_its_coincident_vertices_and_keeps_its_triangles() {
    let m = generate::grid(5, 4, 1.0, 1.0);
    let s = split(&m, &[6, 7, 8]);
    let w = Weld::of_mesh(&s, WELD_TOLERANCE);
    assert_eq!(w.merged(), 3);
    assert!(w.keeps_triangles(&s.triangles));
    assert_eq!(w.mesh(&s), m);
    assert_eq!(w.representative().len(), m.num_vertices());
    // Sets of other vertex counts weld nothing.
    let other = vec![[0.0; 3]; 2];
    assert!(
        Weld::of_positions(&[&s.positions, &other], &s.triangles, WELD_TOLERANCE).is_identity()
    );
    // A triangle with two coincident corners would be lost.
    let mut p = m.positions.clone();
    p[1] = p[0];
    assert!(
        !Weld::of_mesh(&TriMesh::new(p, m.triangles.clone()), WELD_TOLERANCE)
            .keeps_triangles(&m.triangles)
    );
}
