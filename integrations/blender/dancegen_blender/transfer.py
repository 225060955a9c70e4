"""The dance onto the user's own armature: the pose of the dancing copy dancegen made (the
character exported, retargeted with `--character`, imported again) baked onto the selected
armature bone by bone, in world space, at every frame; then the copy is removed. The user keeps
their rig, meshes, materials and everything parented to the bones, exactly as they were: a
glTF export and import of a rig can move meshes that are parented to bones (the three.js robot
came back in pieces from Blender 3.4's exporter), so the copy is only used for its motion.

Bones are matched by name: the copy is the same armature, exported and imported. Blender poses a
bone as `P = P_parent · Rest_parent⁻¹ · Rest · B` (armature space; `Rest` = `bone.matrix_local`,
`B` = `matrix_basis`), so the basis that puts the bone where the copy's is follows without
evaluating the scene once per bone.
"""

import bpy

ACTION_NAME = "dancegen dance"


def bake_onto(context, source, target, first, last):
    """Keys `target`'s bones at every frame `first..=last` to the world pose of `source`'s bones
    of the same names. Returns the new action."""
    scene = context.scene
    bones = [pb for pb in target.pose.bones if pb.name in source.pose.bones]
    # Parents before children.
    bones.sort(key=lambda pb: len(pb.parent_recursive))
    rest = {pb.name: pb.bone.matrix_local.copy() for pb in target.pose.bones}
    if target.animation_data is None:
        target.animation_data_create()
    action = bpy.data.actions.new(ACTION_NAME)
    target.animation_data.action = action
    for pb in bones:
        pb.rotation_mode = "QUATERNION"
    to_target = target.matrix_world.inverted()
    for f in range(first, last + 1):
        scene.frame_set(f)
        want = {pb.name: to_target @ source.matrix_world @ source.pose.bones[pb.name].matrix
                for pb in bones}
        for pb in bones:
            pose = want[pb.name]
            if pb.parent is None:
                basis = rest[pb.name].inverted() @ pose
            else:
                parent = want.get(pb.parent.name, pb.parent.matrix)
                basis = (parent @ rest[pb.parent.name].inverted() @ rest[pb.name]).inverted() @ pose
            pb.matrix_basis = basis
            for path in ("location", "rotation_quaternion", "scale"):
                pb.keyframe_insert(path, frame=f, group=pb.name)
    return action


def remove_with_children(objects):
    """Deletes `objects` and everything parented under them, and the data they leave unused."""
    doomed = set()
    for o in objects:
        doomed.add(o)
        doomed.update(o.children_recursive)
    for o in doomed:
        bpy.data.objects.remove(o, do_unlink=True)
