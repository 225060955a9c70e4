"""The Python package's music analysis and `evaluate` against the CLI they mirror: the same
numbers as `dancegen features` and `dancegen eval --json` for the same inputs, features equal to
librosa's golden outputs within the CLI's tolerances, and bad input as DancegenError in the
CLI's words.

Run: pytest crates/dancegen-py/tests (after `maturin develop` or `pip install ./crates/dancegen-py`),
with DANCEGEN_BIN naming the dancegen binary to compare with (default: dancegen on PATH).
"""

import json
import wave

import numpy as np
import pytest

import dancegen
from conftest import DEMO, MUSIC, cli


def ref_cases():
    """Every (clip, fps) of the librosa 0.11 golden features (`fixtures/music/ref`)."""
    out = []
    for key_dir in sorted((MUSIC / "ref").iterdir()):
        if key_dir.name.startswith("_") or not key_dir.is_dir():
            continue
        for fps in (30, 60):
            if (key_dir / f"fps{fps}").is_dir():
                out.append((key_dir.name, fps))
    return out


def clip_for_key(key):
    for suffix, ext in (("_ogg", "ogg"), ("_mp3", "mp3")):
        if key.endswith(suffix):
            return MUSIC / "clips" / f"{key[:-len(suffix)]}.{ext}"
    return MUSIC / "clips" / f"{key}.wav"


def agreement(got, want):
    """|A ∩ B| / max(|A|, |B|): the share of frames both mark, extras penalised."""
    got, want = set(np.flatnonzero(got > 0.5)), set(np.flatnonzero(want > 0.5))
    return 1.0 if not (got or want) else len(got & want) / max(len(got), len(want))


@pytest.mark.parametrize("key,fps", ref_cases())
def test_features_equal_librosa_within_the_cli_tolerances(key, fps):
    """The tolerances of crates/dancegen-music/tests/features35.rs, which says why each is."""
    ref = MUSIC / "ref" / key / f"fps{fps}"
    want = np.load(ref / "feats35.npy").astype(np.float32)
    meta = json.loads((ref / "meta.json").read_text())
    got = dancegen.features(clip_for_key(key), fps=fps)
    assert got.shape == want.shape
    env_max = max(float(want[:, 0].max()), 1e-6)
    assert np.abs(got[:, 0] - want[:, 0]).max() <= 1e-3 * env_max, "onset envelope"
    assert np.abs(got[:, 1:21] - want[:, 1:21]).max() < 0.01, "mfcc"
    assert np.abs(got[:, 21:33] - want[:, 21:33]).max() < 1e-3, "chroma_cens"
    assert agreement(got[:, 33], want[:, 33]) >= 0.98, "onset peaks"
    assert agreement(got[:, 34], want[:, 34]) >= 0.98, "beats"
    assert dancegen.beats(clip_for_key(key), fps=fps)["tempo_bpm"] == meta["tempo"]


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
