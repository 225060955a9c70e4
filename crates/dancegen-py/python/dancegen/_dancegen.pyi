"""Type stubs of dancegen's native module (crates/dancegen-py/src)."""

import os
import pathlib
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

_Path = Union[str, "os.PathLike[str]"]
_F32 = npt.NDArray[np.float32]
_Floats = Union[npt.NDArray[np.float32], npt.NDArray[np.float64]]

class DancegenError(Exception):
    """dancegen refused or failed; the message says why, in the CLI's words."""

def features(
    audio: Union[_Path, npt.NDArray[np.float32]],
    fps: int = 30,
    set: str = "edge35",
    start_bpm: Optional[float] = None,
    sample_rate: Optional[int] = None,
) -> _F32:
    """Music features `(T, D)` float32 at `fps` ("edge35": 35, "tcdiff438": 438), as
    `dancegen features`: from a path, or mono samples with their `sample_rate`."""

def beats(
    audio: Union[_Path, npt.NDArray[np.float32]],
    fps: int = 30,
    start_bpm: Optional[float] = None,
    sample_rate: Optional[int] = None,
) -> Dict[str, Any]:
    """`tempo_bpm`, `beat_times`, `onset_times` (seconds), `beat_frames`, `onset_frames`, as
    `dancegen beats`."""

def evaluate_json(
    pred: List[Union[str, Tuple[str, _Floats]]],
    gt: List[Union[str, Tuple[str, _Floats]]],
    leader: List[Union[str, Tuple[str, _Floats]]],
    gt_leader: List[Union[str, Tuple[str, _Floats]]],
    protocol: str,
    fps: Optional[float],
    source_fps: Optional[float],
    metrics: Optional[str],
    music: Optional[str],
    beats: Union[None, str, List[int]],
    bas_variant: str,
    window: int,
    gt_genres: Optional[str],
    want_genre: Optional[str],
    genre_min_clips: int,
) -> str:
    """`dancegen eval --json` as text (use `dancegen.evaluate`)."""

class Motion:
    """A motion as `dancegen convert` holds it: SMPL 24 rotations and root path (one dancer or
    a group), a BVH with its own skeleton, or joint positions only."""

    @property
    def fps(self) -> float: ...
    @property
    def kind(self) -> str:
        """"SMPL 24 motion", "group motion", "BVH motion" or "joint positions"."""
    @property
    def dancers(self) -> int: ...
    @property
    def joints(self) -> _F32:
        """World joint positions `(T, J, 3)` (`(N, T, J, 3)` for a group)."""
    @property
    def poses(self) -> Optional[_F32]:
        """SMPL axis-angle rotations `(T, 24, 3)` (`(N, T, 24, 3)`), or None."""
    @property
    def trans(self) -> Optional[_F32]:
        """SMPL pelvis path `(T, 3)` (`(N, T, 3)`), metres, Y-up, or None."""
    def convert(
        self, fps: Optional[float] = None, to: Optional[str] = None, dancer: Optional[int] = None
    ) -> "Motion":
        """The motion `dancegen convert` makes with `--fps`, `--to smpl24`, `--dancer`."""
    def save(
        self,
        path: _Path,
        rig: str = "smpl",
        npz_style: str = "amass",
        fps: Optional[float] = None,
        to: Optional[str] = None,
        dancer: Optional[int] = None,
    ) -> None:
        """Writes the motion as `dancegen convert` does (.bvh .glb .fbx .npz .npy .json)."""

def read(path: _Path, source_fps: Optional[float] = None) -> Motion:
    """Reads any motion `dancegen convert` reads."""

def smpl(poses: _Floats, trans: _Floats, fps: float = 30.0) -> Motion:
    """A motion from SMPL axis-angle `poses` `(T, 24, 3)`/`(T, 72)` and `trans` `(T, 3)`
    (a group: `(N, T, 24, 3)` and `(N, T, 3)`)."""

def joints(positions: _Floats, fps: float = 30.0) -> Motion:
    """A motion of joint positions only, `(T, J, 3)` or `(N, T, J, 3)`."""

def smpl_fk(poses: _Floats, trans: _Floats) -> _F32:
    """SMPL 24 forward kinematics: world joints `(T, 24, 3)` (`(N, T, 24, 3)`)."""

class Dance:
    """A generated dance (`dancegen.generate`)."""

    @property
    def joints(self) -> _F32:
        """World joint positions as the CLI's `.npy`: `(T, 24, 3)` ((T, 52, 3) holistic,
        (N, T, 24, 3) group, the follower of a duet)."""
    @property
    def fps(self) -> int: ...
    @property
    def system(self) -> str: ...
    @property
    def model(self) -> pathlib.Path: ...
    @property
    def span(self) -> Tuple[float, float]:
        """Seconds of the song danced to: (start, end)."""
    @property
    def dancers(self) -> int: ...
    @property
    def beat_times(self) -> List[float]: ...
    @property
    def tempo_bpm(self) -> float: ...
    @property
    def summary(self) -> str: ...
    @property
    def warnings(self) -> List[str]: ...
    @property
    def notes(self) -> List[str]: ...
    def save(
        self,
        path: _Path,
        rig: str = "smpl",
        character: Optional[_Path] = None,
        video_size: str = "640x480",
        follower_only: bool = False,
    ) -> List[pathlib.Path]:
        """Writes the dance in `path`'s format: the file `dancegen generate -o PATH` writes."""

def generate_named(options_json: str) -> Dance:
    """`dancegen generate` with its options by name (use `dancegen.generate`)."""
