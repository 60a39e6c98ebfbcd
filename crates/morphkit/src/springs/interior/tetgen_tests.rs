use super::*;

/// A file in a per-test directory outside the `morphkit-tetgen-<pid>-` prefix.
fn tmp(name: &str, text: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("morphkit-parse-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let p = d.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn node_and_ele_files_parse_and_bad_ones_name_file_and_line() {
    let p = tmp(
        "a.node",
        "# c\n3 3 0 0\n0 0 0 0\n1 1 0 0 # x\n\n2 0 1e0 0.5\n",
    );
    assert_eq!(
        read_nodes(&p).unwrap(),
        vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.5]]
    );
    let p = tmp("b.node", "2 3 0 0\n0 0 0 0\n1 1 zero 0\n");
    let e = read_nodes(&p).unwrap_err().to_string();
    assert!(
        e.contains("b.node line 3") && e.contains("coordinate"),
        "{e}"
    );
    let p = tmp("c.node", "3 3 0 0\n1 0 0 0\n");
    let e = read_nodes(&p).unwrap_err().to_string();
    assert!(e.contains("announced"), "{e}");
    let p = tmp("d.ele", "1 4 0\n0 0 1 2 3\n");
    assert_eq!(read_tets(&p, 4).unwrap(), vec![[0, 1, 2, 3]]);
    let e = read_tets(&p, 3).unwrap_err().to_string();
    assert!(
        e.contains("d.ele line 2") && e.contains("out of range"),
        "{e}"
    );
    let p = tmp("e.ele", "1 10 0\n");
    assert!(read_tets(&p, 4)
        .unwrap_err()
        .to_string()
        .contains("expected 4"));
    assert!(read_nodes(&PathBuf::from("/nonexistent/x.node"))
        .unwrap_err()
        .to_string()
        .contains("cannot read"));
}

fn leftovers() -> Vec<String> {
    let prefix = format!("morphkit-tetgen-{}-", std::process::id());
    std::fs::read_dir(std::env::temp_dir())
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|f| f.starts_with(&prefix))
        .collect()
}

/// The only test of this crate's unit tests that makes `morphkit-tetgen-<pid>-*`
/// directories, so that it can check that none is left.
#[test]
fn tetgen_runs_leave_no_temporary_files_and_failures_are_clear() {
    let e = find_program(Some(OsStr::new(""))).unwrap_err().to_string();
    assert!(e.contains("no tetgen executable on the PATH"), "{e}");
    assert!(e.contains("AGPL"), "{e}");
    let d = TempDir::new().unwrap();
    let p = d.0.clone();
    assert!(p.is_dir());
    drop(d);
    assert!(!p.exists());
    let Ok(program) = find_program(None) else {
        assert!(
            std::env::var("MORPHKIT_REQUIRE_TETGEN").as_deref() != Ok("1"),
            "MORPHKIT_REQUIRE_TETGEN=1 but no tetgen on the PATH"
        );
        return eprintln!("no tetgen on the PATH; skipping the runs");
    };
    let m = crate::mesh::generate::uv_sphere(1.0, 12, 16);
    let o = InteriorOptions::default();
    let (solids, skipped) = lattice::solids(&m.positions, &m.triangles);
    let i = build_with(&program, &m.positions, &m.triangles, &solids, skipped, &o).unwrap();
    assert!(!i.points.is_empty() && !i.tets.is_empty(), "{i:?}");
    assert!(i.skipped.is_empty());
    let n = m.num_vertices() as u32;
    let pos = |v: u32| {
        if v < n {
            m.positions[v as usize]
        } else {
            i.points[(v - n) as usize]
        }
    };
    // Positive tets filling the ball's polyhedron; Steiner points inside it.
    let vol: f64 = i
        .tets
        .iter()
        .map(|t| lattice::tet_volume6(pos, *t) / 6.0)
        .sum();
    assert!(i.tets.iter().all(|t| lattice::tet_volume6(pos, *t) > 0.0));
    assert!(
        (vol - solids[0].volume).abs() < 1e-9 * vol,
        "{vol} vs {}",
        solids[0].volume
    );
    assert!(i.points.iter().all(|p| norm(*p) < 1.0));
    // No surface edge is an internal spring; every spring is a tet edge.
    assert!(i.springs.windows(2).all(|w| w[0] < w[1]));
    for &[a, b] in &i.springs {
        assert!(i.tets.iter().any(|t| t.contains(&a) && t.contains(&b)));
        let surface = m.triangles.iter().any(|t| t.contains(&a) && t.contains(&b));
        assert!(!surface, "{a}-{b}");
    }
    // A self-intersecting surface: one vertex pushed through the far side.
    let mut bad = m.clone();
    let v = 40;
    bad.positions[v] = bad.positions[v].map(|x| -1.5 * x);
    let (solids, skipped) = lattice::solids(&bad.positions, &bad.triangles);
    let e = build_with(
        &program,
        &bad.positions,
        &bad.triangles,
        &solids,
        skipped,
        &o,
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.starts_with("--interior tetgen: ") && e.contains("component 0"),
        "{e}"
    );
    eprintln!("{e}");
    // An unusable program.
    let (solids, skipped) = lattice::solids(&m.positions, &m.triangles);
    let e = build_with(
        Path::new("/bin/false"),
        &m.positions,
        &m.triangles,
        &solids,
        skipped,
        &o,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("exited with status 1"), "{e}");
    assert!(leftovers().is_empty(), "{:?}", leftovers());
}

#[test]
fn max_volume_is_a_regular_tet_of_the_lattice_spacing() {
    // Edge 2: volume 8 / (6√2).
    let v = max_volume(1.0, 1.0);
    assert!((v - 8.0 / (6.0 * 2f64.sqrt())).abs() < 1e-12);
    assert!((max_volume(1.0, 2.0) - v / 8.0).abs() < 1e-12);
}
