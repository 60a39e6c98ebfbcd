"""Screenshot of the add-on's sidebar panels in a real Blender window (for the README):

    blender/tests/panel_screenshot.sh ADDON.zip DATA_DIR OUT.png

(in a fresh user configuration, whose splash screen the script's first run turns off).

Builds the cylinder with a `bend` shape key, runs the physical blend, opens the 3D view's
sidebar on the morphkit tab and saves a screenshot of the window; then quits.
"""

import pathlib
import sys

import bpy

argv = sys.argv[sys.argv.index("--") + 1 :]
ZIP, DATA, OUT = pathlib.Path(argv[0]), pathlib.Path(argv[1]), pathlib.Path(argv[2])
if bpy.context.preferences.view.show_splash:
    # First run in this configuration: no splash next time, then start again.
    bpy.context.preferences.view.show_splash = False
    bpy.ops.wm.save_userpref()
    print("SPLASH OFF: run again")
    sys.exit(0)
bpy.ops.preferences.addon_install(filepath=str(ZIP), overwrite=True)
bpy.ops.preferences.addon_enable(module="morphkit_blender")
import morphkit  # noqa: E402
from morphkit_blender import geometry  # noqa: E402

for o in list(bpy.data.objects):
    bpy.data.objects.remove(o)
d = DATA / "cragl-bending-cylinder"
V0, F = morphkit.read(d / "cylinder-rest.obj")
V1, _ = morphkit.read(d / "cylinder-bend-4.obj")
mesh = bpy.data.meshes.new("cylinder")
mesh.from_pydata(V0.tolist(), [], F.tolist())
obj = bpy.data.objects.new("cylinder", mesh)
bpy.context.scene.collection.objects.link(obj)
obj.shape_key_add(name="Basis")
geometry.set_key_coords(obj.shape_key_add(name="bend"), V1)
obj.data.shape_keys.key_blocks["bend"].value = 0.6
bpy.context.view_layer.objects.active = obj
obj.select_set(True)


def shoot():
    win = bpy.context.window_manager.windows[0]
    area = next(a for a in win.screen.areas if a.type == "VIEW_3D")
    space = area.spaces.active
    space.show_region_ui = True
    region = next(r for r in area.regions if r.type == "WINDOW")
    with bpy.context.temp_override(window=win, area=area, region=region):
        bpy.ops.morphkit.physical_update()
        bpy.ops.view3d.view_selected()
    for r in area.regions:
        if r.type == "UI":
            r.tag_redraw()
    # Blender 3.4 cannot switch the sidebar tab from Python: show the panels in the tab that
    # is open (Item), below its Transform panel (collapsed), for the picture only.
    from morphkit_blender import physical_ui, synth_ops, transfer_ops

    for cls in (physical_ui.MORPHKIT_PT_physical, transfer_ops.MORPHKIT_PT_transfer,
                synth_ops.MORPHKIT_PT_synth):
        bpy.utils.unregister_class(cls)
        cls.bl_category = "Item"
        bpy.utils.register_class(cls)
    bpy.app.timers.register(lambda: save(win, area), first_interval=1.0)
    return None


def save(win, area):
    with bpy.context.temp_override(window=win, area=area):
        bpy.ops.screen.screenshot_area(filepath=str(OUT))
    bpy.ops.wm.quit_blender()
    return None


bpy.app.timers.register(shoot, first_interval=1.5)
