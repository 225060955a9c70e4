"""`dancegen.metrics` against the reference implementations' own outputs on the golden set
(`fixtures/metrics`, produced by running the reference repositories' code; README there), with
the clips passed as numpy arrays, at the tolerances of the Rust golden tests (float64 inputs:
the golden precision)."""

import json

import numpy as np
import pytest

import dancegen
from dancegen import metrics
from conftest import METRICS, cli

INPUTS = METRICS / "inputs"
OUT = METRICS / "outputs"
GOLDEN = json.loads((METRICS / "golden_values.json").read_text())


def rel(got, want):
    return 0.0 if got == want else abs(got - want) / max(abs(want), 1e-300)


def load(sub, name):
    return np.load(INPUTS / sub / f"{name}.npy")


def yup60(sub):
    """The set's `_yup_60fps` clips by name, as arrays."""
    return {p.name[: -len("_yup_60fps.npy")]: np.load(p)
            for p in sorted((INPUTS / sub).glob("*_yup_60fps.npy"))}


def test_fid_and_div_equal_bailando():
    want = json.loads((OUT / "fid_bailando_60fps" / "metrics.json").read_text())
    pred, gt = yup60("generated"), yup60("real")
    kw = dict(protocol="aistpp-bailando", fps=60)
    assert rel(metrics.fid_k(pred, gt, **kw), want["fid_k"]["real"]) < 1e-6
    assert rel(metrics.fid_g(pred, gt, **kw), want["fid_m"]["real"]) < 1e-6
    assert rel(metrics.div_k(pred, gt, **kw), want["div_k"]["real"]) < 1e-6
    assert rel(metrics.div_g(pred, gt, **kw), want["div_m"]["real"]) < 1e-6
    report = dancegen.evaluate(pred, gt, metrics="div_k,div_g", **kw)
    assert rel(report["div_k_gt"], want["div_k_gt"]["real"]) < 1e-6
    assert rel(report["div_g_gt"], want["div_m_gt"]["real"]) < 1e-6


@pytest.mark.parametrize("variant", ["bailando", "lodge", "fact", "gcd"])
def test_bas_equals_each_reference_variant_per_clip(variant):
    golden = json.loads((OUT / "bas" / f"bas_{variant}.json").read_text())["per_clip"]
    beats = {
        fps: np.load(OUT / "bas" / f"music_beats_real_freezingpoint_fps{fps}.npy").astype(int)
        for fps in (30, 60)
    }
    lodge_beats = np.load(OUT / "bas" / "lodge_beats_from_wav_fps30.npy").astype(int)
    checked = 0
    for key, entry in golden.items():
        name, at = key.split("@")
        fps = int(at[: -len("fps")])
        sub = "generated" if name.startswith("gen") else "real"
        clip = load(sub, f"{name}_yup_{fps}fps")
        music = lodge_beats if variant == "lodge" else beats[fps]
        got = metrics.bas(clip, beats=music.tolist(), variant=variant, fps=fps)
        if "error" in entry:
            assert got is None, f"{key}: the reference raised, ours {got}"
        else:
            assert rel(got, entry["score"]) < 1e-6, f"{key}: {got} vs {entry['score']}"
        checked += 1
    assert checked >= 11


def test_pfc_equals_edge():
    golden = GOLDEN["pfc_edge_per_clip"]
    for name, want in golden.items():
        if not name.startswith("gen"):
            # The real Z-up clips were made by EDGE's own rotation, up to 1.2e-6 m from the
            # plain (x, -z, y) of their Y-up files, which `eval` applies.
            continue
        got = metrics.pfc(load("generated", f"{name}_yup_30fps"), fps=30)
        if want == "NaN":
            assert got is None, name
        else:
            assert rel(got, want) < 1e-6, f"{name}: {got} vs {want}"


def scenes(prefix):
    return {f"scene{i}": load("scenes", f"{prefix}_scene{i}_yup_30fps") for i in range(1, 5)}


