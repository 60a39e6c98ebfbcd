//! Issue 56, "rigs with baked physical correctives": `morphkit bake` adds a rig's in-between
//! and combination shapes to its glTF asset with the slider mapping in
//! `mesh.extras.morphkitBake`. Played from the written file by that mapping (the evaluation
//! docs/bake.md gives in JavaScript, written again here), the asset is the library's
//! `BakedRig::evaluate` within f32 storage, hence the physical solve at the bake's samples.

mod common;
#[path = "../../morphkit/tests/common/gltf_asset.rs"]
mod fixture;

use common::*;
use morphkit::geom::max_distance;
use morphkit::io::{GltfAsset, GltfReadOptions};
use morphkit::mesh::{ShapeSet, Weld, WELD_TOLERANCE};
use morphkit::springs::{BlendOptions, PhysicalBlend, Weights};
use serde_json::Value;

fn body() -> GltfReadOptions {
    GltfReadOptions {
        mesh: Some("Body".into()),
    }
}

/// The piecewise-linear hat of docs/bake.md: adds each shape's factor at `x` to `z`.
fn hat(weights: &[f64], targets: &[usize], x: f64, z: &mut [f64]) {
    if x == 0.0 {
        return;
    }
    let k = weights
        .iter()
        .position(|&w| x <= w)
        .unwrap_or(weights.len() - 1);
    let a = if k == 0 { 0.0 } else { weights[k - 1] };
    let s = (x - a) / (weights[k] - a);
    z[targets[k]] += s;
    if k > 0 {
        z[targets[k - 1]] += 1.0 - s;
    }
}

/// Every target's weight at slider weights `x`, from the asset's `morphkitBake` mapping.
fn target_weights(map: &Value, x: &[f64], n_targets: usize) -> Vec<f64> {
    let nums = |v: &Value| -> Vec<f64> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    let ids = |v: &Value| -> Vec<usize> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_u64().unwrap() as usize)
            .collect()
    };
    let mut z = vec![0.0; n_targets];
    for ib in map["inbetweens"].as_array().unwrap() {
        let s = ib["slider"].as_u64().unwrap() as usize;
        hat(&nums(&ib["weights"]), &ids(&ib["targets"]), x[s], &mut z);
    }
    let total: f64 = x.iter().map(|v| v.max(0.0)).sum();
    let damping = map["damping"].as_f64().unwrap();
    for c in map["combinations"].as_array().unwrap() {
        let ij = ids(&c["sliders"]);
        let (a, b) = (x[ij[0]], x[ij[1]]);
        let phi = if a > 0.0 && b > 0.0 {
            4.0 * a * b * ((a + b) / total).min(1.0).powf(damping)
        } else {
            0.0
        };
        hat(&nums(&c["levels"]), &ids(&c["targets"]), phi, &mut z);
    }
    z
}

/// The bake of `input`'s rig made by the library (3 in-betweens), with what made it.
struct Library {
    shapes: ShapeSet,
    weld: Weld,
    solver: PhysicalBlend,
    baked: morphkit::bake::BakedRig,
}

fn library_bake(input: &std::path::Path) -> Library {
    let im = GltfAsset::read(input, &body()).unwrap().morphs().clone();
    let named = std::iter::once(("base".to_string(), im.base.positions.clone()))
        .chain(im.target_names.iter().cloned().zip(im.targets.clone()))
        .collect();
    let shapes = ShapeSet::new(im.base.clone(), named).unwrap();
    let weld = Weld::of_shapes(&shapes, WELD_TOLERANCE);
    let welded = weld.shapes(&shapes).unwrap();
    let mut solver = PhysicalBlend::new(&welded, &BlendOptions::default()).unwrap();
    let opts = morphkit::bake::BakeOptions {
        inbetweens: 3,
        inbetween_tolerance: 0.0,
        ..Default::default()
    };
    let baked = morphkit::bake::bake(&mut solver, &opts, 1)
        .unwrap()
        .unweld(&weld, &welded);
    Library {
        shapes,
        weld,
        solver,
        baked,
    }
}

