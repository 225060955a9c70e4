"""Every metric of `dancegen.evaluate` against `bench/metrics_reference.py`, the Python/numpy
port of the reference metric code that the metrics benchmark times, on the golden set's clips
(`fixtures/metrics/inputs`): set values and per-clip values, solo under two protocols, group
scenes and duets."""

import sys

import numpy as np
import pytest

import dancegen
from conftest import METRICS, ROOT

sys.path.insert(0, str(ROOT / "bench"))
ref = pytest.importorskip("metrics_reference")  # needs scipy (tests/requirements.txt)

INPUTS = METRICS / "inputs"
BEATS = np.load(METRICS / "outputs" / "bas" / "music_beats_real_freezingpoint_fps30.npy")
# Float rounding between numpy's and Rust's summation orders; FID goes through sqrtm.
TOLERANCE = 1e-6


def clips(sub, suffix):
    files = sorted((INPUTS / sub).glob(f"*{suffix}.npy"))
    return [(p.name[: -len(f"{suffix}.npy")], np.load(p).astype(np.float64)) for p in files]


def check(groups, report):
    worst = {}
    for fn in groups.values():
        if fn is None:
            continue
        values, per_clip = fn()
        worst.update(ref.compare(values, per_clip, report))
    assert worst, "nothing compared"
    bad = {k: w for k, w in worst.items() if w is None or w > TOLERANCE}
    assert not bad, f"differ from the reference port (relative): {bad}; all: {worst}"
    return worst


@pytest.mark.parametrize("protocol", ["none", "finedance-lodge"])
def test_solo_metrics_equal_the_reference_port(protocol):
    pred, gt = clips("generated", "_yup_30fps"), clips("real", "_yup_30fps")
    report = dancegen.evaluate(dict(pred), dict(gt), protocol=protocol, fps=30,
                               beats=BEATS.astype(int).tolist(),
                               metrics="fid_k,div_k,fid_g,div_g,bas,pfc,fsr,freeze,boundary_jerk")
    worst = check(ref.solo_groups(pred, gt, BEATS.astype(np.int64), protocol, 30.0), report)
    assert {"fid_k", "fid_g", "bas", "pfc", "fsr", "freeze", "boundary_jerk"} <= set(worst)


def test_group_metrics_equal_the_reference_port():
    pred = [(f"scene{i}", np.load(INPUTS / "scenes" / f"gen_scene{i}_yup_30fps.npy"))
            for i in range(1, 5)]
    gt = [(f"scene{i}", np.load(INPUTS / "scenes" / f"gt_scene{i}_yup_30fps.npy"))
          for i in range(1, 5)]
    pytest.importorskip("dtaidistance")
    report = dancegen.evaluate(dict(pred), dict(gt), fps=30, metrics="gmr,gmc")
    check(ref.group_groups([(n, a.astype(np.float64)) for n, a in pred],
                           [(n, a.astype(np.float64)) for n, a in gt]), report)


def test_duet_metrics_equal_the_reference_port():
    def role(prefix, r):
        return [(f"duet{i}", np.load(
            INPUTS / "duets" / f"{prefix}_duet{i}_{r}_smpl24_yup_30fps.npy").astype(np.float64))
            for i in range(1, 5)]

    pf, pl, gf, gl = (role("gen", "follower"), role("gen", "leader"),
                      role("gt", "follower"), role("gt", "leader"))
    report = dancegen.evaluate(dict(pf), dict(gf), leader=dict(pl), gt_leader=dict(gl), fps=30,
                               metrics="fid_cd,div_cd,bed")
    check(ref.duet_groups(pf, pl, gf, gl), report)