def test_group_metrics_equal_gcd():
    g = GOLDEN["gcd"]
    pred, gt = scenes("gen"), scenes("gt")
    assert rel(metrics.gmr(pred, gt, fps=30), g["GMR_k"]) < 1e-6
    assert rel(metrics.gmc(pred, fps=30), g["gmc_mean_generated"]) < 1e-9
    report = dancegen.evaluate(pred, fps=30, metrics="gmc")
    for i, row in enumerate(report["per_clip"], 1):
        assert rel(row["gmc"], g["GMC_per_scene"][f"gen_scene{i}"]) < 1e-9


def duets(prefix):
    def role(r):
        return {f"duet{i}": load("duets", f"{prefix}_duet{i}_{r}_smpl24_yup_30fps")
                for i in range(1, 5)}
    return role("follower"), role("leader")


def test_duet_metrics_equal_duolando():
    g = GOLDEN["duolando"]
    (pred, lead), (gt, gt_lead) = duets("gen"), duets("gt")
    assert rel(metrics.fid_cd(pred, lead, gt, gt_lead, fps=30), g["FID_cd"]) < 1e-6
    assert rel(metrics.div_cd(pred, lead, gt, gt_lead, fps=30), g["Div_cd"]) < 1e-6
    assert rel(metrics.bed(pred, lead, fps=30), g["BED_mean_generated"]) < 1e-9


def test_mpjpe_equals_souldance():
    golden = json.loads((OUT / "mpjpe" / "mpjpe_souldance.json").read_text())
    for key, entry in golden.items():
        if entry["joints"] != 24:
            continue
        pair = entry["pair"]
        gt = np.load(INPUTS / pair["gt"]["file"])[pair["gt"]["start"]: pair["gt"]["stop"]]
        pred = np.load(INPUTS / pair["pred"]["file"])
        got = metrics.mpjpe({"c": pred}, {"c": gt}, fps=30)
        assert rel(got, entry["mean_f64"]) < 1e-6, f"{key}: {got} vs {entry['mean_f64']}"


def test_physical_figures_are_the_clis(tmp_path):
    clip = load("real", "R3_yup_30fps")
    figures = metrics.physical(clip, fps=30)
    assert set(figures) == set(metrics.PHYSICAL)
    path, out = tmp_path / "R3.npy", tmp_path / "eval.json"
    np.save(path, clip)
    cli("eval", "--pred", path, "--fps", "30", "--metrics", "physical", "--json", out)
    want = json.loads(out.read_text())
    assert figures == {k: want[k] for k in metrics.PHYSICAL}
    # A real dancer steps and moves its joints: figures a broken metric would not give.
    assert figures["step_rate"] > 0.1 and figures["joint_speed"] > 0.1


def test_arrays_and_files_give_the_same_report(tmp_path):
    pred, gt = yup60("generated"), yup60("real")
    for sub, clips in (("pred", pred), ("gt", gt)):
        (tmp_path / sub).mkdir()
        for name, a in clips.items():
            np.save(tmp_path / sub / f"{name}.npy", a)
    kw = dict(protocol="aistpp-bailando", fps=60, metrics="fid_k,div_k,pfc,fsr,physical")
    files = dancegen.evaluate(tmp_path / "pred", tmp_path / "gt", **kw)
    arrays = dancegen.evaluate(pred, gt, **kw)
    for report in (files, arrays):
        for row in report["per_clip"]:
            row["file"] = row["file"].rsplit("/", 1)[-1].removesuffix(".npy")
    assert files == arrays


def test_a_wrong_shape_names_the_array():
    with pytest.raises(dancegen.DancegenError, match=r"array bad.*\[90, 72\]"):
        metrics.pfc({"bad": np.zeros((90, 72), np.float32)}, fps=30)
    with pytest.raises(dancegen.DancegenError, match="float32 or float64"):
        metrics.pfc({"ints": np.zeros((90, 24, 3), np.int64)}, fps=30)
    with pytest.raises(TypeError, match="pred"):
        metrics.pfc(42, fps=30)
