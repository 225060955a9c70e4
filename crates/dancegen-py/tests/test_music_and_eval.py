"""The Python package against the CLI it mirrors: the same numbers as `dancegen features` and
`dancegen eval --json` for the same inputs, and bad input as DancegenError in the CLI's words.

Run: pytest crates/dancegen-py/tests (after `maturin develop` or `pip install ./crates/dancegen-py`),
with DANCEGEN_BIN naming the dancegen binary to compare with (default: dancegen on PATH).
"""

import json
import os
import shutil
import subprocess
import wave
from pathlib import Path

import numpy as np
import pytest

import dancegen

ROOT = Path(__file__).resolve().parents[3]
SHARED = ROOT.parent / "shared"
SONG = SHARED / "data" / "music" / "sectoid" / "feelings.ogg"
DEMO = ROOT / "assets" / "demo_metal_madness_45s.ogg"
BIN = os.environ.get("DANCEGEN_BIN") or shutil.which("dancegen")


def cli(*args):
    if not BIN:
        pytest.skip("no dancegen binary (set DANCEGEN_BIN)")
    out = subprocess.run([BIN, *map(str, args)], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    return out


def test_features_are_the_clis(tmp_path):
    npy = tmp_path / "f.npy"
    cli("features", DEMO, "-o", npy)
    want = np.load(npy)
    got = dancegen.features(DEMO)
    assert got.dtype == np.float32 and got.flags.c_contiguous
    assert got.shape == want.shape == (want.shape[0], 35)
    np.testing.assert_array_equal(got, want)


def test_samples_in_an_array_are_read_as_a_file_of_them(tmp_path):
    rate = 22050
    t = np.arange(rate * 4) / rate
    clicks = (np.sin(2 * np.pi * 440 * t) * (np.mod(t, 0.5) < 0.05)).astype(np.float32)
    path = tmp_path / "clicks.wav"
    with wave.open(str(path), "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(rate)
        w.writeframes((clicks * 32767).astype("<i2").tobytes())
    pcm16 = (clicks * 32767).astype("<i2").astype(np.float32) / 32768.0
    from_array = dancegen.features(pcm16, sample_rate=rate)
    from_file = dancegen.features(path)
    np.testing.assert_allclose(from_array, from_file, atol=1e-4)
    b = dancegen.beats(pcm16, sample_rate=rate)
    assert set(b) >= {"tempo_bpm", "beat_times", "onset_times"}


def joints(path, phase):
    frames = 90
    t = np.arange(frames)[:, None] / 30.0
    j = np.arange(24)[None, :]
    sway = 0.1 * np.sin(2 * np.pi * (t + phase) + 0.3 * j)
    a = np.stack([sway, 1.0 + 0.02 * j + 0 * t, 0.05 * j * sway], axis=-1).astype(np.float32)
    np.save(path, a)
    return path


def test_evaluate_is_eval_json(tmp_path):
    pred, gt = tmp_path / "pred", tmp_path / "gt"
    pred.mkdir()
    gt.mkdir()
    for k, ph in enumerate([0.0, 0.3]):
        joints(pred / f"p{k}.npy", ph)
    for k, ph in enumerate([0.1, 0.6]):
        joints(gt / f"g{k}.npy", ph)
    out = tmp_path / "eval.json"
    cli("eval", "--pred", pred, "--gt", gt, "--fps", "30", "--metrics",
        "fid_k,div_k,pfc,physical", "--json", out)
    want = json.loads(out.read_text())
    got = dancegen.evaluate(pred, gt, fps=30, metrics=["fid_k", "div_k", "pfc", "physical"])
    assert got == want


def test_bad_input_says_what_is_wrong(tmp_path):
    with pytest.raises(dancegen.DancegenError, match="nowhere.ogg"):
        dancegen.features(tmp_path / "nowhere.ogg")
    with pytest.raises(dancegen.DancegenError, match="sample_rate"):
        dancegen.features(np.zeros(100, np.float32))
    with pytest.raises(dancegen.DancegenError, match="1-D float32"):
        dancegen.features(np.zeros((2, 100), np.float32), sample_rate=22050)
    with pytest.raises(dancegen.DancegenError, match="protocol 'paper'"):
        dancegen.evaluate(tmp_path, protocol="paper")
    with pytest.raises(dancegen.DancegenError, match="--gt"):
        dancegen.evaluate(joints(tmp_path / "a.npy", 0.0), fps=30, metrics="fid_k")
