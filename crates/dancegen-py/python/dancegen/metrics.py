"""The metrics of `dancegen eval`, one function each, on arrays, files or folders.

Each function runs `dancegen eval --metrics NAME` on its inputs (`dancegen.evaluate`) and
returns the set value: the mean over the clips where the metric is defined, `None` where it is
defined for none. Clips are given as in `dancegen.evaluate`: a path, an array of joint positions
(`(T, J, 3)` metres Y-up, a group scene `(N, T, J, 3)`), a list of them or a dict of named
arrays. `protocol` and `fps` are `dancegen eval`'s (`--protocol`, `--fps`); arrays store no
frame rate, so give `fps` unless the protocol fixes one.

Formulas, their references and their known reference bugs: `crates/dancegen-metrics` and
`../shared/reference/anchors.md` section A.
"""

from typing import Any, Dict, Optional, Sequence, Union

from ._inputs import Clips, PathLike

__all__ = [
    "bas", "bed", "boundary_jerk", "collision", "contact_range", "div_cd", "div_g", "div_k",
    "fid_cd", "fid_g", "fid_k", "freeze", "fsd", "fsr", "gmc", "gmr", "inverted", "ipr",
    "min_distance", "mpjpe", "penetration", "pfc", "physical", "tif",
]

# The physical-plausibility figures `dancegen eval --metrics physical` reports.
PHYSICAL = (
    "floor_median", "floor_p05", "floor_p95", "float", "foot_slide", "jerk", "jerk_p99",
    "max_step", "spikes", "leg_cross", "lean", "joint_speed", "pelvis_speed", "step_rate",
)


def _one(name: str, pred: Clips, **kw: Any) -> Optional[float]:
    from . import evaluate

    return evaluate(pred, metrics=[name], **kw).get(name)


def fid_k(pred: Clips, gt: Clips, *, protocol: str = "none", fps: Optional[float] = None
          ) -> Optional[float]:
    """FID on kinetic features (Bailando's normalisation by the GT statistics)."""
    return _one("fid_k", pred, gt=gt, protocol=protocol, fps=fps)


def fid_g(pred: Clips, gt: Clips, *, protocol: str = "none", fps: Optional[float] = None
          ) -> Optional[float]:
    """FID on geometric (manual) features."""
    return _one("fid_g", pred, gt=gt, protocol=protocol, fps=fps)


def div_k(pred: Clips, gt: Optional[Clips] = None, *, protocol: str = "none",
          fps: Optional[float] = None) -> Optional[float]:
    """Diversity of kinetic features (normalised by the GT statistics when `gt` is given)."""
    return _one("div_k", pred, gt=gt, protocol=protocol, fps=fps)


def div_g(pred: Clips, gt: Optional[Clips] = None, *, protocol: str = "none",
          fps: Optional[float] = None) -> Optional[float]:
    """Diversity of geometric features (normalised by the GT statistics when `gt` is given)."""
    return _one("div_g", pred, gt=gt, protocol=protocol, fps=fps)


def bas(pred: Clips, *, music: Optional[PathLike] = None,
        beats: Union[None, PathLike, Sequence[int]] = None, variant: str = "bailando",
        protocol: str = "none", fps: Optional[float] = None) -> Optional[float]:
    """Beat-align score. `variant`: bailando, lodge, fact or gcd (`--bas-variant`). Music beats
    from `beats` (beat frames, or a `.npy` of them) or found in `music`."""
    return _one("bas", pred, music=music, beats=beats, bas_variant=variant, protocol=protocol,
                fps=fps)


def pfc(pred: Clips, *, protocol: str = "none", fps: Optional[float] = None) -> Optional[float]:
    """EDGE's physical foot contact score, ×10⁴ as EDGE prints it."""
    return _one("pfc", pred, protocol=protocol, fps=fps)


def fsr(pred: Clips, *, protocol: str = "none", fps: Optional[float] = None) -> Optional[float]:
    """LODGE's foot-skating ratio."""
    return _one("fsr", pred, protocol=protocol, fps=fps)


def fsd(pred: Clips, *, protocol: str = "none", fps: Optional[float] = None) -> Optional[float]:
    """Duolando's foot-skating duration, percent of frame steps."""
    return _one("fsd", pred, protocol=protocol, fps=fps)


