//! Synthesis recipes on generated meshes written to disk: a good recipe runs, and bad input
//! (scribble index out of range, misspelt key, empty scribble, contradicting layers) gives a
//! clear error naming the recipe line.

use morphkit::io::write_mesh;
use morphkit::mesh::generate;
use morphkit::synth::{RecipeError, RecipeFile};
use std::path::{Path, PathBuf};

fn setup(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("morphkit-recipe-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(d.join("frames")).unwrap();
    let bar = generate::bar(4.0, 0.5, 2, 32);
    write_mesh(&d.join("bar.obj"), &bar).unwrap();
    for k in 0..4 {
        let a = (k as f64 + 1.0) * 30f64.to_radians();
        let bent = bar.with_positions(generate::bend(&bar.positions, 1.9, 0.25, a));
        write_mesh(&d.join(format!("frames/bend-{k}.obj")), &bent).unwrap();
    }
    let x = |t: usize| {
        (0..3)
            .map(|k| bar.positions[bar.triangles[t][k] as usize][0])
            .sum::<f64>()
            / 3.0
    };
    let far: Vec<usize> = (0..bar.num_triangles()).filter(|&t| x(t) > 2.3).collect();
    let near: Vec<usize> = (0..bar.num_triangles()).filter(|&t| x(t) < 1.8).collect();
    let all: Vec<usize> = (0..bar.num_triangles()).collect();
    for (n, v) in [("far", far), ("near", near), ("all", all)] {
        std::fs::write(
            d.join(format!("{n}.json")),
            serde_json::json!({ "triangles": v }).to_string(),
        )
        .unwrap();
    }
    std::fs::write(d.join("empty.json"), r#"{"triangles": []}"#).unwrap();
    std::fs::write(d.join("huge.json"), r#"{"triangles": [0, 99999]}"#).unwrap();
    d
}

const GOOD: &str = r#"target = "bar.obj"
frames = 6

[[layer]]
name = "bend"
source_frames = "frames/bend-*.obj"
scribble = "far.json"
mode = "blend"
loop = true

[[layer]]
name = "bend again, compounded"
source_frames = ["frames/bend-0.obj", "frames/bend-1.obj"]
scribble = "near.json"
mode = "compound"
offset = 2
blend_region = "geodesic"
blend_width = 0.1
"#;

fn build(dir: &Path, text: &str) -> Result<morphkit::synth::BuiltRecipe, RecipeError> {
    let p = dir.join("recipe.toml");
    std::fs::write(&p, text).unwrap();
    RecipeFile::read(&p)?.build()
}

#[test]
fn a_good_recipe_builds_and_runs() {
    let d = setup("good");
    let b = build(&d, GOOD).unwrap();
    assert_eq!(b.layer_names, ["bend", "bend again, compounded"]);
    assert_eq!(b.synthesizer.num_frames(), 6);
    for f in b.synthesizer.frames() {
        assert!(f.unwrap().positions.iter().flatten().all(|c| c.is_finite()));
    }
    assert!(b.inputs.iter().any(|p| p.ends_with("far.json")));
    // The geodesic layer: exact 1 deep inside the scribble, 0 far outside, a band between.
    let w = &b.synthesizer.layer_info(1).weights.values;
    assert!(w.contains(&1.0) && w.contains(&0.0));
    assert!(w.iter().any(|&v| v > 0.0 && v < 1.0));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn bad_input_names_the_recipe_line() {
    let d = setup("bad");
    let path = d.join("recipe.toml");
    let check = |text: String, line: usize, key: &str, says: &str| {
        let e = build(&d, &text).unwrap_err();
        let msg = e.to_string();
        assert_eq!(e.line, line, "{msg}");
        assert_eq!(e.key, key, "{msg}");
        assert!(
            msg.starts_with(&format!("{}:{line}: {key}: ", path.display())),
            "{msg}"
        );
        assert!(msg.contains(says), "{msg}");
        assert!(!msg.contains('\n'), "one line: {msg}");
    };
    check(
        GOOD.replacen("far.json", "huge.json", 1),
        7,
        "scribble",
        "triangle 99999 is out of range",
    );
    check(
        GOOD.replace("offset = 2", "ofset = 2"),
        16,
        "ofset",
        "unknown field",
    );
    check(
        GOOD.replacen("near.json", "empty.json", 1),
        14,
        "scribble",
        "it is empty",
    );
    // A later blend over the whole bar erases the first layer: contradiction, at its mode.
    let contra = GOOD
        .replace("near.json", "all.json")
        .replace("mode = \"compound\"\noffset = 2", "mode = \"blend\"");
    check(contra, 15, "mode", "layer 1 (blend) fully covers");
    check(
        GOOD.replace("mode = \"compound\"", "mode = \"multiply\""),
        15,
        "mode",
        "unknown variant",
    );
    check(
        GOOD.replace("\"frames/bend-*.obj\"", "\"nothing-*.obj\""),
        6,
        "source_frames",
        "no files match",
    );
    check(
        GOOD.replace(
            "scribble = \"near.json\"",
            "scribble = \"near.json\"\nmarkers = \"m.json\"",
        ),
        15,
        "markers",
        "animates the target itself",
    );
    check(
        GOOD.replace("blend_width = 0.1", "blend_width = -1.0"),
        18,
        "blend_width",
        "must be positive",
    );
    let _ = std::fs::remove_dir_all(&d);
}
