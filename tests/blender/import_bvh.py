"""Run inside Blender: import a BVH with Blender's own importer and dump what Blender sees.

    blender --background --factory-startup --python tests/blender/import_bvh.py -- IN.bvh OUT.json

Writes bone names, the imported action's frame range, the scene's frame rate, and every bone
head's world position per frame (Blender's Z-up metres).
"""

import builtins
import json
import sys

import bpy

# Debian's Blender 3.4 runs on Python 3.11, where open(..., "rU") is gone; its BVH importer still asks
# for it. Map the mode back to "r" (what "rU" meant) so the distribution's own importer runs.
_open = builtins.open
builtins.open = lambda file, mode="r", *args, **kwargs: _open(file, mode.replace("U", ""), *args, **kwargs)

bvh_path, out_path = sys.argv[sys.argv.index("--") + 1:][:2]
bpy.ops.import_anim.bvh(filepath=bvh_path, global_scale=1.0, frame_start=1, use_fps_scale=False,
                        update_scene_fps=True, update_scene_duration=True, rotate_mode="NATIVE",
                        axis_forward="-Z", axis_up="Y")
armature = next(obj for obj in bpy.context.scene.objects if obj.type == "ARMATURE")
scene = bpy.context.scene
first, last = (int(round(f)) for f in armature.animation_data.action.frame_range)  # the importer only extends the scene
frames = []
for frame in range(first, last + 1):
    scene.frame_set(frame)
    frames.append([list(armature.matrix_world @ bone.head) for bone in armature.pose.bones])
with open(out_path, "w") as handle:
    json.dump({"bones": [bone.name for bone in armature.pose.bones], "frame_start": first, "frame_end": last,
               "fps": scene.render.fps / scene.render.fps_base, "heads": frames}, handle)
