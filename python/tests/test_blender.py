"""The Blender add-on, headless: builds the add-on zip with this build's module inside, then
runs blender/tests/run_addon_tests.py in `blender -b` (install, every operator, numerical
checks against the module, one non-blank Workbench render per mode).

Skipped when no `blender` is on the PATH, unless MORPHKIT_REQUIRE_BLENDER is set (CI), when
that fails. Needs the real data (MORPHKIT_DATA). Renders and results.json are kept in
target/blender-test for inspection.
"""

import json
import os
import pathlib
import shutil
import subprocess
import sys

import pytest

import morphkit

ROOT = pathlib.Path(__file__).resolve().parents[2]


def addon_zip(tmp_path, *tools):
    """The add-on zip with this build's module inside; skips (or fails, in CI) without the
    programs `tools`."""
    missing = [t for t in tools if shutil.which(t) is None]
    if missing:
        if os.environ.get("MORPHKIT_REQUIRE_BLENDER"):
            pytest.fail(f"MORPHKIT_REQUIRE_BLENDER is set but {missing} are not on the PATH")
        pytest.skip(f"{missing} not on the PATH")
    sys.path.insert(0, str(ROOT / "blender"))
    import build_addon

    module_root = pathlib.Path(morphkit.__file__).resolve().parents[1]
    return build_addon.build(tmp_path / "morphkit_blender.zip", module_root)


FAKE_BPY = """
import types as _t
context = _t.SimpleNamespace(preferences=_t.SimpleNamespace(addons={}))
types = _t.SimpleNamespace(AddonPreferences=object)
props = _t.SimpleNamespace(StringProperty=lambda **k: None)
path = _t.SimpleNamespace(abspath=lambda p: p)
"""

FIND = """
import sys
if sys.argv[1] == "imported":
    import morphkit  # the installed copy, imported before the add-on
    assert "vendor" not in morphkit.__file__, morphkit.__file__
import morphkit_blender
assert morphkit_blender._find_module()
import morphkit
print(morphkit.__file__)
morphkit.transfer_defaults()  # the vendored extension works
"""


def test_addon_imports_its_vendored_module(tmp_path):
    """Issue 55: the add-on imports the module it ships even where another copy is installed
    (this environment's, on PYTHONPATH) or already imported; no Blender needed (a stand-in
    `bpy`)."""
    import zipfile

    sys.path.insert(0, str(ROOT / "blender"))
    import build_addon

    module_root = pathlib.Path(morphkit.__file__).resolve().parents[1]
    addon = build_addon.build(tmp_path / "morphkit_blender.zip", module_root)
    with zipfile.ZipFile(addon) as z:
        z.extractall(tmp_path / "addons")
    (tmp_path / "fake").mkdir()
    (tmp_path / "fake" / "bpy.py").write_text(FAKE_BPY)
    env = dict(os.environ)
    env.pop("MORPHKIT_PYTHONPATH", None)
    env["PYTHONPATH"] = os.pathsep.join(
        [str(module_root), str(tmp_path / "fake"), str(tmp_path / "addons")]
    )
    vendor = (tmp_path / "addons" / "morphkit_blender" / "vendor" / "morphkit").resolve()
    for case in ("imported", "installed"):
        r = subprocess.run(
            [sys.executable, "-c", FIND, case], capture_output=True, text=True, env=env,
            cwd=tmp_path, timeout=120,
        )
        assert r.returncode == 0, r.stdout + r.stderr
        used = pathlib.Path(r.stdout.strip().splitlines()[-1]).resolve()
        assert used.parent == vendor, (case, used)


def test_addon_headless(tmp_path, data):
    addon = addon_zip(tmp_path, "blender")
    exe = shutil.which("blender")
    data_dir = data("cragl-bending-cylinder").parent
    out = ROOT / "target" / "blender-test"
    shutil.rmtree(out, ignore_errors=True)
    env = dict(os.environ)
    # Install into a throwaway user profile, not the user's own Blender configuration.
    env["BLENDER_USER_SCRIPTS"] = str(tmp_path / "scripts")
    env["BLENDER_USER_CONFIG"] = str(tmp_path / "config")
    env.pop("PYTHONPATH", None)  # the add-on must find its vendored module by itself
    r = subprocess.run(
        [exe, "-b", "--factory-startup", "--python-exit-code", "1", "--python",
         str(ROOT / "blender" / "tests" / "run_addon_tests.py"), "--",
         str(addon), str(data_dir), str(out)],
        capture_output=True, text=True, env=env, timeout=900,
    )
    assert r.returncode == 0 and "MORPHKIT ADDON TESTS PASSED" in r.stdout, (
        r.stdout[-4000:] + r.stderr[-4000:]
    )
    results = json.loads((out / "results.json").read_text())
    assert "vendor" in results["module"]
    assert results["physical_key_error"] < 1e-6 and results["transfer_error"] < 1e-6
    # Issue 56: the baked rig's drivers play BakedRig.evaluate, also without the add-on.
    assert results["bake_shapes_added"] > 0
    assert max(results["bake_error"], results["bake_error_no_addon"]) < 1e-6
    if os.environ.get("MORPHKIT_BIN"):  # the exported scene.toml was replayed by the CLI
        assert results["scene_replay_error"] < 1e-5
    for png in ("physical", "obstacle", "transfer", "flexibility", "partitions", "pose"):
        assert (out / f"{png}.png").stat().st_size > 1000


def test_panel_screenshot(tmp_path, data):
    """The sidebar panels in a real window on a virtual display (xvfb-run), for the README."""
    addon = addon_zip(tmp_path, "blender", "xvfb-run")
    data_dir = data("cragl-bending-cylinder").parent
    out = ROOT / "target" / "blender-test" / "panel.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ)
    env.pop("PYTHONPATH", None)
    r = subprocess.run(
        [str(ROOT / "blender" / "tests" / "panel_screenshot.sh"), str(addon), str(data_dir),
         str(out)],
        capture_output=True, text=True, env=env, timeout=600,
    )
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    assert "physical blend in" in r.stdout  # the panel's operator ran in the window
    assert out.stat().st_size > 50_000  # a full window, not a blank image
