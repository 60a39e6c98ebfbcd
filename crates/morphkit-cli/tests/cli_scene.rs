//! `morphkit blend --scene` (issue 12), run as the built binary: a moving ball pushes into a
//! bending tube; the GLB holds the ball with its animation, the report the collision rounds.

mod common;
use common::*;

#[path = "../../morphkit/examples/bend_around_cylinder.rs"]
#[allow(dead_code)]
mod example_meshes;

use morphkit::mesh::generate;

/// Writes the rig; returns the centre of the bent tube's free end.
fn write_rig(d: &std::path::Path) -> [f64; 3] {
    let tube = generate::tube(0.5, 4.0, 12, 16, false);
    morphkit::io::write_mesh(&d.join("rest.obj"), &tube).unwrap();
    let bent = tube.with_positions(generate::bend(&tube.positions, 2.0, 2.0, 1.5));
    morphkit::io::write_mesh(&d.join("bent.obj"), &bent).unwrap();
    let end = &bent.positions[bent.positions.len() - 12..];
    [0, 1, 2].map(|a| end.iter().map(|p| p[a]).sum::<f64>() / 12.0)
}

const SCENE: &str = r#"
base = "rest.obj"
targets = ["bent.obj"]
[weights]
frames = 4
[[obstacle]]
name = "ball"
shape = "sphere"
radius = 0.6
[[obstacle.key]]
frame = 0
translation = [0.0, 0.0, 5.0]
[[obstacle.key]]
frame = 3
translation = END
"#;

#[test]
fn a_scene_writes_the_obstacle_into_the_glb_and_collisions_into_the_report() {
    let d = tmp_dir("scene-glb");
    let end = write_rig(&d);
    let scene = SCENE.replace("END", &format!("{end:?}"));
    std::fs::write(d.join("scene.toml"), scene).unwrap();
    let (glb, report) = (d.join("out.glb"), d.join("r.json"));
    ok(&[
        "blend",
        "--scene",
        s(&d.join("scene.toml")),
        "--out",
        s(&glb),
        "--report",
        s(&report),
    ]);
    // The GLB's JSON chunk: 12-byte header, chunk length, chunk type, JSON.
    let bytes = std::fs::read(&glb).unwrap();
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let doc: serde_json::Value = serde_json::from_slice(&bytes[20..20 + len]).unwrap();
    assert_eq!(doc["meshes"].as_array().unwrap().len(), 2);
    let nodes = doc["nodes"].as_array().unwrap();
    let ball = nodes.iter().position(|n| n["name"] == "ball").unwrap();
    assert_eq!(doc["scenes"][0]["nodes"], serde_json::json!([0, ball]));
    let paths: Vec<_> = doc["animations"][0]["channels"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["target"]["node"] == ball)
        .map(|c| c["target"]["path"].as_str().unwrap().to_string())
        .collect();
    assert_eq!(paths, ["translation", "rotation"]);
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let frames = r["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 4);
    assert_eq!(frames[0]["collision"]["contacts"], 0);
    let last = &frames[3]["collision"];
    assert!(last["contacts"].as_u64().unwrap() > 0, "{last}");
    assert_eq!(last["resolved"], true);
    assert!(last["detection_seconds"].is_number() && last["solve_seconds"].is_number());
}

#[test]
fn scene_errors_name_the_line_and_key_and_scene_excludes_base() {
    let d = tmp_dir("scene-bad");
    write_rig(&d);
    let bad = SCENE
        .replace("END", "[0, 0, 0]")
        .replace("shape = \"sphere\"", "shape = \"torus\"");
    std::fs::write(d.join("scene.toml"), bad).unwrap();
    let e = fails(&[
        "blend",
        "--scene",
        s(&d.join("scene.toml")),
        "--out",
        s(&d.join("o.glb")),
    ]);
    assert!(
        e.contains("scene.toml:8: obstacle[0].shape: unknown primitive 'torus'"),
        "{e}"
    );
    let e = fails(&[
        "blend",
        "--scene",
        s(&d.join("scene.toml")),
        "--base",
        s(&d.join("rest.obj")),
        "--out",
        s(&d.join("o.glb")),
    ]);
    assert!(e.contains("cannot be used with"), "{e}");
}

#[test]
fn scene_outputs_are_planned_together_before_any_work() {
    let d = tmp_dir("scene-plan");
    let end = write_rig(&d);
    std::fs::write(
        d.join("scene.toml"),
        SCENE.replace("END", &format!("{end:?}")),
    )
    .unwrap();
    let scene = d.join("scene.toml");
    // The same path twice, and an output in a missing directory: refused, nothing written.
    let e = fails(&[
        "blend",
        "--scene",
        s(&scene),
        "--out",
        s(&d.join("x.glb")),
        "--report",
        s(&d.join("x.glb")),
    ]);
    assert!(e.contains("x.glb"), "{e}");
    let e = fails(&[
        "blend",
        "--scene",
        s(&scene),
        "--out",
        s(&d.join("out.glb")),
        "--report",
        s(&d.join("nodir/r.json")),
    ]);
    assert!(e.contains("nodir"), "{e}");
    assert!(!d.join("x.glb").exists() && !d.join("out.glb").exists());
}

/// Issue 55: the README's scene example read its meshes from the real-mesh collection beside
/// the repository, so on a fresh clone it failed with "cannot read the file". The README's own
/// command, run from a copy of the examples folder with nothing beside it, now blends the
/// example's generated tube around the bar; and the committed meshes are what the documented
/// generator (`cargo run --example bend_around_cylinder`) writes.
#[test]
fn the_readme_scene_example_runs_from_a_copy_of_the_examples_folder() {
    let repo = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let root = tmp_dir("readme-scene");
    let ex = root.join("examples/bend-around-cylinder");
    std::fs::create_dir_all(&ex).unwrap();
    for e in std::fs::read_dir(repo.join("examples/bend-around-cylinder")).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), ex.join(e.file_name())).unwrap();
    }
    let readme = std::fs::read_to_string(repo.join("README.md")).unwrap();
    let line = readme
        .lines()
        .find(|l| l.starts_with("morphkit blend --scene examples/bend-around-cylinder/"))
        .expect("the README shows the scene example");
    let args: Vec<&str> = line.split_whitespace().skip(1).collect();
    assert!(args.contains(&"--report"), "{line}");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_morphkit"))
        .args(&args)
        .current_dir(&root)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{line}: {err}");
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(root.join("wrap.json")).unwrap()).unwrap();
    let frames = report["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 24);
    let touched = frames
        .iter()
        .filter(|f| f["collision"]["contacts"].as_u64().unwrap() > 0)
        .count();
    assert!(touched >= 3, "the bar is hit in {touched} frames");
    assert!(frames
        .iter()
        .all(|f| f["collision"]["resolved"].as_bool() == Some(true)));
    assert!(root.join("wrap.glb").exists());
    // The committed meshes are the generator's, byte for byte.
    let (rest, bent) = example_meshes::meshes();
    for (name, mesh) in [("tube-rest.obj", rest), ("tube-bend.obj", bent)] {
        let fresh = root.join(name);
        morphkit::io::write_mesh(&fresh, &mesh).unwrap();
        assert_eq!(
            std::fs::read(&fresh).unwrap(),
            std::fs::read(ex.join(name)).unwrap(),
            "{name}: run the generator again (see scene.toml)"
        );
    }
}
