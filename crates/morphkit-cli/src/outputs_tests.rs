//! Tests of the parent module (kept apart so that the module itself stays one concept).
use super::*;

fn tmp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("morphkit-plan-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn outputs_must_be_distinct_writable_and_of_the_right_format() {
    let d = tmp_dir("check");
    let input = d.join("in.obj");
    std::fs::write(&input, "v 0 0 0\n").unwrap();
    let ins = [input.clone()];
    let e = |p: Plan| p.check().unwrap_err().to_string();
    let x = d.join("x.json");
    let s = e(Plan::new(&ins).output("--out", &x, Kind::Json).output(
        "--report",
        &d.join(".").join("x.json"),
        Kind::Json,
    ));
    assert!(s.contains("--out and --report are the same file"), "{s}");
    let s = e(Plan::new(&ins).output("--out", &input, Kind::Mesh));
    assert!(s.contains("refusing to overwrite"), "{s}");
    let s = e(Plan::new(&ins).output("--out", &d.join("t.ply"), Kind::Animation));
    assert!(s.contains("--out") && s.contains("holds one mesh"), "{s}");
    let s = e(Plan::new(&ins).output("--out", &d.join("nodir/x.obj"), Kind::Mesh));
    assert!(s.contains("does not exist"), "{s}");
    let s = e(Plan::new(&ins)
        .output("--out", &d.join("frames"), Kind::Animation)
        .output("--report", &d.join("frames/frame_0000.obj"), Kind::Json));
    assert!(s.contains("inside the frame directory"), "{s}");
    if Path::new("/proc/self").exists() {
        let s = e(Plan::new(&ins).output("--report", Path::new("/proc/x.json"), Kind::Json));
        assert!(s.contains("cannot write in the directory /proc"), "{s}");
    }
    assert!(Plan::new(&ins)
        .output("--out", &d.join("new/deeper/frames"), Kind::Animation)
        .output("--report", &x, Kind::Json)
        .check()
        .is_ok());
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn existing_frames_need_force() {
    let d = tmp_dir("force");
    std::fs::write(d.join("frame_0005.obj"), "old").unwrap();
    let s = Plan::new(&[])
        .output("OUT", &d, Kind::Animation)
        .check()
        .unwrap_err()
        .to_string();
    assert!(s.contains("frame_0005.obj") && s.contains("--force"), "{s}");
    assert!(Plan::new(&[])
        .force(true)
        .output("OUT", &d, Kind::Animation)
        .check()
        .is_ok());
    let _ = std::fs::remove_dir_all(&d);
}
