"""examples/python/score_folder.py, the README's example, run as a user runs it on the golden
set: its table shows the reference implementations' FID and Div values."""

import json
import shutil
import subprocess
import sys

from conftest import METRICS, ROOT

EXAMPLE = ROOT / "examples" / "python" / "score_folder.py"


def test_the_example_prints_the_papers_table(tmp_path):
    for sub, to in (("generated", "gen"), ("real", "real")):
        (tmp_path / to).mkdir()
        for p in (METRICS / "inputs" / sub).glob("*_yup_60fps.npy"):
            shutil.copy(p, tmp_path / to / p.name)
    beats = METRICS / "outputs" / "bas" / "music_beats_real_freezingpoint_fps60.npy"
    out = subprocess.run(
        [sys.executable, EXAMPLE, tmp_path / "gen", tmp_path / "real", "--protocol",
         "aistpp-bailando", "--fps", "60", "--beats", beats, "--json", tmp_path / "r.json"],
        capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    header = lines[1].split()
    assert header == ["FID_k", "FID_g", "Div_k", "Div_g", "BAS", "PFC"]
    generated = dict(zip(header, lines[3].split()[1:]))
    golden = json.loads((METRICS / "outputs" / "fid_bailando_60fps" / "metrics.json").read_text())
    for column, key in (("FID_k", "fid_k"), ("FID_g", "fid_m"), ("Div_k", "div_k"),
                        ("Div_g", "div_m")):
        want = golden[key]["real"]
        # Printed to 4 decimals; the values agree to 1e-6 relative (tests/test_metrics.py).
        assert abs(float(generated[column]) - want) <= 5e-5 + 1e-6 * abs(want), column
    report = json.loads((tmp_path / "r.json").read_text())
    assert len(report["generated"]["per_clip"]) == 8
    assert lines[2].split()[:2] == ["Ground", "truth"] and "jerk" in out.stdout
