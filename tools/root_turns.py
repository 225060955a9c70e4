#!/usr/bin/env python3
"""How each dancer's body turns and tilts, from world joints (Y-up, metres, SMPL-24 order):
solo `(T, 24, 3)` or group `(N, T, 24, 3)` .npy files (`dancegen generate`, `dancegen convert`).

Per dancer, the heading is the angle of the hip axis (right hip -> left hip) in the floor plane,
unwrapped; the tilt is the angle between the pelvis -> spine1 segment and the vertical.
- turn deg/s: the heading's total absolute change per second (every turn, either way);
- range deg: the unwrapped heading's largest minus smallest value. A dancer who spins keeps
  adding to it; one who only twists back and forth stays within a few tens of degrees;
- heading d2, tilt d2 (deg): RMS of the second frame difference of each, the frame-to-frame
  jitter of the body's orientation;
- min up: the smallest vertical component of the unit pelvis -> spine1 segment (1 upright,
  0 lying, < 0 upside down);
- spread cm: the pose spread of docs/group-eval.md (mean distance of the pelvis-relative joints
  from their own mean, in world axes, so turning counts); facing cm: the same with every frame
  turned about the vertical to face one way (by the hip axis), the body's own motion.

The last line averages every dancer of every file: spread, facing, and the median range.

Written for issue 43 (docs/group-collapse.md §21), to tell a jitter of the heading from one of
the tilt, which the physical figures (`dancegen eval --metrics physical`) do not separate.

    python3 tools/root_turns.py [--fps 30] FILE.npy...

Standard library only (3.11+).
"""

import math
import os
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from solo_eval import read_npy  # noqa: E402

L_HIP, R_HIP, PELVIS, SPINE1 = 1, 2, 0, 3


def unwrap(angles):
    """Radians with each step taken the short way round."""
    out = [angles[0]]
    for a in angles[1:]:
        d = (a - out[-1] + math.pi) % math.tau - math.pi
        out.append(out[-1] + d)
    return out


def rms_second_difference(v):
    d2 = [v[i + 2] - 2 * v[i + 1] + v[i] for i in range(len(v) - 2)]
    return math.sqrt(statistics.fmean(x * x for x in d2)) if d2 else 0.0


def dancer_figures(flat, t, fps):
    """(turn deg/s, range deg, heading d2 deg, tilt d2 deg, min up, spread cm, facing cm) of
    one dancer."""
    def joint(f, j):
        i = f * 72 + 3 * j
        return flat[i], flat[i + 1], flat[i + 2]

    heading, tilt, up = [], [], []
    for f in range(t):
        (lx, _, lz), (rx, _, rz) = joint(f, L_HIP), joint(f, R_HIP)
        heading.append(math.atan2(lz - rz, lx - rx))
        (px, py, pz), (sx, sy, sz) = joint(f, PELVIS), joint(f, SPINE1)
        n = math.dist((px, py, pz), (sx, sy, sz)) or 1.0
        u = (sy - py) / n
        up.append(u)
        tilt.append(math.acos(max(-1.0, min(1.0, u))))
    h = unwrap(heading)
    turning = sum(abs(b - a) for a, b in zip(h, h[1:])) / (t / fps)
    world, facing = [], []
    for f in range(t):
        p = joint(f, PELVIS)
        c, s = math.cos(-heading[f]), math.sin(-heading[f])
        rel = [tuple(v - o for v, o in zip(joint(f, j), p)) for j in range(24)]
        world.append(rel)
        facing.append([(x * c - z * s, y, x * s + z * c) for x, y, z in rel])
    return (math.degrees(turning), math.degrees(max(h) - min(h)),
            math.degrees(rms_second_difference(h)), math.degrees(rms_second_difference(tilt)),
            min(up), spread_cm(world), spread_cm(facing))


def spread_cm(frames):
    """Mean distance (cm) of each joint from its own mean over the frames."""
    t = len(frames)
    means = [tuple(statistics.fmean(fr[j][c] for fr in frames) for c in range(3))
             for j in range(24)]
    return 100.0 * statistics.fmean(math.dist(fr[j], means[j]) for fr in frames
                                    for j in range(24)) if t else 0.0


def main(args):
    fps = 30.0
    if args[:1] == ["--fps"]:
        if len(args) < 2:
            raise SystemExit(__doc__)
        fps, args = float(args[1]), args[2:]
    if not args:
        raise SystemExit(__doc__)
    every = []
    for path in args:
        shape, a = read_npy(path)
        if len(shape) == 3:
            shape = (1,) + tuple(shape)
        if len(shape) != 4 or tuple(shape[2:]) != (24, 3) or shape[1] < 3:
            raise SystemExit(f"{path}: expected world joints (T, 24, 3) or (N, T, 24, 3) with T >= 3, "
                             f"got {shape}")
        n, t = shape[0], shape[1]
        rows = [dancer_figures(a[k * t * 72:(k + 1) * t * 72], t, fps) for k in range(n)]
        every += rows
        cols = list(zip(*rows))
        fmt = lambda vals, p: " ".join(f"{v:.{p}f}" for v in vals)  # noqa: E731
        print(f"{path}: turn deg/s {fmt(cols[0], 0)} | range deg {fmt(cols[1], 0)} | "
              f"heading d2 deg {fmt(cols[2], 2)} | tilt d2 deg {fmt(cols[3], 2)} | "
              f"min up {fmt(cols[4], 2)} | spread cm {fmt(cols[5], 1)} | facing cm {fmt(cols[6], 1)}")
    cols = list(zip(*every))
    print(f"{len(every)} dancers: spread cm {statistics.fmean(cols[5]):.2f}, facing one way "
          f"{statistics.fmean(cols[6]):.2f}, range deg median {statistics.median(cols[1]):.0f}")


if __name__ == "__main__":
    main(sys.argv[1:])
