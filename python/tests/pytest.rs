//! Runs the Python test suite (`python/tests/test_*.py`, pytest) against the extension module
//! that this `cargo test` built (`target/<profile>/deps/lib_morphkit.so`), in a virtual environment
//! under `target/python-venv` that it creates itself (`tests/requirements.txt`: numpy, pytest,
//! Dask; and libigl for cross-checks, all from PyPI).
//!
//! Without a usable `python3` (or `MORPHKIT_PYTHON`) or without network for the first set-up
//! the suite is skipped with a message, unless `MORPHKIT_REQUIRE_PYTHON` is set (CI sets it),
//! when that is a failure. `MORPHKIT_DATA` is passed through; the `morphkit` binary of the same
//! build is passed as `MORPHKIT_BIN` for the tests that compare with the CLI.

use std::path::{Path, PathBuf};
use std::process::Command;

fn required() -> bool {
    std::env::var_os("MORPHKIT_REQUIRE_PYTHON").is_some_and(|v| !v.is_empty() && v != "0")
}

fn skip_or_fail(why: &str) {
    if required() {
        panic!("Python tests are required (MORPHKIT_REQUIRE_PYTHON) but {why}");
    }
    eprintln!("SKIPPED the Python tests: {why} (set MORPHKIT_REQUIRE_PYTHON=1 to make this fail)");
}

/// `target/<profile>`, from this test binary's path `target/<profile>/deps/pytest-HASH`.
fn profile_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("test binary path");
    exe.parent()
        .and_then(Path::parent)
        .expect("target/<profile>/deps")
        .to_path_buf()
}

fn run(cmd: &mut Command) -> Result<(), String> {
    let shown = format!("{cmd:?}");
    match cmd.status() {
        Ok(s) if s.success() => Ok(()),
        Ok(s) => Err(format!("`{shown}` exited with {s}")),
        Err(e) => Err(format!("`{shown}` could not start: {e}")),
    }
}

/// Creates the virtual environment with `tests/requirements.txt` (numpy, pytest, Dask), and
/// libigl when it installs; a marker file holding the requirements records a complete set-up,
/// so a changed list installs again.
fn venv(target: &Path, src: &Path) -> Result<PathBuf, String> {
    let dir = target.join("python-venv");
    let python = dir.join("bin").join("python");
    let done = dir.join(".morphkit-ready");
    let reqs = src.join("tests").join("requirements.txt");
    let wanted = std::fs::read_to_string(&reqs).map_err(|e| format!("{}: {e}", reqs.display()))?;
    if python.exists() && std::fs::read_to_string(&done).is_ok_and(|d| d == wanted) {
        return Ok(python);
    }
    if !python.exists() {
        let host = std::env::var("MORPHKIT_PYTHON").unwrap_or_else(|_| "python3".into());
        run(Command::new(&host).args(["-m", "venv"]).arg(&dir))?;
    }
    let pip = |args: &[&str]| {
        let mut c = Command::new(&python);
        c.args(["-m", "pip", "install", "-q", "--disable-pip-version-check"])
            .args(args);
        run(&mut c)
    };
    pip(&["-r", reqs.to_str().ok_or("non-UTF-8 path")?])?;
    // libigl is for numerical cross-checks only; its absence skips those tests.
    if let Err(e) = pip(&["libigl"]) {
        eprintln!("libigl not installed ({e}); its cross-checks will be skipped");
    }
    std::fs::write(&done, wanted).map_err(|e| e.to_string())?;
    Ok(python)
}

/// Lays out the package (`morphkit/*.py` + the built library as `_morphkit.abi3.so`).
fn stage(profile: &Path, src: &Path) -> Result<PathBuf, String> {
    let name = if cfg!(target_os = "macos") {
        "lib_morphkit.dylib"
    } else {
        "lib_morphkit.so"
    };
    // Built beside this test (deps/) as the lib it depends on; `cargo build` uplifts a copy.
    let lib = [profile.join("deps").join(name), profile.join(name)]
        .into_iter()
        .filter(|p| p.exists())
        .max_by_key(|p| std::fs::metadata(p).and_then(|m| m.modified()).ok())
        .ok_or_else(|| format!("{name} was not built under {}", profile.display()))?;
    let root = profile.join("python-test");
    let pkg = root.join("morphkit");
    std::fs::create_dir_all(&pkg).map_err(|e| e.to_string())?;
    for entry in std::fs::read_dir(src.join("morphkit")).map_err(|e| e.to_string())? {
        let p = entry.map_err(|e| e.to_string())?.path();
        if p.is_file() {
            std::fs::copy(&p, pkg.join(p.file_name().unwrap())).map_err(|e| e.to_string())?;
        }
    }
    std::fs::copy(&lib, pkg.join("_morphkit.abi3.so")).map_err(|e| e.to_string())?;
    Ok(root)
}

#[test]
fn python_suite() {
    let src = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let profile = profile_dir();
    let target = profile.parent().expect("target dir").to_path_buf();
    let python = match venv(&target, &src) {
        Ok(p) => p,
        Err(e) => return skip_or_fail(&format!("the virtual environment failed: {e}")),
    };
    let root = match stage(&profile, &src) {
        Ok(r) => r,
        Err(e) => return skip_or_fail(&e),
    };
    let mut cmd = Command::new(&python);
    cmd.args(["-m", "pytest", "-q", "-p", "no:cacheprovider"])
        .arg(src.join("tests"))
        .current_dir(&root) // not python/, whose morphkit/ lacks the built library
        .env("PYTHONPATH", &root)
        .env("PYTHONDONTWRITEBYTECODE", "1");
    let bin = profile.join("morphkit");
    if bin.exists() {
        cmd.env("MORPHKIT_BIN", &bin);
    } else if required() {
        panic!(
            "{} was not built: run the whole workspace's tests",
            bin.display()
        );
    }
    if let Err(e) = run(&mut cmd) {
        panic!("the Python test suite failed: {e}");
    }
}
