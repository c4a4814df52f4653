"""Run inside Blender: the largest step between two keys of any animation curve in an FBX file.

    blender --background --factory-startup --python tests/blender/fbx_curves.py -- IN.fbx OUT.json

Reads the file's own curves with Blender's FBX parser (no import, so nothing is converted): a
rotation curve that wraps from +180 to -180 degrees shows as a step of about 360.
"""

import json
import sys

from io_scene_fbx import parse_fbx

fbx_path, out_path = sys.argv[sys.argv.index("--") + 1:]


def elements(element):
    yield element
    for child in element.elems:
        yield from elements(child)


steps = []
for element in elements(parse_fbx.parse(fbx_path)[0]):
    if element.id == b"AnimationCurve":
        for values in (child.props[0] for child in element.elems if child.id == b"KeyValueFloat"):
            steps.append(max((abs(b - a) for a, b in zip(values, values[1:])), default=0.0))
with open(out_path, "w") as handle:
    json.dump({"curves": len(steps), "largest_step": max(steps, default=0.0)}, handle)
