"""Shared helpers of the Python package's tests: the paths of the checkout and its shared data,
and the `dancegen` binary the package is compared with (DANCEGEN_BIN, else dancegen on PATH).
Models: the checkout's `models/` (DANCEGEN_MODEL_DIR, for the package and the binary alike)."""

import os
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
SHARED = ROOT.parent / "shared"
METRICS = SHARED / "fixtures" / "metrics"
MUSIC = SHARED / "fixtures" / "music"
DEMO = ROOT / "assets" / "demo_metal_madness_45s.ogg"
BIN = os.environ.get("DANCEGEN_BIN") or shutil.which("dancegen")

os.environ.setdefault("DANCEGEN_MODEL_DIR", str(ROOT / "models"))


def cli(*args):
    """Runs `dancegen ARGS`; fails the test with its stderr unless it succeeds."""
    if not BIN:
        pytest.skip("no dancegen binary (set DANCEGEN_BIN)")
    out = subprocess.run([BIN, *map(str, args)], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    return out
