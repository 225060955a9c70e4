"""Import a dancegen .glb with a face into an empty Blender scene and report the face.

Run headless by crates/dancegen-formats/tests/gltf_face.rs:

    blender -b --factory-startup -noaudio --python-exit-code 1 \
        --python face_report.py -- FILE REPORT.json FRAMES

The report (JSON): the shape keys of the mesh object named "face" (Blender's names for the
glTF morph targets), how many of them the imported action animates, and every shape key's
value at each requested 0-based motion frame (Blender frame = first key + frame).
"""

import json
import sys
import warnings

import bpy
import numpy

# glTF importer of Blender 3.4 uses numpy.bool, removed in numpy 1.24.
with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    if not hasattr(numpy, "bool"):
        numpy.bool = bool


def main():
    argv = sys.argv[sys.argv.index("--") + 1:]
    path, report_path, frames = argv[0], argv[1], [int(f) for f in argv[2].split(",") if f]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps = 30
    scene.render.fps_base = 1.0
    bpy.ops.import_scene.gltf(filepath=path)
    faces = [o for o in bpy.data.objects if o.type == "MESH" and o.data.shape_keys]
    if len(faces) != 1:
        raise SystemExit(f"expected one mesh with shape keys, found {len(faces)}")
    face = faces[0]
    keys = face.data.shape_keys
    names = [k.name for k in keys.key_blocks[1:]]  # [0] is the basis
    action = keys.animation_data.action if keys.animation_data else None
    curves = [c for c in action.fcurves] if action else []
    first = min(c.range()[0] for c in curves) if curves else 0
    values = {}
    for f in frames:
        scene.frame_set(int(first) + f)
        values[str(f)] = [k.value for k in keys.key_blocks[1:]]
    report = {
        "object": face.name,
        "parent_bone": face.parent_bone if face.parent_type == "BONE" else None,
        "shape_keys": names,
        "animated_keys": len(curves),
        "first_frame": first,
        "values": values,
    }
    with open(report_path, "w") as out:
        json.dump(report, out)


main()