#[test]
fn a_baked_asset_plays_the_bake_through_its_mapping() {
    let d = tmp_dir("bake");
    let input = d.join("in.glb");
    fixture::write(&input, &fixture::standard(false, 100.0));
    let out = d.join("baked.glb");
    let report = d.join("bake.json");
    let (_, err) = run_ok(&[
        "bake",
        "--rig",
        s(&input),
        "--inbetweens",
        "3",
        "--inbetween-tolerance",
        "0",
        "--report",
        s(&report),
        "--out",
        s(&out),
    ]);
    assert!(err.contains("baked 2 targets into 6 in-betweens"), "{err}");
    fixture::assert_valid(&[&out]);
    let a = GltfAsset::read(&out, &body()).unwrap();
    let m = a.morphs();
    // Two sliders, three in-betweens each, one pair with two levels.
    assert_eq!(m.targets.len(), 2 + 6 + 2);
    for n in [
        "bend@0.25",
        "bend@0.5",
        "lift@0.75",
        "bend+lift@1",
        "bend+lift@4",
    ] {
        assert!(
            m.target_names.iter().any(|t| t == n),
            "{n} in {:?}",
            m.target_names
        );
    }
    let doc = fixture::json_of(&out);
    let mesh = doc["meshes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|x| x["name"] == "Body")
        .unwrap();
    let map = &mesh["extras"]["morphkitBake"];
    assert_eq!(map["sliders"], serde_json::json!(["bend", "lift"]));
    // The same bake in the library, on the input.
    let Library {
        shapes,
        weld,
        mut solver,
        baked,
    } = library_bake(&input);
    let diag = shapes.base().bbox_diagonal();
    for x in [
        [0.25, 0.0],
        [0.6, 0.0],
        [0.0, 1.0],
        [0.5, 0.5],
        [0.8, 0.3],
        [1.2, 0.9],
    ] {
        let z = target_weights(map, &x, m.targets.len());
        let played = m.evaluate(&z);
        let e = max_distance(&played, &baked.evaluate(&x)) / diag;
        assert!(e <= 1e-6, "{x:?}: {e}");
    }
    // At the samples, the physical solve.
    for x in [[0.5, 0.0], [0.5, 0.5], [1.0, 1.0]] {
        let z = target_weights(map, &x, m.targets.len());
        let w = Weights::Delta(x.to_vec());
        let c = w.coefficients(3).unwrap();
        let solve = weld.scatter_frame(&solver.solve(&w).unwrap().positions, &c);
        let e = max_distance(&m.evaluate(&z), &solve) / diag;
        assert!(e <= 1e-6, "{x:?}: {e}");
    }
    let r: Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    assert_eq!(r["targets_added"], 8);
    // A baked asset is not baked again (refused before any solve: the first message is the
    // error); other outputs than glTF are refused.
    let e = fails(&["bake", "--rig", s(&out), "--out", s(&d.join("again.glb"))]);
    assert!(e.contains("already baked") && !e.contains("baking"), "{e}");
    let e = fails(&["bake", "--rig", s(&input), "--out", s(&d.join("x.obj"))]);
    assert!(e.contains(".glb, .gltf") && e.contains(".usda"), "{e}");
    assert!(!d.join("again.glb").exists());
    let _ = std::fs::remove_dir_all(&d);
}

/// `--check` solves each row in full and reports the bake's and the linear blend's distances
/// from it; `--check-frames` writes what a client plays there: the library's evaluation.
#[test]
fn a_bake_checks_itself_against_the_full_solve() {
    let d = tmp_dir("bake-check");
    let input = d.join("in.glb");
    fixture::write(&input, &fixture::standard(false, 100.0));
    let rows = d.join("rows.csv");
    std::fs::write(&rows, "lift,bend\n0.5,0.5\n1,1\n0.3,0.8\n0,0.6\n").unwrap();
    let (report, played) = (d.join("r.json"), d.join("played"));
    let (_, err) = run_ok(&[
        "bake",
        "--rig",
        s(&input),
        "--inbetweens",
        "3",
        "--inbetween-tolerance",
        "0",
        "--out",
        s(&d.join("baked.glb")),
        "--check",
        s(&rows),
        "--check-frames",
        s(&played),
        "--report",
        s(&report),
    ]);
    assert!(err.contains("checked 4 states"), "{err}");
    let r: Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    let check = r["check"].as_array().unwrap();
    assert_eq!(check.len(), 4);
    // The header names the sliders in another order than the mesh (bend, lift).
    assert_eq!(check[2]["weights"], serde_json::json!([0.8, 0.3]));
    let Library { shapes, baked, .. } = library_bake(&input);
    let frames = morphkit::io::read_animation(&played, None).unwrap();
    assert_eq!(frames.len(), 4);
    let diag = shapes.base().bbox_diagonal();
    for (k, c) in check.iter().enumerate() {
        let (b, l) = (
            c["bake_error"].as_f64().unwrap(),
            c["linear_error"].as_f64().unwrap(),
        );
        assert!(b.is_finite() && l > 0.0 && c["converged"] == true, "{c}");
        let w: Vec<f64> = serde_json::from_value(c["weights"].clone()).unwrap();
        let e = max_distance(frames.positions(k), &baked.evaluate(&w)) / diag;
        assert!(
            e <= 1e-6,
            "row {k}: the written frame is {e} from the evaluation"
        );
    }
    // At the pair's samples the bake is the solve itself; elsewhere it is closer than linear.
    for c in &check[..2] {
        assert!(c["bake_error"].as_f64().unwrap() <= 1e-9, "{c}");
    }
    for c in &check[2..] {
        assert!(
            c["bake_error"].as_f64().unwrap() < c["linear_error"].as_f64().unwrap(),
            "{c}"
        );
    }
    // --check-frames needs --check; a row naming no slider is refused before any solve.
    let e = fails(&[
        "bake",
        "--rig",
        s(&input),
        "--out",
        s(&d.join("x.glb")),
        "--check-frames",
        s(&d.join("p2")),
    ]);
    assert!(e.contains("--check"), "{e}");
    std::fs::write(&rows, "chin\n0.5\n").unwrap();
    let e = fails(&[
        "bake",
        "--rig",
        s(&input),
        "--out",
        s(&d.join("x.glb")),
        "--check",
        s(&rows),
    ]);
    assert!(e.contains("chin") && !e.contains("baking"), "{e}");
    assert!(!d.join("x.glb").exists());
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_usd_bake_plays_the_bake_through_usdskel() {
    let d = tmp_dir("bake-usd");
    let input = d.join("in.glb");
    fixture::write(&input, &fixture::standard(false, 100.0));
    let out = d.join("baked.usda");
    ok(&[
        "bake",
        "--rig",
        s(&input),
        "--inbetweens",
        "3",
        "--inbetween-tolerance",
        "0",
        "--out",
        s(&out),
    ]);
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(
        text.contains("skel:blendShapes = [\"bend\", \"lift\", \"bend+lift\"]"),
        "{text}"
    );
    assert!(text.contains("inbetweens:w0_25") && text.contains("weight = 0.25"));
    let Some(check) = std::env::var_os("MORPHKIT_USD_CHECK") else {
        eprintln!("MORPHKIT_USD_CHECK is unset; skipping the usd-core checks");
        return;
    };
    let r = std::process::Command::new("python3")
        .arg(&check)
        .args(["--blendshapes", "bend,lift,bend+lift"])
        .arg(&out)
        .output()
        .unwrap();
    let t = String::from_utf8_lossy(&r.stdout);
    assert!(r.status.success() && t.contains(": 0 errors"), "{t}");
    // UsdSkel's own evaluation (in-betweens interpolated by Pixar's code) against the
    // library's bake: sliders at their weights, the combination at φ / 4.
    let baked = library_bake(&input).baked;
    let c = &baked.combinations[0];
    let cases: Vec<Value> = [[0.3, 0.0], [0.0, 0.8], [0.5, 0.5], [0.8, 0.3], [1.0, 1.0]]
        .iter()
        .map(|x| {
            serde_json::json!({
                "weights": {"bend": x[0], "lift": x[1], "bend+lift": baked.combination_weight(c, x) / 4.0},
                "points": baked.evaluate(x),
            })
        })
        .collect();
    let json = d.join("cases.json");
    std::fs::write(&json, serde_json::to_string(&cases).unwrap()).unwrap();
    let eval = std::path::Path::new(&check).with_file_name("bake_eval.py");
    let r = std::process::Command::new("python3")
        .arg(eval)
        .arg(&out)
        .arg(&json)
        .output()
        .unwrap();
    let t = String::from_utf8_lossy(&r.stdout);
    assert!(
        r.status.success(),
        "{t}{}",
        String::from_utf8_lossy(&r.stderr)
    );
    let worst: f64 = t
        .lines()
        .find_map(|l| l.strip_prefix("max "))
        .and_then(|x| x.trim().parse().ok())
        .unwrap_or_else(|| panic!("no result: {t}"));
    // f32 storage of points and offsets.
    assert!(worst <= 1e-6, "{t}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_bake_adds_in_betweens_where_the_tolerance_needs_them() {
    let d = tmp_dir("bake-refine");
    let input = d.join("in.glb");
    fixture::write(&input, &fixture::standard(false, 100.0));
    let rows = d.join("rows.csv");
    std::fs::write(
        &rows,
        "lift,bend\n0.1,0\n0.3,0\n0.45,0\n0.6,0\n0.85,0\n0,0.1\n0,0.3\n0,0.45\n0,0.6\n0,0.85\n",
    )
    .unwrap();
    let bake = |tolerance: &str, name: &str| -> Value {
        let report = d.join(format!("{name}.json"));
        let (_, err) = run_ok(&[
            "bake",
            "--rig",
            s(&input),
            "--inbetweens",
            "3",
            "--inbetween-tolerance",
            tolerance,
            "--out",
            s(&d.join(format!("{name}.glb"))),
            "--check",
            s(&rows),
            "--report",
            s(&report),
        ]);
        assert!(err.contains("where the tolerance needed them"), "{err}");
        serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap()
    };
    let (regular, refined) = (bake("0", "regular"), bake("1e-3", "refined"));
    let count = |r: &Value| -> usize {
        r["inbetweens"]
            .as_array()
            .unwrap()
            .iter()
            .map(|t| t.as_array().unwrap().len())
            .sum()
    };
    assert_eq!(count(&regular), 8, "{}", regular["inbetweens"]);
    assert!(count(&refined) > 8, "{}", refined["inbetweens"]);
    assert!(refined["solves"].as_u64() > regular["solves"].as_u64());
    let worst = |r: &Value| {
        r["check"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c["bake_error"].as_f64().unwrap())
            .fold(0.0, f64::max)
    };
    assert!(
        worst(&refined) < worst(&regular),
        "{} against {}",
        worst(&refined),
        worst(&regular)
    );
    let e = fails(&[
        "bake",
        "--rig",
        s(&input),
        "--inbetween-tolerance",
        "-1",
        "--out",
        s(&d.join("x.glb")),
    ]);
    assert!(e.contains("--inbetween-tolerance"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}
