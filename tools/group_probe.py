#!/usr/bin/env python3
"""Quick figures of group dances (`dancegen generate --system group -o X.npy`, (N, T, 24, 3)):
per file, the root steps over 0.25 m in one frame and the largest, each dancer's pose spread,
its pose jumps (frames in which a joint moves more than 0.15 m relative to the pelvis: the leg
IK's throws measured in docs/group-collapse.md §22; real salsa has 2-8 in 1,000 frames, mostly
hands) and the closest pair of dancers; with two files (two seeds of one request), how much
they differ.
The measures are tools/group_eval.py's, so the figures match its report.

    python3 tools/group_probe.py seed0.npy [seed1.npy]

Standard library only (3.11+).
"""

import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from group_eval import TELEPORT_M, closest_pair_cm, pose_spread_cm, seed_difference_cm  # noqa: E402
from solo_eval import read_npy  # noqa: E402


def root_steps(flat, n, t):
    """Horizontal root moves between consecutive frames of every dancer (m)."""
    out = []
    for k in range(n):
        p = flat[k * t * 72:(k + 1) * t * 72]
        out += [math.dist((p[f * 72], p[f * 72 + 2]), (p[(f - 1) * 72], p[(f - 1) * 72 + 2]))
                for f in range(1, t)]
    return out


POSE_JUMP_M = 0.15


def pose_jumps(p, t):
    """Frames of one dancer's joints `p` (flat, t × 24 × 3) in which some joint moves more than
    POSE_JUMP_M relative to the pelvis since the frame before."""
    def rel(f, j):
        return [p[f * 72 + j * 3 + a] - p[f * 72 + a] for a in range(3)]
    return sum(
        any(math.dist(rel(f, j), rel(f - 1, j)) > POSE_JUMP_M for j in range(1, 24))
        for f in range(1, t))


def main(paths):
    if not 1 <= len(paths) <= 2:
        raise SystemExit(__doc__)
    for path in paths:
        shape, a = read_npy(path)
        if len(shape) != 4 or shape[2:] != (24, 3):
            raise SystemExit(f"{path}: expected a group .npy of shape (N, T, 24, 3), got {shape}")
        n, t = shape[0], shape[1]
        steps = root_steps(a, n, t)
        spread = [pose_spread_cm(a[k * t * 72:(k + 1) * t * 72], t) for k in range(n)]
        jumps = [pose_jumps(a[k * t * 72:(k + 1) * t * 72], t) for k in range(n)]
        print(f"{path}: {n} dancers x {t} frames; root steps > {TELEPORT_M} m: "
              f"{sum(s > TELEPORT_M for s in steps)} of {len(steps)} (largest {max(steps):.3f} m); "
              f"pose spread cm {' '.join(f'{s:.1f}' for s in spread)}; "
              f"pose jumps {' '.join(str(j) for j in jumps)}; "
              f"closest pair {closest_pair_cm(path):.1f} cm")
    if len(paths) == 2:
        print(f"seeds differ {seed_difference_cm(*paths):.2f} cm")


if __name__ == "__main__":
    main(sys.argv[1:])
