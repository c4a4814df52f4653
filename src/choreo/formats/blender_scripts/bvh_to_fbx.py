"""Run inside Blender: turn one of choreo's BVH files into an FBX for game engines.

    blender --background --factory-startup --python bvh_to_fbx.py -- IN.bvh OUT.fbx FRAMES [NUMPY_DIR]
    python bvh_to_fbx.py -- IN.bvh OUT.fbx FRAMES [NUMPY_DIR]        (a Python with the bpy module)

Imports the BVH with Blender's own importer (Y up, +Z forward, metres, as choreo writes it), keeps
only the armature, moves the dance to frames 0..FRAMES-1 (so its first key is at time 0, as in
choreo's other formats), and exports it with its animation baked at every frame (no key reduction) using
Blender's FBX defaults for Unity and Unreal: -Z forward, Y up, real size (apply_unit_scale: the file
is in centimetres, as Mixamo's own FBX files are, and engines read it at the right size).
NUMPY_DIR is where numpy is found when Blender's Python lacks it (its FBX exporter needs numpy).
The FBX exporter writes each bone's static (non-animated) transform from the pose at the current
frame, and importers take that as the rest pose. So the script keys the rest pose (every rotation
zero, the root standing on the floor) one frame after the dance and exports from there: an engine
then sees the rig's own rest pose (the T-pose for Mixamo's rig), not the dance's first frame.
Prints nothing on success beyond Blender's own log; any failure exits non-zero with the reason last.
"""

import builtins
import sys

args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
bvh_path, fbx_path, frames, *numpy_dir = args
try:  # Debian's Blender has no numpy of its own; the FBX exporter needs it
    import numpy  # noqa: F401
except ImportError:
    sys.path.extend(numpy_dir)

import bpy  # noqa: E402

# Debian's Blender 3.4 runs on Python 3.11, where open(..., "rU") is gone but its BVH importer still
# asks for it: map that mode back to "r" (what "rU" meant) while importing.
_open = builtins.open


def _open_without_u(file, mode="r", *rest, **kwargs):
    return _open(file, mode.replace("U", "") if isinstance(mode, str) else mode, *rest, **kwargs)


def fcurves(action) -> list:
    """The action's curves: Blender < 5 lists them on the action, 4.4+ in layered strips' channel bags."""
    if hasattr(action, "fcurves"):
        return list(action.fcurves)
    return [curve for layer in action.layers for strip in layer.strips for bag in strip.channelbags
            for curve in bag.fcurves]


def shift_keys(action, frames: float) -> None:
    """Move every key of ``action`` by ``frames``."""
    for curve in fcurves(action):
        for key in curve.keyframe_points:
            key.co.x += frames
            key.handle_left.x += frames
            key.handle_right.x += frames
        curve.update()


def key_rest_pose(armature, frame: int) -> None:
    """Key every bone at rest at ``frame``, the root moved so that the lowest joint or tip touches the floor."""
    from mathutils import Vector

    world = armature.matrix_world
    bones = armature.data.bones
    lowest = min(min((world @ bone.head_local).z, (world @ bone.tail_local).z) for bone in bones)
    for pose_bone in armature.pose.bones:
        pose_bone.rotation_quaternion = (1.0, 0.0, 0.0, 0.0)
        pose_bone.rotation_euler = (0.0, 0.0, 0.0)
        pose_bone.location = (0.0, 0.0, 0.0)
        if pose_bone.parent is None:  # its location is along its rest axes, from its rest head
            head = world @ pose_bone.bone.head_local
            target = world.inverted() @ Vector((0.0, 0.0, head.z - lowest))
            pose_bone.location = pose_bone.bone.matrix_local.to_3x3().inverted() @ (target - pose_bone.bone.head_local)
        for path in ("location", "rotation_euler", "rotation_quaternion"):
            pose_bone.keyframe_insert(path, frame=frame)


def main() -> None:
    scene = bpy.context.scene
    for obj in list(scene.objects):  # the factory scene's cube, camera and light
        bpy.data.objects.remove(obj, do_unlink=True)
    builtins.open = _open_without_u
    try:
        bpy.ops.import_anim.bvh(filepath=bvh_path, global_scale=1.0, frame_start=1, use_fps_scale=False,
                                update_scene_fps=True, update_scene_duration=True, rotate_mode="NATIVE",
                                axis_forward="-Z", axis_up="Y")
    finally:
        builtins.open = _open
    armature = next(obj for obj in scene.objects if obj.type == "ARMATURE")
    armature.name = armature.data.name = "Armature"
    armature.animation_data.action.name = "dance"
    count = int(frames)
    shift_keys(armature.animation_data.action, -1.0)  # the importer starts at frame 1
    key_rest_pose(armature, frame=count)
    scene.frame_start, scene.frame_end = 0, count - 1  # exactly the dance's frames, baked one by one
    scene.frame_set(count)  # the rest pose: what the exporter writes as the bones' static transforms
    bpy.ops.export_scene.fbx(
        filepath=fbx_path, use_selection=False, object_types={"ARMATURE"},
        axis_forward="-Z", axis_up="Y", global_scale=1.0, apply_unit_scale=True, apply_scale_options="FBX_SCALE_NONE",
        add_leaf_bones=False, primary_bone_axis="Y", secondary_bone_axis="X", armature_nodetype="NULL",
        use_armature_deform_only=False,
        bake_anim=True, bake_anim_use_all_bones=True, bake_anim_use_nla_strips=False, bake_anim_use_all_actions=False,
        bake_anim_force_startend_keying=True, bake_anim_step=1.0, bake_anim_simplify_factor=0.0)


main()
