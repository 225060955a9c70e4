"""dancegen for Blender: a panel in the 3D view's sidebar (N panel, tab "dancegen") that turns a
song into a dance with the `dancegen` binary and brings it into the scene: one armature per
dancer with its action at the scene's frame rate, the frame range set to the dance, and the song
in the sequencer in sync. With an armature selected, the dance can land on that character.

The binary is run as a separate program (its path in the add-on's preferences; by default the
`dancegen` on PATH), with `--progress json`, so the add-on needs nothing but Blender.
"""

bl_info = {
    "name": "dancegen",
    "author": "dancegen contributors",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > dancegen",
    "description": "Music in, 3D dance out: a dance made by dancegen for a song, in the scene",
    "doc_url": "https://github.com/dancegen/dancegen#blender-add-on",
    "category": "Animation",
}

if "bpy" in locals():
    import importlib

    for _m in (command, compat, transfer, settings, scene_import, operator, panel):  # noqa: F821
        importlib.reload(_m)
else:
    from . import command, compat, transfer, settings, scene_import, operator, panel

import bpy

_CLASSES = (
    settings.DancegenPreferences,
    settings.DancegenSettings,
    operator.DANCEGEN_OT_dance,
    panel.DANCEGEN_PT_panel,
)


def register():
    for cls in _CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Scene.dancegen = bpy.props.PointerProperty(type=settings.DancegenSettings)


def unregister():
    del bpy.types.Scene.dancegen
    for cls in reversed(_CLASSES):
        bpy.utils.unregister_class(cls)
