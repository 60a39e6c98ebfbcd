"""morphkit for Blender: physical shape keys, animation and rig transfer, and synthesis tools
on Blender's own objects. A thin client of the `morphkit` Python module (no algorithm here).

The module is found, in order: the `vendor/` folder inside the add-on (where
`blender/build_addon.py` puts it); the folder in the add-on preferences; the
`MORPHKIT_PYTHONPATH` environment variable; wherever it is already importable. The copy the
add-on ships wins over any other (issue 55): a `morphkit` installed in the Python that runs
Blender (a virtual environment's, the user's site-packages) or imported earlier by another
script may be another version, whose answers the add-on was not built against, so it is
dropped from `sys.modules` and the vendored folder is put first on `sys.path`.
"""

bl_info = {
    "name": "morphkit",
    "author": "morphkit developers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > morphkit",
    "description": "Physical blendshapes, deformation and rig transfer, animation synthesis",
    "category": "Animation",
}

import os
import sys

import bpy


def _vendor_dir():
    return os.path.join(os.path.dirname(os.path.abspath(__file__)), "vendor")


def _loaded_from(folder):
    """Whether the imported `morphkit` (if any) is the package inside `folder`."""
    module = sys.modules.get("morphkit")
    where = getattr(module, "__file__", None)
    if not where:
        return False
    inside = os.path.normcase(os.path.realpath(os.path.join(folder, "morphkit")))
    return os.path.normcase(os.path.realpath(os.path.dirname(where))) == inside


def _forget_morphkit():
    """Drops an imported `morphkit` and its submodules, so that the next import finds the
    first copy on `sys.path`."""
    for name in [n for n in sys.modules if n == "morphkit" or n.startswith("morphkit.")]:
        del sys.modules[name]


def _import_from(folder):
    """Imports the `morphkit` package inside `folder`, whatever else is installed or imported;
    False (and `sys.path` as before) when it does not import."""
    if _loaded_from(folder):
        return True
    _forget_morphkit()
    if folder in sys.path:
        sys.path.remove(folder)
    sys.path.insert(0, folder)
    try:
        import morphkit  # noqa: F401

        if _loaded_from(folder):
            return True
    except ImportError:
        pass
    sys.path.remove(folder)
    _forget_morphkit()
    return False


def _find_module():
    candidates = [_vendor_dir()]
    addon = bpy.context.preferences.addons.get(__package__)
    if addon is not None and getattr(addon.preferences, "module_path", ""):
        candidates.append(bpy.path.abspath(addon.preferences.module_path))
    if os.environ.get("MORPHKIT_PYTHONPATH"):
        candidates.extend(os.environ["MORPHKIT_PYTHONPATH"].split(os.pathsep))
    for c in candidates:
        if os.path.isdir(os.path.join(c, "morphkit")) and _import_from(c):
            return True
    try:
        import morphkit  # noqa: F401

        return True
    except ImportError:
        return False


class MorphkitPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    module_path: bpy.props.StringProperty(
        name="morphkit module folder",
        description="Folder holding the morphkit Python package (if not installed)",
        subtype="DIR_PATH",
    )

    def draw(self, context):
        self.layout.prop(self, "module_path")


_modules = []


def register():
    bpy.utils.register_class(MorphkitPreferences)
    if not _find_module():
        print("morphkit: the morphkit Python module was not found; set its folder in the "
              "add-on preferences or MORPHKIT_PYTHONPATH")
    from . import bake_ops, physical_ui, synth_ops, transfer_ops

    _modules[:] = [physical_ui, bake_ops, transfer_ops, synth_ops]
    for m in _modules:
        m.register()


def unregister():
    for m in reversed(_modules):
        m.unregister()
    _modules.clear()
    bpy.utils.unregister_class(MorphkitPreferences)
