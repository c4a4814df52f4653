"""Run inside Blender: import a glb with Blender's own glTF importer and dump what Blender sees.

    blender --background --factory-startup --python tests/blender/import_glb.py -- IN.glb FPS OUT.json [NUMPY_DIR]

NUMPY_DIR, when given, is where numpy is found if Blender's Python lacks it. Sets the scene's frame rate to FPS first (the importer turns key times into frames at the scene's
rate), then writes bone names, the imported action's frame range, the meshes' skinning, and every
bone head's world position per frame (Blender's Z-up metres).
"""

import json
import sys

import bpy

glb_path, fps, out_path, *numpy_dir = sys.argv[sys.argv.index("--") + 1:]
try:  # Blender's glTF importer needs numpy; Debian's Blender does not always bring it
    import numpy  # noqa: F401
except ImportError:
    sys.path.extend(numpy_dir)  # the folder holding the test's own numpy (same Python minor version)
scene = bpy.context.scene
scene.render.fps, scene.render.fps_base = int(round(float(fps))), int(round(float(fps))) / float(fps)
bpy.ops.import_scene.gltf(filepath=glb_path)
armature = next(obj for obj in scene.objects if obj.type == "ARMATURE")
meshes = [obj for obj in scene.objects if obj.type == "MESH"]
first, last = (int(round(f)) for f in armature.animation_data.action.frame_range)
frames = []
for frame in range(first, last + 1):
    scene.frame_set(frame)
    frames.append([list(armature.matrix_world @ bone.head) for bone in armature.pose.bones])
with open(out_path, "w") as handle:
    json.dump({"bones": [bone.name for bone in armature.pose.bones], "frame_start": first, "frame_end": last,
               "fps": scene.render.fps / scene.render.fps_base, "heads": frames,
               "meshes": [{"vertices": len(obj.data.vertices), "groups": len(obj.vertex_groups),
                           "deformed_by": [m.object.name for m in obj.modifiers if m.type == "ARMATURE" and m.object]}
                          for obj in meshes]}, handle)
