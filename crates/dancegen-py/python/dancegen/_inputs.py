"""How the Python API's clip arguments become `dancegen eval`'s inputs (private)."""

import os
from typing import Any, List, Mapping, Sequence, Tuple, Union

import numpy as np

PathLike = Union[str, "os.PathLike[str]"]
# One clip: a path (file or folder), or joint positions (T, J, 3) / (N, T, J, 3).
Clip = Union[PathLike, np.ndarray]
# Clips: one clip, a list of clips, or a mapping of names to arrays.
Clips = Union[Clip, Sequence[Clip], Mapping[str, np.ndarray]]


def is_path(x: Any) -> bool:
    return isinstance(x, (str, os.PathLike))


def clips(x: Any, what: str) -> List[Union[str, Tuple[str, np.ndarray]]]:
    """Paths as strings and arrays as `(name, array)` pairs.

    A list's arrays are named by position (`"0000"`, `"0001"`, ...), so that two lists pair
    clip by clip as files of the same stem do (`mpjpe`, duet leaders); a mapping names them
    itself; a single array is `"0000"`.
    """
    if x is None:
        return []
    if is_path(x):
        return [os.fspath(x)]
    if isinstance(x, np.ndarray):
        return [("0000", x)]
    if isinstance(x, Mapping):
        out = []
        for name, a in x.items():
            if not isinstance(a, np.ndarray):
                raise TypeError(f"{what}[{name!r}]: expected a numpy array, got {type(a).__name__}")
            out.append((str(name), a))
        return out
    if isinstance(x, (list, tuple)):
        out = []
        for i, item in enumerate(x):
            if is_path(item):
                out.append(os.fspath(item))
            elif isinstance(item, np.ndarray):
                out.append((f"{i:04d}", item))
            else:
                raise TypeError(
                    f"{what}[{i}]: expected a path or a numpy array, got {type(item).__name__}")
        return out
    raise TypeError(
        f"{what}: expected a path, a numpy array, a list of them or a dict of arrays, "
        f"got {type(x).__name__}")
