"""Run inside Blender: import an FBX with Blender's own importer and dump what Blender sees.

    blender --background --factory-startup --python tests/blender/import_fbx.py -- IN.fbx OUT.json [NUMPY_DIR]

NUMPY_DIR, when given, is where numpy is found if Blender's Python lacks it (the FBX importer needs it).
Writes bone names and parents, the imported action's frame range, the scene's frame rate (the
importer sets it from the file), every bone head's world position in the rest pose and per frame
(Blender's Z-up metres), and the objects' names and types.
"""

import json
import sys

fbx_path, out_path, *numpy_dir = sys.argv[sys.argv.index("--") + 1:]
try:
    import numpy  # noqa: F401
except ImportError:
    sys.path.extend(numpy_dir)

import bpy  # noqa: E402

scene = bpy.context.scene
for obj in list(scene.objects):  # the factory scene's cube, camera and light
    bpy.data.objects.remove(obj, do_unlink=True)
bpy.ops.import_scene.fbx(filepath=fbx_path)
armature = next(obj for obj in scene.objects if obj.type == "ARMATURE")
first, last = (int(round(f)) for f in armature.animation_data.action.frame_range)
frames = []
for frame in range(first, last + 1):
    scene.frame_set(frame)
    frames.append([list(armature.matrix_world @ bone.head) for bone in armature.pose.bones])
bones = armature.data.bones
with open(out_path, "w") as handle:
    json.dump({"bones": [bone.name for bone in armature.pose.bones],
               "parents": [bone.parent.name if bone.parent else None for bone in armature.pose.bones],
               "rest_heads": [list(armature.matrix_world @ bones[bone.name].head_local) for bone in armature.pose.bones],
               "frame_start": first, "frame_end": last, "fps": scene.render.fps / scene.render.fps_base,
               "heads": frames, "objects": [[obj.name, obj.type] for obj in scene.objects]}, handle)
