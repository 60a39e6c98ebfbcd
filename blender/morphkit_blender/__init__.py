"""morphkit for Blender: physical shape keys, animation and rig transfer, and synthesis tools
on Blender's own objects. A thin client of the `morphkit` Python module (no algorithm here).

The module is found, in order: already importable; the folder in the add-on preferences; the
`MORPHKIT_PYTHONPATH` environment variable; a `vendor/` folder inside the add-on (where
`blender/build_addon.py` puts it).
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


def _find_module():
    try:
        import morphkit  # noqa: F401

        return True
    except ImportError:
        pass
    candidates = []
    addon = bpy.context.preferences.addons.get(__package__)
    if addon is not None and getattr(addon.preferences, "module_path", ""):
        candidates.append(bpy.path.abspath(addon.preferences.module_path))
    if os.environ.get("MORPHKIT_PYTHONPATH"):
        candidates.extend(os.environ["MORPHKIT_PYTHONPATH"].split(os.pathsep))
    candidates.append(os.path.join(os.path.dirname(__file__), "vendor"))
    for c in candidates:
        if os.path.isdir(os.path.join(c, "morphkit")) and c not in sys.path:
            sys.path.insert(0, c)
            try:
                import morphkit  # noqa: F401

                return True
            except ImportError:
                sys.path.remove(c)
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
    from . import physical_ui, synth_ops, transfer_ops

    _modules[:] = [physical_ui, transfer_ops, synth_ops]
    for m in _modules:
        m.register()


def unregister():
    for m in reversed(_modules):
        m.unregister()
    _modules.clear()
    bpy.utils.unregister_class(MorphkitPreferences)
