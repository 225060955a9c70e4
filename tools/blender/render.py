"""Render one frame of a dancegen .fbx or .glb as Blender imports it, headless (Cycles on the
CPU, no GPU or display needed). Used for the README's pictures of our files in Blender:

    blender -b --factory-startup -noaudio --python-exit-code 1 \
        --python tools/blender/render.py -- dance.fbx FRAME out.png
"""

import math
import sys
import warnings

import bpy
import numpy

# Blender 3.4's glTF importer uses numpy.bool, removed in numpy 1.24.
with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    if not hasattr(numpy, "bool"):
        numpy.bool = bool
from mathutils import Vector


def main():
    argv = sys.argv[sys.argv.index("--") + 1:]
    path, frame, out = argv[0], int(argv[1]), argv[2]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps = 30
    if path.lower().endswith(".fbx"):
        bpy.ops.import_scene.fbx(filepath=path)
    else:
        bpy.ops.import_scene.gltf(filepath=path)
    scene.frame_set(frame)

    # Frame the dancers: the bounding box of every mesh at this frame.
    depsgraph = bpy.context.evaluated_depsgraph_get()
    points = []
    for o in scene.objects:
        if o.type == "MESH":
            ev = o.evaluated_get(depsgraph)
            points += [ev.matrix_world @ v.co for v in ev.to_mesh().vertices]
    lo = Vector([min(p[i] for p in points) for i in range(3)])
    hi = Vector([max(p[i] for p in points) for i in range(3)])
    centre, size = (lo + hi) / 2, max(hi - lo)

    bpy.ops.mesh.primitive_plane_add(size=8, location=(centre.x, centre.y, 0))
    bpy.ops.object.light_add(type="SUN", rotation=(math.radians(40), 0, math.radians(30)))
    bpy.context.object.data.energy = 3
    # Blender is Z-up and dancegen's dancers face +Z (Y-up), i.e. Blender's -Y: look from there.
    cam_loc = centre + Vector((0.8 * size, -2.6 * size, 0.5 * size))
    bpy.ops.object.camera_add(location=cam_loc)
    cam = bpy.context.object
    cam.rotation_euler = (centre - cam_loc).to_track_quat("-Z", "Y").to_euler()
    scene.camera = cam

    world = bpy.data.worlds.new("world")
    world.color = (0.8, 0.8, 0.85)
    scene.world = world
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 32
    scene.cycles.use_denoising = False  # Debian builds Blender without OpenImageDenoise
    scene.render.resolution_x, scene.render.resolution_y = 640, 480
    scene.render.filepath = out
    bpy.ops.render.render(write_still=True)


main()
