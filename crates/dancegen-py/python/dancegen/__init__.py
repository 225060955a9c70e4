"""dancegen from Python: music features identical to librosa's pipelines, and dance metrics
computed exactly as the reference code computes them, numpy in and out.

    import dancegen
    feats = dancegen.features("song.ogg")            # (T, 35) float32, EDGE's 30 fps features
    report = dancegen.evaluate(pred="generated/", gt="real/", protocol="aistpp-bailando")
"""

import json as _json

from . import _dancegen
from ._dancegen import DancegenError, beats, features

__all__ = ["DancegenError", "beats", "evaluate", "features"]


def evaluate(pred, gt=None, *, leader=None, gt_leader=None, protocol="none", fps=None,
             source_fps=None, metrics=None, music=None, beats=None, bas_variant="bailando",
             window=150):
    """`dancegen eval` as a function: the same dict as `dancegen eval --json`.

    `pred`, `gt`, `leader`, `gt_leader`: a folder, a file, or a list of them. `metrics`: a list
    of names or a comma-separated string (`"physical"` and `"all"` as in the CLI).
    """
    def paths(x):
        if x is None:
            return []
        if isinstance(x, (str, bytes)) or hasattr(x, "__fspath__"):
            return [str(x)]
        return [str(p) for p in x]

    if metrics is not None and not isinstance(metrics, str):
        metrics = ",".join(metrics)
    text = _dancegen.evaluate_json(
        paths(pred), paths(gt), paths(leader), paths(gt_leader), protocol, fps, source_fps,
        metrics, None if music is None else str(music), None if beats is None else str(beats),
        bas_variant, window,
    )
    return _json.loads(text)
