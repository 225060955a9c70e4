#!/usr/bin/env python3
"""How much two seeds of one leader differ (issue 41's duet target), from a duet eval run.

    /usr/bin/python3 tools/duet_seed_spread.py target/duet-eval [SEED_A SEED_B]

For every held-out clip, the mean distance between the root-relative joints of the followers
generated with SEED_A and SEED_B (default 0 and 1; `OUT/gen/full/seed<N>/<clip>.npy`, world
joints (T, 24, 3)), against the real held-out followers' pose spread: the mean distance of
their root-relative joints to their mean pose (`OUT/gt/*.npy`). The target is a seed
difference of at least half that spread. Needs numpy.
"""
import glob
import os
import sys

import numpy as np


def rel(j):
    return j - j[:, :1, :]


def main():
    if len(sys.argv) not in (2, 4) or not os.path.isdir(sys.argv[1]):
        sys.exit(__doc__.split("\n\n")[1].strip() + "\n(OUT: a tools/duet_eval.sh output directory)")
    out = sys.argv[1]
    a, b = (sys.argv[2], sys.argv[3]) if len(sys.argv) > 3 else ("0", "1")
    diffs = []
    for f in sorted(glob.glob(f"{out}/gen/full/seed{a}/*.npy")):
        clip = os.path.basename(f)
        other = f"{out}/gen/full/seed{b}/{clip}"
        if not os.path.exists(other):
            continue
        x, y = rel(np.load(f)), rel(np.load(other))
        n = min(len(x), len(y))
        d = float(np.linalg.norm(x[:n] - y[:n], axis=2).mean())
        diffs.append(d)
        print(f"{clip}: seeds {a} and {b} differ by {d:.3f} m")
    real = [rel(np.load(f)) for f in sorted(glob.glob(f"{out}/gt/*.npy"))]
    if not diffs or not real:
        sys.exit(f"{out}: no generated pairs or no real followers")
    poses = np.concatenate(real)
    spread = float(np.linalg.norm(poses - poses.mean(0), axis=2).mean())
    mean = float(np.mean(diffs))
    verdict = "met" if mean >= spread / 2 else "not met"
    print(f"mean seed difference {mean:.3f} m; real pose spread {spread:.3f} m, half {spread / 2:.3f}: {verdict}")


if __name__ == "__main__":
    main()
