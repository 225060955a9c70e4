"""`dancegen.generate`: for the same song, options and seed, `Dance.save` writes the files
`dancegen generate -o` writes, byte for byte, for each system; `Dance.joints` is the `.npy`;
options are `generate`'s flags by name and bad ones are refused in its words."""

import numpy as np
import pytest

import dancegen
from conftest import DEMO, SHARED, cli

ROBOT = SHARED / "data" / "holistic" / "three-js-robot-expressive" / "RobotExpressive.glb"
# Short dances with few denoising steps: the comparison is of code paths, not of quality.
QUICK = dict(end=5, steps=4)
QUICK_FLAGS = ["--end", "5", "--steps", "4"]


def same_files(tmp_path, dance, flags, exts, **save):
    """Writes `exts` from `dance` and from `dancegen generate FLAGS`; asserts equal bytes."""
    for ext in exts:
        mine = tmp_path / f"py.{ext}"
        written = dance.save(mine, **save)
        assert [str(p) for p in written] == [str(mine)]
        theirs = tmp_path / f"cli.{ext}"
        cli("generate", *flags, "-q", "-o", theirs)
        assert mine.read_bytes() == theirs.read_bytes(), ext


def test_solo_is_the_clis_byte_for_byte(tmp_path):
    dance = dancegen.generate(DEMO, seed=3, start=2, **QUICK)
    assert (dance.system, dance.fps, dance.dancers) == ("solo", 30, 1)
    assert dance.span == (2.0, 5.0)
    flags = [DEMO, "--seed", "3", "--start", "2", *QUICK_FLAGS]
    same_files(tmp_path, dance, flags, ["npy", "npz", "bvh", "glb", "json"])
    joints = np.load(tmp_path / "cli.npy")
    assert joints.shape == (90, 24, 3)
    np.testing.assert_array_equal(dance.joints, joints)
    assert dance.joints.dtype == np.float32 and dance.joints.flags.c_contiguous


def test_rig_and_character_are_save_options(tmp_path):
    dance = dancegen.generate(DEMO, seed=1, **QUICK)
    flags = [DEMO, "--seed", "1", *QUICK_FLAGS]
    same_files(tmp_path, dance, [*flags, "--rig", "ue5"], ["fbx"], rig="ue5")
    mine, theirs = tmp_path / "py_robot.glb", tmp_path / "cli_robot.glb"
    dance.save(mine, character=ROBOT)
    cli("generate", *flags, "--character", ROBOT, "-q", "-o", theirs)
    assert mine.read_bytes() == theirs.read_bytes()
    with pytest.raises(dancegen.DancegenError, match="character.*dances in a .glb"):
        dance.save(tmp_path / "robot.bvh", character=ROBOT)


def test_group_and_duet_are_the_clis(tmp_path):
    group = dancegen.generate(DEMO, system="group", dancers=3, seed=2, **QUICK)
    assert group.joints.shape[:2] == (3, 150)
    same_files(tmp_path, group,
               [DEMO, "--system", "group", "--dancers", "3", "--seed", "2", *QUICK_FLAGS],
               ["npy", "glb"])
    leader = tmp_path / "leader.npz"
    dancegen.generate(DEMO, seed=5, **QUICK).save(leader)
    # A duet lasts as long as its leader (5 s here).
    duet = dancegen.generate(DEMO, leader=leader, seed=4, steps=4)
    assert (duet.system, duet.dancers, duet.joints.shape) == ("duet", 2, (150, 24, 3))
    same_files(tmp_path, duet, [DEMO, "--leader", leader, "--seed", "4", "--steps", "4"],
               ["npy", "glb"])


def test_holistic_is_the_clis(tmp_path):
    dance = dancegen.generate(DEMO, system="holistic", seed=6, **QUICK)
    assert dance.joints.shape == (150, 52, 3)
    same_files(tmp_path, dance,
               [DEMO, "--system", "holistic", "--seed", "6", *QUICK_FLAGS], ["npy", "csv"])


def test_bad_requests_are_refused_in_the_clis_words(tmp_path):
    with pytest.raises(dancegen.DancegenError, match="tango"):
        dancegen.generate(DEMO, system="tango")
    with pytest.raises(dancegen.DancegenError, match="--tempo"):
        dancegen.generate(DEMO, tempo=120)
    with pytest.raises(dancegen.DancegenError, match="is an option of Dance.save"):
        dancegen.generate(DEMO, rig="mixamo")
    with pytest.raises(dancegen.DancegenError, match="nowhere.ogg"):
        dancegen.generate(tmp_path / "nowhere.ogg", **QUICK)
    with pytest.raises(dancegen.DancegenError, match="--dancers"):
        dancegen.generate(DEMO, system="group", **QUICK)
    with pytest.raises(dancegen.DancegenError, match="no_foot_lock.*switch"):
        dancegen.generate(DEMO, no_foot_lock="yes", **QUICK)
    dance = dancegen.generate(DEMO, seed=0, **QUICK)
    with pytest.raises(dancegen.DancegenError, match="dance.xyz"):
        dance.save(tmp_path / "dance.xyz")
    with pytest.raises(dancegen.DancegenError, match="follower_only"):
        dance.save(tmp_path / "dance.glb", follower_only=True)
    assert not list(tmp_path.iterdir()), "a refused request leaves no file"


def test_ctrl_c_stops_a_long_generation():
    """SIGINT (Ctrl-C) during `generate` raises KeyboardInterrupt within a sampler step or
    two, instead of running to the end of a 40-second dance."""
    import signal
    import subprocess
    import sys
    import time

    # A shell that starts commands in the background (CI, nohup) hands them SIGINT ignored,
    # and Python then installs no KeyboardInterrupt handler: the child installs it, as an
    # interactive Python has it.
    script = (
        "import signal\n"
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        "import dancegen, sys\n"
        "print('started', flush=True)\n"
        f"dancegen.generate({str(DEMO)!r}, end=40)\n"
        "print('finished', flush=True)\n"
    )
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    assert proc.stdout.readline().strip() == "started"
    time.sleep(3.0)  # into the model load and the sampling
    sent = time.monotonic()
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    stopped_after = time.monotonic() - sent
    assert "finished" not in out
    assert "KeyboardInterrupt" in err, err
    assert stopped_after < 5.0, f"took {stopped_after:.1f} s to stop"
