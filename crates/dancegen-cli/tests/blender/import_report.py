"""Import one dancegen file into an empty Blender scene and report what Blender made of it.

Run headless by the Blender client test (crates/dancegen-cli/tests/cli_blender.rs):

    blender -b --factory-startup -noaudio --python-exit-code 1 \
        --python import_report.py -- FORMAT FILE REPORT.json FRAMES

FORMAT is bvh, glb or fbx; FRAMES a comma-separated list of 0-based motion frames. The report
(JSON) holds the scene's frame rate and range and, per armature, its bone names, its action's
frame range and, at each requested frame, every bone head in world space (metres, Blender's
Z-up). Frame f of the motion is Blender frame `first + f`, where `first` is the first key of
the action. The Rust test compares these with the dance's .npy.

Written for the importers that ship with Blender (Debian's 3.4 and newer); two shims let
Blender 3.4's add-ons run on Python 3.11 and numpy >= 1.24 (see ecosystem.md, section 4).
"""

import builtins
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

# BVH importer of Blender 3.4 opens files with mode 'rU'; Python 3.11 removed 'U'.
_open = builtins.open


def _open_without_u(file, mode="r", *args, **kwargs):
    if isinstance(mode, str):
        mode = mode.replace("U", "")
    return _open(file, mode, *args, **kwargs)


builtins.open = _open_without_u

FPS = 30


def main():
    argv = sys.argv[sys.argv.index("--") + 1:]
    fmt, path, report_path, frames = argv[0], argv[1], argv[2], argv[3]
    frames = [int(f) for f in frames.split(",") if f]

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    # glTF is sampled at the scene's rate on import: set ours first.
    scene.render.fps = FPS
    scene.render.fps_base = 1.0

    if fmt == "bvh":
        # Our BVH is in centimetres (as BVH tools expect) and Y-up; 0.01 gives metres.
        bpy.ops.import_anim.bvh(
            filepath=path,
            global_scale=0.01,
            axis_forward="-Z",
            axis_up="Y",
            update_scene_fps=True,
            update_scene_duration=True,
        )
    elif fmt == "glb":
        bpy.ops.import_scene.gltf(filepath=path)
    elif fmt == "fbx":
        bpy.ops.import_scene.fbx(filepath=path)
    else:
        raise SystemExit(f"unknown format {fmt}")

    armatures = sorted(
        (o for o in scene.objects if o.type == "ARMATURE"), key=lambda o: o.name
    )
    report = {
        "fps": scene.render.fps / scene.render.fps_base,
        "scene_frame_start": scene.frame_start,
        "scene_frame_end": scene.frame_end,
        "meshes": sorted(o.name for o in scene.objects if o.type == "MESH"),
        "armatures": [],
    }
    for arm in armatures:
        action = arm.animation_data.action if arm.animation_data else None
        first, last = (action.frame_range if action else (0.0, 0.0))
        entry = {
            "name": arm.name,
            "bones": [b.name for b in arm.data.bones],
            "action_first": first,
            "action_last": last,
            "frames": {},
        }
        report["armatures"].append(entry)
    for f in frames:
        for arm, entry in zip(armatures, report["armatures"]):
            bf = entry["action_first"] + f
            whole = int(bf)
            scene.frame_set(whole, subframe=bf - whole)
            bpy.context.view_layer.update()
            entry["frames"][str(f)] = {
                pb.name: list(arm.matrix_world @ pb.head) for pb in arm.pose.bones
            }
    with _open(report_path, "w") as out:
        json.dump(report, out)


main()
