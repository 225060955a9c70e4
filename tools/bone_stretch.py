#!/usr/bin/env python3
"""How much real and generated joints stretch their bones: the evidence behind
`MAX_BONE_STRETCH_M` (crates/dancegen-motion/src/body_bounds.rs).

For every joint array (T, J, 3) / (N, T, J, 3) with J in {22, 24} (SMPL order, metres) under
the shared fixtures, and every AIST++ keypoints3d pickle (COCO 17, triangulated from video,
centimetres), prints the largest difference of a bone's length in one frame from its median
over the clip, worst first.

    python3 tools/bone_stretch.py [SHARED_DIR]      (default ../shared; needs numpy)
"""
import glob
import pickle
import sys

import numpy as np

SMPL24_PARENTS = [-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21]
COCO_BONES = [(5, 7), (7, 9), (6, 8), (8, 10), (11, 13), (13, 15), (12, 14), (14, 16),
              (5, 6), (11, 12), (5, 11), (6, 12)]


def worst_stretch(x, bones):
    """Largest |length - median length| over the bones of one dancer (T, J, 3), metres."""
    worst = 0.0
    for a, b in bones:
        lengths = np.linalg.norm(x[:, a] - x[:, b], axis=-1)
        lengths = lengths[np.isfinite(lengths)]
        if lengths.size:
            worst = max(worst, float(np.abs(lengths - np.median(lengths)).max()))
    return worst


def main():
    shared = sys.argv[1] if len(sys.argv) > 1 else "../shared"
    rows = []
    for f in sorted(glob.glob(f"{shared}/fixtures/**/*.npy", recursive=True)):
        try:
            a = np.load(f)
        except ValueError:
            continue
        if a.ndim == 3 and a.shape[2] == 3 and a.shape[1] in (22, 24):
            dancers = [a]
        elif a.ndim == 4 and a.shape[3] == 3 and a.shape[2] in (22, 24):
            dancers = list(a)
        else:
            continue
        j = dancers[0].shape[1]
        bones = [(k, SMPL24_PARENTS[k]) for k in range(1, j)]
        rows.append((max(worst_stretch(d, bones) for d in dancers), f))
    for f in sorted(glob.glob(f"{shared}/data/aistpp/keypoints3d/*.pkl")):
        with open(f, "rb") as fh:
            d = pickle.load(fh)
        k = d.get("keypoints3d_optim", d.get("keypoints3d")) / 100.0
        rows.append((worst_stretch(k, COCO_BONES), f))
    rows.sort(reverse=True)
    for stretch, f in rows:
        print(f"{stretch:.3f} m  {f}")
    print(f"{len(rows)} files; the largest stretch is {rows[0][0]:.3f} m")


if __name__ == "__main__":
    main()
