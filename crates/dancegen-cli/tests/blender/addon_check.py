"""Installs the dancegen add-on from its zip into an empty Blender, runs its Dance operator
as a script would, and reports what came into the scene. Run headless by the add-on's test
(crates/dancegen-cli/tests/cli_blender_addon.rs):

    blender -b --factory-startup -noaudio --python-exit-code 1 --python addon_check.py -- \
        ZIP BINARY OUT_DIR REPORT.json CASE SONG [CHARACTER.glb]

CASE is `solo` (scene at 24 fps, seed 1, start 2 s, end 6 s), `character` (CHARACTER.glb
imported and its armature selected first, then a solo on it: the report's armature is that
one, which the dance is baked onto) or `bad_song` (SONG is not audio;
the operator's error is reported). The report (JSON): the scene's fps and frame range, the sound
strips, the dance's folder, and per new armature its bones, its action's frame range and every
bone head in world space (metres, Blender's Z-up) at the frames of the dance's whole seconds.
"""

import json
import sys

import bpy

ADDON = "dancegen_blender"


def main():
    argv = sys.argv[sys.argv.index("--") + 1:]
    zip_path, binary, out_dir, report_path, case, song = argv[:6]
    character = argv[6] if len(argv) > 6 else None

    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.preferences.addon_install(filepath=zip_path, overwrite=True)
    bpy.ops.preferences.addon_enable(module=ADDON)
    prefs = bpy.context.preferences.addons[ADDON].preferences
    prefs.binary = binary
    prefs.keep_dir = out_dir

    scene = bpy.context.scene
    scene.render.fps = 24
    scene.render.fps_base = 1.0
    s = scene.dancegen
    s.song = song
    s.system = "solo"
    s.seed = 1
    s.start = 2.0
    s.end = 6.0
    if case == "character":
        from dancegen_blender.compat import patch_numpy_bool

        patch_numpy_bool()
        bpy.ops.import_scene.gltf(filepath=character)
        arm = next(o for o in scene.objects if o.type == "ARMATURE")
        for o in scene.objects:
            o.select_set(False)
        arm.select_set(True)
        bpy.context.view_layer.objects.active = arm
        s.use_character = True
    before = set(scene.objects)
    report = {"case": case}
    try:
        bpy.ops.dancegen.dance()
        report["error"] = None
    except RuntimeError as e:
        report["error"] = str(e)
    report["last_error"] = s.last_error
    report["last_dir"] = s.last_dir
    fps = scene.render.fps / scene.render.fps_base
    report["fps"] = fps
    report["frame_start"] = scene.frame_start
    report["frame_end"] = scene.frame_end
    seq = scene.sequence_editor
    report["sounds"] = [
        {
            "name": st.name,
            "path": bpy.path.abspath(st.sound.filepath),
            "frame_start": st.frame_start,
            "frame_final_start": st.frame_final_start,
            "frame_offset_start": st.frame_offset_start,
            "channel": st.channel,
        }
        for st in (seq.sequences_all if seq else [])
        if st.type == "SOUND"
    ]
    # A character's dance is baked onto the selected armature itself: report that one.
    armatures = sorted((o for o in scene.objects if o.type == "ARMATURE"
                        and (o not in before or case == "character")), key=lambda o: o.name)
    report["objects_before"] = sorted(o.name for o in before)
    report["objects_after"] = sorted(o.name for o in scene.objects)
    report["armatures"] = []
    for arm in armatures:
        action = arm.animation_data.action if arm.animation_data else None
        first, last = tuple(action.frame_range) if action else (0.0, 0.0)
        report["armatures"].append({
            "name": arm.name,
            "action": action.name if action else None,
            "bones": [b.name for b in arm.data.bones],
            "action_first": first,
            "action_last": last,
            "heads": {},
        })
    # The dance's whole seconds fall on whole frames at 24 fps: frame first + 24 t.
    for entry, arm in zip(report["armatures"], armatures):
        t = 0
        while entry["action_first"] + fps * t <= entry["action_last"] + 1e-6:
            scene.frame_set(int(round(entry["action_first"] + fps * t)))
            bpy.context.view_layer.update()
            entry["heads"][str(t)] = {pb.name: list(arm.matrix_world @ pb.head) for pb in arm.pose.bones}
            t += 1
    with open(report_path, "w") as out:
        json.dump(report, out)


main()
