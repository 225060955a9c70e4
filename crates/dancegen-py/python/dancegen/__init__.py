"""dancegen from Python: music features identical to librosa's pipelines, dance metrics
computed exactly as the reference code computes them, every motion format, and the four dance
generators, numpy in and out.

    import dancegen
    feats = dancegen.features("song.ogg")            # (T, 35) float32, EDGE's 30 fps features
    report = dancegen.evaluate(pred="generated/", gt="real/", protocol="aistpp-bailando")
    dance = dancegen.generate("song.ogg", seed=3)    # dance.joints: (T, 24, 3), 30 fps
    dance.save("dance.glb")

Every function mirrors a `dancegen` command and takes its flags as keywords (`--bas-variant`
is `bas_variant=`); errors are `DancegenError` with the command's words.
"""

import json as _json
import os as _os
from typing import Any, Dict, Optional, Sequence, Union

from . import _dancegen, io, metrics
from ._dancegen import Dance, DancegenError, beats, features
from ._inputs import Clips, PathLike, clips as _clips

__all__ = [
    "Dance",
    "DancegenError",
    "beats",
    "evaluate",
    "features",
    "generate",
    "io",
    "metrics",
]


def evaluate(
    pred: Clips,
    gt: Optional[Clips] = None,
    *,
    leader: Optional[Clips] = None,
    gt_leader: Optional[Clips] = None,
    protocol: str = "none",
    fps: Optional[float] = None,
    source_fps: Optional[float] = None,
    metrics: Union[None, str, Sequence[str]] = None,
    music: Optional[PathLike] = None,
    beats: Union[None, PathLike, Sequence[int]] = None,
    bas_variant: str = "bailando",
    window: int = 150,
    gt_genres: Optional[PathLike] = None,
    want_genre: Optional[str] = None,
    genre_min_clips: int = 1,
) -> Dict[str, Any]:
    """`dancegen eval` as a function: the same dict as `dancegen eval --json`.

    `pred`, `gt`, `leader`, `gt_leader`: a folder, a file, an array of joint positions
    (`(T, J, 3)` metres Y-up, or a group scene `(N, T, J, 3)`), a list of them, or a dict of
    named arrays. Arrays are read as a `.npy` of the same values would be; clips pair by name
    (file stem, dict key, or list position). Arrays and `.npy` files store no frame rate: give
    `fps` unless the protocol fixes one. `metrics`: a list of names or a comma-separated
    string (`"physical"` and `"all"` as in the CLI; default: every metric the inputs allow).
    `beats`: a `.npy` of beat frames, or the beat frames themselves; `music`: a song whose
    beats are found.
    """
    if metrics is not None and not isinstance(metrics, str):
        metrics = ",".join(metrics)
    if beats is not None and not isinstance(beats, (str, _os.PathLike)):
        beats = [int(b) for b in beats]
    text = _dancegen.evaluate_json(
        _clips(pred, "pred"),
        _clips(gt, "gt"),
        _clips(leader, "leader"),
        _clips(gt_leader, "gt_leader"),
        protocol,
        fps,
        source_fps,
        metrics,
        None if music is None else _os.fspath(music),
        None if beats is None else (beats if isinstance(beats, list) else _os.fspath(beats)),
        bas_variant,
        window,
        None if gt_genres is None else _os.fspath(gt_genres),
        want_genre,
        genre_min_clips,
    )
    return _json.loads(text)


def generate(
    song: Optional[PathLike] = None,
    system: Optional[str] = None,
    seed: int = 0,
    **options: Any,
) -> Dance:
    """`dancegen generate` as a function: a `Dance` (write it with `Dance.save(path)`).

    `song`: the song file (default: the bundled demo song). `system`: "solo" (default),
    "duet" (default with `leader=`), "group" (with `dancers=N`) or "holistic". `options` are
    `generate`'s flags by their long names with underscores (`start=10, end=40, steps=20,
    leader="lead.npz", no_foot_lock=True, regenerate=["8-12"]`); `True`/`False` for switches,
    a list for a repeatable flag. The output flags (`rig`, `character`, `video_size`,
    `follower_only`) are `Dance.save`'s. Models are found as the CLI finds them
    (`dancegen models` lists the search path). For the same song, options and seed, the files
    `Dance.save` writes are the ones `dancegen generate -o` writes, byte for byte.
    """
    named: Dict[str, Any] = {}
    for key, value in options.items():
        if isinstance(value, _os.PathLike):
            value = _os.fspath(value)
        elif isinstance(value, (list, tuple)):
            value = [_os.fspath(v) if isinstance(v, _os.PathLike) else v for v in value]
        named[key] = value
    if song is not None:
        named["song"] = _os.fspath(song)
    if system is not None:
        named["system"] = system
    named["seed"] = seed
    return _dancegen.generate_named(_json.dumps(named))