def mpjpe(pred: Clips, gt: Clips, *, protocol: str = "none", fps: Optional[float] = None
          ) -> Optional[float]:
    """Mean per-joint position error against the `gt` clip of the same name, metres."""
    return _one("mpjpe", pred, gt=gt, protocol=protocol, fps=fps)


def penetration(pred: Clips, *, protocol: str = "none", fps: Optional[float] = None
                ) -> Optional[float]:
    """Percent of forearm/hand samples inside another body part (capsule body)."""
    return _one("penetration", pred, protocol=protocol, fps=fps)


def freeze(pred: Clips, *, protocol: str = "none", fps: Optional[float] = None
           ) -> Optional[float]:
    """Share of the dance standing still (dancegen's long-form figure)."""
    return _one("freeze", pred, protocol=protocol, fps=fps)


def inverted(pred: Clips, *, protocol: str = "none", fps: Optional[float] = None
             ) -> Optional[float]:
    """Share of upside-down frames."""
    return _one("inverted", pred, protocol=protocol, fps=fps)


def boundary_jerk(pred: Clips, *, window: int = 150, protocol: str = "none",
                  fps: Optional[float] = None) -> Optional[float]:
    """Jerk at the boundaries every `window` frames over the jerk elsewhere."""
    return _one("boundary_jerk", pred, window=window, protocol=protocol, fps=fps)


def gmr(pred: Clips, gt: Clips, *, fps: Optional[float] = None) -> Optional[float]:
    """GCD's group motion realism (group scenes in both)."""
    return _one("gmr", pred, gt=gt, fps=fps)


def gmc(pred: Clips, *, fps: Optional[float] = None) -> Optional[float]:
    """GCD's group motion correlation (group scenes)."""
    return _one("gmc", pred, fps=fps)


def tif(pred: Clips, *, fps: Optional[float] = None) -> Optional[float]:
    """Trajectory intersection frequency (group scenes)."""
    return _one("tif", pred, fps=fps)


def collision(pred: Clips, *, fps: Optional[float] = None) -> Optional[float]:
    """Share of frames with two dancers' bodies intersecting (group scenes)."""
    return _one("collision", pred, fps=fps)


def min_distance(pred: Clips, *, fps: Optional[float] = None) -> Optional[float]:
    """Smallest distance between two dancers' bodies, metres (group scenes)."""
    return _one("min_distance", pred, fps=fps)


def fid_cd(pred: Clips, leader: Clips, gt: Clips, gt_leader: Optional[Clips] = None, *,
           fps: Optional[float] = None) -> Optional[float]:
    """Duolando's FID on the cross-distance features of follower and leader."""
    return _one("fid_cd", pred, leader=leader, gt=gt, gt_leader=gt_leader, fps=fps)


def div_cd(pred: Clips, leader: Clips, gt: Optional[Clips] = None,
           gt_leader: Optional[Clips] = None, *, fps: Optional[float] = None
           ) -> Optional[float]:
    """Duolando's diversity of cross-distance features (normalised by the GT statistics when
    `gt` duets are given)."""
    return _one("div_cd", pred, leader=leader, gt=gt, gt_leader=gt_leader, fps=fps)


def bed(pred: Clips, leader: Clips, *, fps: Optional[float] = None) -> Optional[float]:
    """Duolando's beat echo degree of follower and leader."""
    return _one("bed", pred, leader=leader, fps=fps)


def ipr(pred: Clips, leader: Clips, *, fps: Optional[float] = None) -> Optional[float]:
    """Share of frames in which the two capsule bodies intersect."""
    return _one("ipr", pred, leader=leader, fps=fps)


def contact_range(pred: Clips, leader: Clips, *, fps: Optional[float] = None
                  ) -> Optional[float]:
    """Share of frames in which the two are within touching range."""
    return _one("contact_range", pred, leader=leader, fps=fps)


def physical(pred: Clips, *, protocol: str = "none", fps: Optional[float] = None
             ) -> Dict[str, Optional[float]]:
    """The physical-plausibility figures (feet on the floor, jerk, foot sliding, joint speed,
    step rate, ...), each the mean over the clips, by name (`PHYSICAL`)."""
    from . import evaluate

    report = evaluate(pred, metrics="physical", protocol=protocol, fps=fps)
    return {k: report.get(k) for k in PHYSICAL}
