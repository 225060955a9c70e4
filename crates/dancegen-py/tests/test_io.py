"""`dancegen.io`: real motion read as `dancegen convert` reads it, every format written as
`convert` writes it (byte for byte), an arbitrary motion round-tripping through the formats,
SMPL forward kinematics, and bad input as DancegenError."""

import numpy as np
import pytest

import dancegen
from dancegen import io
from conftest import SHARED, cli

AIST = SHARED / "data" / "aistpp" / "motions" / "gBR_sBM_cAll_d04_mBR2_ch08.pkl"
SALSA = SHARED / "data" / "cmu-salsa" / "60_01_scaled.bvh"


def test_a_real_take_reads_as_convert_reads_it(tmp_path):
    m = io.read(AIST)
    assert (m.kind, m.fps, m.dancers) == ("SMPL 24 motion", 60, 1)
    frames = m.poses.shape[0]
    assert m.poses.shape == (frames, 24, 3) and m.trans.shape == (frames, 3)
    cli("convert", AIST, "-o", tmp_path / "cli.npy")
    np.testing.assert_array_equal(m.joints, np.load(tmp_path / "cli.npy"))
    # The salsa takes were captured at 60 fps, whatever their headers say.
    salsa = io.read(SALSA, source_fps=60)
    assert (salsa.kind, salsa.fps) == ("BVH motion", 60)
    assert salsa.poses is None and salsa.joints.ndim == 3
    smpl = salsa.convert(to="smpl24", fps=30)
    assert (smpl.kind, smpl.fps, smpl.poses.shape[1:]) == ("SMPL 24 motion", 30, (24, 3))


@pytest.mark.parametrize("ext", ["bvh", "glb", "fbx", "npz", "npy", "json"])
def test_every_format_is_the_file_convert_writes(tmp_path, ext):
    mine, theirs = tmp_path / f"py.{ext}", tmp_path / f"cli.{ext}"
    io.read(AIST).save(mine, rig="mixamo" if ext in ("bvh", "glb", "fbx") else "smpl", fps=30)
    rig = ["--rig", "mixamo"] if ext in ("bvh", "glb", "fbx") else []
    cli("convert", AIST, "--fps", "30", *rig, "-o", theirs)
    assert mine.read_bytes() == theirs.read_bytes()


def arbitrary_motion(frames=75, seed=7):
    """Smooth random SMPL rotations (up to ~0.6 rad a joint) on a wandering root path."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 2 * np.pi, frames)[:, None, None]
    amp = rng.uniform(-0.6, 0.6, (1, 24, 3))
    phase = rng.uniform(0, 2 * np.pi, (1, 24, 3))
    poses = (amp * np.sin(t + phase)).astype(np.float32)
    trans = np.stack([0.3 * np.sin(t[:, 0, 0]), 0.9 + 0.05 * np.cos(2 * t[:, 0, 0]),
                      0.2 * t[:, 0, 0]], axis=-1).astype(np.float32)
    return poses, trans


# Measured: 1.9e-19 m (npz), 1.2e-7 m (bvh, glb, fbx: one float32 step at a metre); 1e-6 leaves
# room for other float32 orders of operations, and a wrong joint or axis is off by centimetres.
@pytest.mark.parametrize("ext,tol", [("npz", 1e-6), ("bvh", 1e-6), ("glb", 1e-6), ("fbx", 1e-6)])
def test_an_arbitrary_motion_round_trips(tmp_path, ext, tol):
    poses, trans = arbitrary_motion()
    m = io.smpl(poses, trans, fps=30)
    joints = io.smpl_fk(poses, trans)
    np.testing.assert_array_equal(joints, m.joints)
    path = tmp_path / f"m.{ext}"
    io.write(path, m)
    back = io.read(path)
    if back.kind != "SMPL 24 motion":
        back = back.convert(to="smpl24")
    assert back.fps == 30
    assert np.abs(back.joints - joints).max() <= tol, ext  # metres
    if ext == "npz":
        np.testing.assert_array_equal(back.poses, poses)
        # AMASS stores SMPL's `transl` (the root path less the pelvis rest offset) in float64.
        np.testing.assert_allclose(back.trans, trans, rtol=0, atol=1e-6)


def test_smpl_fk_is_the_fk_of_every_reader():
    m = io.read(AIST)
    np.testing.assert_array_equal(io.smpl_fk(m.poses, m.trans), m.joints)
    # (T, 72) poses are the same rotations; a group stacks dancers.
    flat = m.poses.reshape(len(m.poses), 72)
    np.testing.assert_array_equal(io.smpl_fk(flat, m.trans), m.joints)
    group = io.smpl(np.stack([m.poses[:50]] * 2), np.stack([m.trans[:50], m.trans[:50] + 1]))
    assert (group.kind, group.dancers, group.joints.shape) == ("group motion", 2, (2, 50, 24, 3))


def test_joints_only_write_npy(tmp_path):
    a = np.random.default_rng(0).normal(size=(40, 24, 3)).astype(np.float32)
    io.joints(a, fps=30).save(tmp_path / "j.npy")
    np.testing.assert_array_equal(np.load(tmp_path / "j.npy"), a)


def test_bad_input_says_what_is_wrong(tmp_path):
    with pytest.raises(dancegen.DancegenError, match="nowhere.bvh"):
        io.read(tmp_path / "nowhere.bvh")
    poses, trans = arbitrary_motion()
    with pytest.raises(dancegen.DancegenError, match=r"expected poses \(T, 24, 3\)"):
        io.smpl(poses[:, :22], trans)
    with pytest.raises(dancegen.DancegenError, match=r"poses.*not a finite number"):
        bad = poses.copy()
        bad[3, 4, 1] = np.nan
        io.smpl(bad, trans)
    with pytest.raises(dancegen.DancegenError, match="source_fps"):
        io.read(SALSA, source_fps=0)
    with pytest.raises(dancegen.DancegenError, match="npz_style 'matlab'"):
        io.smpl(poses, trans).save(tmp_path / "m.npz", npz_style="matlab")
    with pytest.raises(dancegen.DancegenError, match="rig"):
        io.smpl(poses, trans).save(tmp_path / "m.bvh", rig="blender-rigify")
    assert not list(tmp_path.iterdir()), "a refused write leaves no file"


def test_arrays_in_any_memory_order_are_read_alike():
    poses, trans = arbitrary_motion()
    want = io.smpl_fk(poses, trans)
    fortran = np.asfortranarray(poses.astype(np.float64))
    strided = np.concatenate([poses, poses], axis=0)[::2]
    np.testing.assert_array_equal(io.smpl_fk(fortran, trans), want)
    np.testing.assert_array_equal(io.smpl_fk(strided, trans[: len(strided)]),
                                  io.smpl_fk(np.ascontiguousarray(strided), trans[: len(strided)]))
