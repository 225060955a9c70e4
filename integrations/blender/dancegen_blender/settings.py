"""The add-on's preferences (where the binary is) and the panel's settings (what to dance)."""

import bpy

from .command import SYSTEMS

ADDON = __package__


class DancegenPreferences(bpy.types.AddonPreferences):
    bl_idname = ADDON

    binary: bpy.props.StringProperty(
        name="dancegen binary",
        description="The dancegen program to run; empty: the one on PATH",
        subtype="FILE_PATH",
        default="",
    )
    keep_dir: bpy.props.StringProperty(
        name="Keep the files in",
        description="Folder for each dance's files (.glb, .npy); empty: a new temporary folder",
        subtype="DIR_PATH",
        default="",
    )

    def draw(self, context):
        self.layout.prop(self, "binary")
        self.layout.prop(self, "keep_dir")


def preferences(context):
    return context.preferences.addons[ADDON].preferences


_SYSTEM_ITEMS = [
    ("solo", "Solo", "One dancer, long-form (Lodge++)"),
    ("duet", "Duet", "A partner for a leader's motion (ReactDance)"),
    ("group", "Group", "2 to 5 dancers together (TCDiff++)"),
    ("holistic", "Holistic", "One dancer with fingers and face (SoulNet)"),
]
assert tuple(i[0] for i in _SYSTEM_ITEMS) == SYSTEMS


class DancegenSettings(bpy.types.PropertyGroup):
    song: bpy.props.StringProperty(name="Song", subtype="FILE_PATH",
                                   description="The music to dance to (WAV, FLAC, OGG, MP3, …)")
    system: bpy.props.EnumProperty(name="Dance", items=_SYSTEM_ITEMS, default="solo")
    leader: bpy.props.StringProperty(name="Leader", subtype="FILE_PATH",
                                     description="The leader's motion (.bvh, .fbx, .glb, .npz, …)")
    dancers: bpy.props.IntProperty(name="Dancers", min=2, max=5, default=3)
    seed: bpy.props.IntProperty(name="Seed", min=0, default=0,
                                description="Same song and seed, same dance")
    start: bpy.props.FloatProperty(name="Start (s)", min=0.0, default=0.0,
                                   description="Where in the song the dance starts")
    end: bpy.props.FloatProperty(name="End (s)", min=0.0, default=0.0,
                                 description="Where it ends; 0: the end of the song")
    use_character: bpy.props.BoolProperty(
        name="On the selected armature",
        description="Dance on the selected armature (exported as a temporary .glb for "
                    "dancegen --character): its rig, meshes and materials",
        default=False,
    )
    # Read-only results, for the user (and the add-on's test).
    last_dir: bpy.props.StringProperty(name="Files", subtype="DIR_PATH", default="")
    last_error: bpy.props.StringProperty(name="Last error", default="")
