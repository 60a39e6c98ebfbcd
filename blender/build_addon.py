"""Packs the Blender add-on as a zip that Blender installs (Edit > Preferences > Add-ons >
Install), optionally with the morphkit Python module inside it (`vendor/`).

    python blender/build_addon.py --out morphkit_blender.zip --module SITE_DIR

SITE_DIR is a folder holding the `morphkit` package (for example the site-packages of the
environment where `pip install ./python` put it). Without --module the add-on finds the module
through its preferences or MORPHKIT_PYTHONPATH.
"""

import argparse
import pathlib
import zipfile

HERE = pathlib.Path(__file__).resolve().parent


def build(out, module=None):
    out = pathlib.Path(out)
    tmp = out.with_name(out.name + ".tmp")
    with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
        for p in sorted((HERE / "morphkit_blender").glob("*.py")):
            z.write(p, f"morphkit_blender/{p.name}")
        if module is not None:
            pkg = pathlib.Path(module) / "morphkit"
            if not (pkg / "__init__.py").exists():
                raise SystemExit(f"{pkg} is not the morphkit package")
            for p in sorted(pkg.iterdir()):
                if p.is_file() and p.suffix in (".py", ".so", ".pyd", ".pyi", ".typed"):
                    z.write(p, f"morphkit_blender/vendor/morphkit/{p.name}")
    tmp.replace(out)
    return out


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--module", help="folder holding the morphkit package to vendor")
    a = ap.parse_args()
    print(build(a.out, a.module))
