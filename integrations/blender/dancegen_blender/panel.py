"""The panel in the 3D view's sidebar (press N, tab "dancegen")."""

import bpy


class DANCEGEN_PT_panel(bpy.types.Panel):
    bl_label = "dancegen"
    bl_idname = "DANCEGEN_PT_panel"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "dancegen"

    def draw(self, context):
        s = context.scene.dancegen
        col = self.layout.column()
        col.prop(s, "song")
        col.prop(s, "system")
        if s.system == "duet":
            col.prop(s, "leader")
        if s.system == "group":
            col.prop(s, "dancers")
        col.prop(s, "seed")
        row = col.row(align=True)
        row.prop(s, "start")
        row.prop(s, "end")
        sub = col.row()
        sub.enabled = s.system != "group"
        sub.prop(s, "use_character")
        if s.use_character:
            arm = context.active_object
            col.label(text=f"Character: {arm.name}" if arm and arm.type == "ARMATURE"
                      else "Select an armature", icon="ARMATURE_DATA")
        col.separator()
        col.operator("dancegen.dance", icon="PLAY_SOUND")
        if s.last_error:
            box = col.box()
            box.label(text="The last dance failed:", icon="ERROR")
            for line in _wrap(s.last_error, 40):
                box.label(text=line)


def _wrap(text, width):
    words, line, out = text.split(), "", []
    for w in words:
        if line and len(line) + 1 + len(w) > width:
            out.append(line)
            line = w
        else:
            line = f"{line} {w}".strip()
    if line:
        out.append(line)
    return out
