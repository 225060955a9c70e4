"""Motion files: read every motion `dancegen convert` reads, write every format it writes, and
SMPL forward kinematics.

    m = dancegen.io.read("take.bvh", source_fps=60)   # a Motion
    m.joints                                            # (T, J, 3) float32 world positions
    m.convert(to="smpl24").save("take.glb", rig="mixamo")
    dancegen.io.smpl(poses, trans, fps=30).save("dance.fbx")

Conventions (the canonical motion of `crates/dancegen-motion`): metres, Y up, SMPL 24 joints in
SMPL's order, axis-angle local rotations.
"""

from ._dancegen import Motion, joints, read, smpl, smpl_fk

__all__ = ["Motion", "joints", "read", "smpl", "smpl_fk", "write"]


def write(path, motion: Motion, **options) -> None:
    """`motion.save(path, **options)`: writes `motion` in the format of `path`'s extension."""
    motion.save(path, **options)
