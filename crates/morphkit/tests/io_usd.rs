//! Issue 15: USD text layers. Baked animation round-trips through the own reader within
//! 1e-6 of the diagonal, output is byte-for-byte deterministic, polygons are kept, the stage
//! metadata is written, blend-shape rigs name their shapes, and (when `MORPHKIT_USD_CHECK`
//! points at `tools/usd-check/check.py` and `pxr` is installed) Pixar's USD validates both.

use morphkit::io::{self, FramesOptions, UsdOptions};
use morphkit::mesh::{generate, Polygons};
use morphkit::{ShapeSet, TriMesh};
use std::path::PathBuf;

fn tmp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("morphkit-usd-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn tube_frames(n: usize) -> ShapeSet {
    let tube = generate::tube(0.5, 4.0, 12, 16, false);
    let shapes = (0..n)
        .map(|k| {
            let a = 2.0 * k as f64 / (n - 1) as f64;
            (
                format!("f{k}"),
                generate::bend(&tube.positions, 0.0, 2.0, a),
            )
        })
        .collect();
    ShapeSet::new(tube, shapes).unwrap()
}

fn max_err(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
        .fold(0.0, f64::max)
}

#[test]
fn baked_animation_round_trips_and_is_deterministic() {
    let d = tmp_dir("anim");
    let f = tube_frames(12);
    let p = d.join("anim.usda");
    let opts = FramesOptions {
        fps: 30.0,
        usd: UsdOptions {
            name: "tube-bend".into(),
            ..UsdOptions::default()
        },
        ..FramesOptions::default()
    };
    io::write_frames(&p, &f, &opts).unwrap();
    let a = std::fs::read(&p).unwrap();
    io::write_frames(&d.join("again.usda"), &f, &opts).unwrap();
    assert_eq!(
        a,
        std::fs::read(d.join("again.usda")).unwrap(),
        "same input, same bytes"
    );
    let text = String::from_utf8(a).unwrap();
    for line in [
        "defaultPrim = \"tube_bend\"",
        "timeCodesPerSecond = 30",
        "startTimeCode = 0",
        "endTimeCode = 11",
        "upAxis = \"Y\"",
        "metersPerUnit = 1",
        "def Xform \"tube_bend\"",
        "point3f[] points.timeSamples",
        "float3[] extent.timeSamples",
        "uniform bool doubleSided = 1",
    ] {
        assert!(text.contains(line), "missing {line}");
    }
    assert!(!text.contains("NaN") && !text.contains("inf"));
    let back = io::read_usd_animation(&p).unwrap();
    assert_eq!(back.samples.len(), 12);
    assert_eq!(back.time_codes_per_second, 30.0);
    assert_eq!(back.mesh.triangles, f.base().triangles);
    let tol = 1e-6 * f.base().bbox_diagonal();
    for (k, (t, s)) in back.samples.iter().enumerate() {
        assert_eq!(*t, k as f64);
        assert!(max_err(s, f.positions(k)) < tol, "frame {k}");
    }
    let set = io::read_animation(&p, None).unwrap();
    assert_eq!(set.len(), 12);
    // One mesh: a static Mesh without time samples.
    io::write_mesh(&d.join("one.usda"), &f.mesh(3)).unwrap();
    let one = std::fs::read_to_string(d.join("one.usda")).unwrap();
    assert!(!one.contains("timeSamples"));
    assert!(
        max_err(
            &io::read_mesh(&d.join("one.usda")).unwrap().positions,
            f.positions(3)
        ) < tol
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn polygons_are_kept_and_bad_input_is_an_error() {
    let d = tmp_dir("quads");
    let quad = TriMesh::from_polygons(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ],
        Polygons {
            offsets: vec![0, 4],
            indices: vec![0, 1, 2, 3],
        },
    );
    let p = d.join("q.usda");
    io::write_mesh(&p, &quad).unwrap();
    let text = std::fs::read_to_string(&p).unwrap();
    assert!(text.contains("int[] faceVertexCounts = [4]"), "{text}");
    assert_eq!(io::read_mesh(&p).unwrap().polygons, quad.polygons);
    let bad = io::write_usd_animation(
        &d.join("bad.usda"),
        &quad,
        &[vec![[f64::NAN, 0.0, 0.0]; 4]],
        24.0,
        &UsdOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        bad.contains("bad.usda") && bad.contains("vertex 0"),
        "{bad}"
    );
    assert!(!d.join("bad.usda").exists());
    std::fs::write(d.join("trunc.usda"), &text[..text.len() / 2]).unwrap();
    let e = io::read_mesh(&d.join("trunc.usda"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("trunc.usda"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn blend_shapes_are_named_usdskel_targets() {
    let d = tmp_dir("skel");
    let f = tube_frames(3);
    let p = d.join("rig.usda");
    let names = vec!["jawOpen".to_string(), "smile L".to_string()];
    let shapes = vec![f.positions(1).to_vec(), f.positions(2).to_vec()];
    io::write_usd_blendshapes(&p, f.base(), &shapes, &names, &UsdOptions::default()).unwrap();
    let text = std::fs::read_to_string(&p).unwrap();
    assert!(text.contains("uniform token[] skel:blendShapes = [\"jawOpen\", \"smile L\"]"));
    assert!(text.contains("def BlendShape \"smile_L\""));
    assert!(text.contains(
        "rel skel:blendShapeTargets = [</morphkit/mesh/jawOpen>, </morphkit/mesh/smile_L>]"
    ));
    let e = io::write_usd_blendshapes(&p, f.base(), &shapes, &names[..1], &UsdOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("1 names for 2 blend shapes"), "{e}");
    if let Some(script) = std::env::var_os("MORPHKIT_USD_CHECK") {
        let anim = d.join("anim.usda");
        io::write_frames(&anim, &tube_frames(7), &FramesOptions::default()).unwrap();
        for (args, file) in [
            (vec!["--blendshapes", "jawOpen,smile L"], &p),
            (vec!["--frames", "7"], &anim),
        ] {
            let out = std::process::Command::new("python3")
                .arg(&script)
                .args(args)
                .arg(file)
                .output()
                .expect("run python3");
            let text = String::from_utf8_lossy(&out.stdout);
            eprintln!("{text}{}", String::from_utf8_lossy(&out.stderr));
            assert!(out.status.success(), "{text}");
            assert!(text.contains(": 0 errors"), "{text}");
        }
    } else {
        eprintln!("MORPHKIT_USD_CHECK is unset; skipping the USD validation");
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn malformed_usda_is_an_error_naming_the_file_not_a_panic() {
    let d = tmp_dir("bad");
    let cases = [
        ("nohdr.usda", "def Mesh \"m\" {}"),
        ("nomesh.usda", "#usda 1.0\ndef Xform \"x\" {}\n"),
        (
            "huge.usda",
            "#usda 1.0\ndef Mesh \"m\" {\nint[] faceVertexCounts = [1e300]\nint[] faceVertexIndices = [0, 1, 2]\npoint3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]\n}\n",
        ),
        (
            "range.usda",
            "#usda 1.0\ndef Mesh \"m\" {\nint[] faceVertexCounts = [3]\nint[] faceVertexIndices = [0, 1, 7]\npoint3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]\n}\n",
        ),
        (
            "nan.usda",
            "#usda 1.0\ndef Mesh \"m\" {\nint[] faceVertexCounts = [3]\nint[] faceVertexIndices = [0, 1, 2]\npoint3f[] points = [(0, 0, 0), (nan, 0, 0), (0, 1, 0)]\n}\n",
        ),
    ];
    for (name, text) in cases {
        let p = d.join(name);
        std::fs::write(&p, text).unwrap();
        let e = io::read_mesh(&p).unwrap_err().to_string();
        assert!(e.contains(name), "{name}: {e}");
    }
    let _ = std::fs::remove_dir_all(&d);
}
