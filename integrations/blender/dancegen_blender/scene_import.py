"""Bringing a finished dance into the scene: the `.glb` imported (one armature per dancer, each
with its action), the actions moved to start at frame 1, the scene's frame range set to the
dance, and the song put in the sequencer so that playback has sound in sync."""

import math
import os

import bpy

from . import transfer
from .compat import patch_numpy_bool

SOUND_STRIP = "dancegen song"


def import_dance(context, glb, song, start_s, onto=None):
    """Imports `glb`; returns its armatures (sorted by name). `start_s` is where the dance
    starts in `song` (seconds): the sound strip is trimmed to start there. With `onto` (the
    user's armature that `glb` is a dancing copy of), the copy's motion is baked onto it and
    the copy removed ([`transfer`]); then `[onto]` is returned."""
    patch_numpy_bool()
    scene = context.scene
    before = set(scene.objects)
    # glTF keys are in seconds; the importer places them on the scene's frame rate.
    bpy.ops.import_scene.gltf(filepath=glb)
    new = [o for o in scene.objects if o not in before]
    armatures = sorted((o for o in new if o.type == "ARMATURE"), key=lambda o: o.name)
    if not armatures:
        raise RuntimeError(f"{os.path.basename(glb)} holds no armature")
    actions = {a.animation_data.action for a in armatures
               if a.animation_data and a.animation_data.action}
    # The importer puts the dance's time 0 on frame 0; Blender's scenes start at frame 1.
    for action in actions:
        for fc in action.fcurves:
            for k in fc.keyframe_points:
                k.co.x += 1.0
                k.handle_left.x += 1.0
                k.handle_right.x += 1.0
            fc.update()
    first = min(a.frame_range[0] for a in actions) if actions else 1.0
    last = max(a.frame_range[1] for a in actions) if actions else 1.0
    scene.frame_start = int(round(first))
    scene.frame_end = int(math.ceil(last - 1e-6))
    if onto is not None:
        if len(armatures) != 1:
            raise RuntimeError(f"the character's dance holds {len(armatures)} armatures, not 1")
        transfer.bake_onto(context, armatures[0], onto, scene.frame_start, scene.frame_end)
        transfer.remove_with_children(new)
        armatures = [onto]
    put_song(scene, song, int(round(first)), start_s)
    return armatures


def put_song(scene, song, first_frame, start_s):
    """The song as a sound strip that plays second `start_s` of it at `first_frame`."""
    fps = scene.render.fps / scene.render.fps_base
    seq = scene.sequence_editor or scene.sequence_editor_create()
    old = seq.sequences.get(SOUND_STRIP)
    if old is not None:
        seq.sequences.remove(old)
    offset = int(round(start_s * fps))
    strip = seq.sequences.new_sound(SOUND_STRIP, song, channel=1, frame_start=first_frame - offset)
    strip.frame_offset_start = offset
    return strip
