#!/usr/bin/env python3
"""Builds the test set of bench/metrics.sh from real data only (deterministic, seeded).

    metrics_make_set.py --binary target/release/dancegen --data ../shared/data --out bench/.metrics-set

Sources, converted with our CLI to world joints (T, 24, 3) float32, Y-up, metres, 30 fps:
  - AIST++ `aistpp/motions/*.pkl` (3 takes; 288 / 288 / 960 frames at 30 fps):
        dancegen convert IN.pkl -o OUT.npy --fps 30
  - CMU salsa `cmu-salsa/{60,61}_KK_scaled.bvh` (13 takes KK x 2 partners, 300-644 frames each
    at 30 fps): dancegen convert IN.bvh -o OUT.npy --fps 30 --to smpl24
Raw conversions are cached in OUT/raw/.

Derived sets (all float32 .npy; every construction is listed in OUT/manifest.json):

solo/gt/clip_XX.npy, solo/pred/clip_XX.npy  (XX = 00..19), (1024, 24, 3):
  The "pool" is the 27 real sequences in a fixed order (salsa 60_01, 61_01, 60_02, 61_02, ...,
  then the 3 AIST++ takes). A clip is a concatenation of whole pool sequences (first one cut at an
  offset) until 1024 frames are reached, cut to 1024. Each appended segment is rigidly translated:
  horizontally so that its first-frame root (x, z) continues at the previous segment's last-frame
  root (x, z), vertically so that its lowest toe height (joints 10, 11, over the segment) is 0.
  gt clip i starts at pool[i] offset 0; pred clip i starts at pool[(i + 7) % 27] offset
  (37 * i) % 200, and gets a smooth seeded perturbation added to every joint coordinate:
  a * sin(2 pi f t / 30 + phi), a ~ U(0, 2 cm), f ~ U(0.1, 0.5) Hz, phi ~ U(0, 2 pi), drawn per
  (joint, axis) from numpy.random.default_rng(1000 + i). pred clip i and gt clip i share the file
  stem, which pairs them for MPJPE.

group/gt/scene_XX.npy, group/pred/scene_XX.npy  (N, 150, 24, 3), XX = 00..12 (take k = XX-th of the 13 takes):
  dancer 0 = 60_k, dancer 1 = 61_k (the two partners, original shared world frame); scenes with an
  even index get a third dancer = 60_{next take} moved by +2.5 m in x (N = 3), odd ones N = 2.
  gt = frames [0, 150) of the take, pred = frames [150, 300) (the shortest take, 10, has 300).

duet/{gt,pred}_{leader,follower}/pair_XX.npy  (100, 24, 3), XX = 00..19 (gt) and 00..18 (pred):
  leader = 60_k, follower = 61_k (which partner leads is undocumented; our choice). Each take gives
  3 windows of 100 frames starting at 0, 100, 200; going through takes 01..14 and their windows in
  order, windows alternate gt, pred, gt, ... (18 pairs each). Leader and follower of a pair are the
  same frames of the same take.

beats.npy: synthetic music beats (NOT from audio): int64 frame indices 0, 15, 30, ... < 1024,
  i.e. a fixed 120 BPM grid at 30 fps.

solo60/{gt,pred}/clip_XX.npy (1200, 24, 3) + beats60.npy (0, 30, 60, ... < 1200): the same solo
  construction from 60-fps conversions (`--fps 60`; AIST++ is native 60 fps, salsa 120 -> 60),
  1200 frames (Bailando's cut), pred offsets doubled ((2 * 37 * i) % 400 frames), perturbation
  with the same seeds and frequencies in Hz; for `--protocol aistpp-bailando`.
"""
import argparse
import json
import os
import subprocess
import sys

import numpy as np

T_SOLO = 1024
T_SOLO60 = 1200
N_SOLO = 20
T_GROUP = 150
T_DUET = 100
FPS = 30


def convert(binary, src, dst, bvh, fps=FPS):
    if os.path.exists(dst):
        return
    cmd = [binary, "-q", "convert", src, "-o", dst, "--fps", str(fps)]
    if bvh:
        cmd += ["--to", "smpl24"]
    subprocess.run(cmd, check=True)


def ground_and_continue(seg, prev_last_root):
    seg = seg.astype(np.float64).copy()
    seg[:, :, 1] -= seg[:, [10, 11], 1].min()
    if prev_last_root is not None:
        shift = prev_last_root[[0, 2]] - seg[0, 0, [0, 2]]
        seg[:, :, 0] += shift[0]
        seg[:, :, 2] += shift[1]
    return seg


def build_clip(pool, start, offset, length=T_SOLO):
    parts, have, k, prev = [], 0, start, None
    first = True
    while have < length:
        seg = pool[k % len(pool)]
        if first:
            seg = seg[offset:]
            first = False
        seg = ground_and_continue(seg, prev)
        parts.append(seg)
        have += len(seg)
        prev = seg[-1, 0]
        k += 1
    return np.concatenate(parts)[:length]


def perturb(clip, seed, fps=FPS):
    rng = np.random.default_rng(seed)
    a = rng.uniform(0.0, 0.02, size=(24, 3))
    f = rng.uniform(0.1, 0.5, size=(24, 3))
    phi = rng.uniform(0.0, 2 * np.pi, size=(24, 3))
    t = np.arange(len(clip), dtype=np.float64)[:, None, None]
    return clip + a * np.sin(2 * np.pi * f * t / fps + phi)


def save(path, arr):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    np.save(path, np.ascontiguousarray(arr, dtype=np.float32))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--binary", required=True)
    ap.add_argument("--data", required=True)
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    raw = os.path.join(args.out, "raw")
    os.makedirs(raw, exist_ok=True)

    takes = sorted(f[3:5] for f in os.listdir(os.path.join(args.data, "cmu-salsa")) if f.startswith("60_"))
    salsa = {}
    for k in takes:
        for who in ("60", "61"):
            src = os.path.join(args.data, "cmu-salsa", f"{who}_{k}_scaled.bvh")
            dst = os.path.join(raw, f"salsa_{who}_{k}.npy")
            convert(args.binary, src, dst, bvh=True)
            salsa[(who, k)] = np.load(dst)
    aist_dir = os.path.join(args.data, "aistpp", "motions")
    aist = []
    for f in sorted(os.listdir(aist_dir)):
        if f.endswith(".pkl"):
            dst = os.path.join(raw, "aist_" + f[:-4] + ".npy")
            convert(args.binary, os.path.join(aist_dir, f), dst, bvh=False)
            aist.append((f[:-4], np.load(dst)))

    pool_names, pool = [], []
    for k in takes:
        for who in ("60", "61"):
            pool_names.append(f"salsa_{who}_{k}")
            pool.append(salsa[(who, k)])
    for name, a in aist:
        pool_names.append("aist_" + name)
        pool.append(a)
    manifest = {"pool": pool_names, "pool_frames": [len(p) for p in pool], "solo": {}, "group": {}, "duet": {}}

    for i in range(N_SOLO):
        stem = f"clip_{i:02d}"
        gt = build_clip(pool, i, 0)
        p_start, p_off = (i + 7) % len(pool), (37 * i) % 200
        pred = perturb(build_clip(pool, p_start, p_off), 1000 + i)
        save(os.path.join(args.out, "solo", "gt", stem + ".npy"), gt)
        save(os.path.join(args.out, "solo", "pred", stem + ".npy"), pred)
        manifest["solo"][stem] = {"gt_start": pool_names[i % len(pool)], "pred_start": pool_names[p_start],
                                  "pred_offset": p_off, "pred_seed": 1000 + i}

    for s, k in enumerate(takes):
        nxt = takes[(s + 1) % len(takes)]
        for split, lo in (("gt", 0), ("pred", T_GROUP)):
            d0, d1 = salsa[("60", k)], salsa[("61", k)]
            assert len(d0) >= lo + T_GROUP, (k, len(d0))
            dancers = [d0[lo:lo + T_GROUP], d1[lo:lo + T_GROUP]]
            third = None
            if s % 2 == 0:
                d2 = salsa[("60", nxt)]
                assert len(d2) >= lo + T_GROUP
                third = d2[lo:lo + T_GROUP].astype(np.float64).copy()
                third[:, :, 0] += 2.5
                dancers.append(third)
            save(os.path.join(args.out, "group", split, f"scene_{s:02d}.npy"), np.stack(dancers))
        manifest["group"][f"scene_{s:02d}"] = {"take": k, "third": f"60_{nxt}" if s % 2 == 0 else None}

    pair = {"gt": 0, "pred": 0}
    n_win = 0
    for k in takes:
        lead, fol = salsa[("60", k)], salsa[("61", k)]
        for w in range(3):
            lo = w * T_DUET
            assert len(lead) >= lo + T_DUET
            split = "gt" if n_win % 2 == 0 else "pred"
            n_win += 1
            name = f"pair_{pair[split]:02d}"
            pair[split] += 1
            save(os.path.join(args.out, "duet", f"{split}_leader", name + ".npy"), lead[lo:lo + T_DUET])
            save(os.path.join(args.out, "duet", f"{split}_follower", name + ".npy"), fol[lo:lo + T_DUET])
            manifest["duet"][f"{split}/{name}"] = {"take": k, "start": lo}

    np.save(os.path.join(args.out, "beats.npy"), np.arange(0, T_SOLO, 15, dtype=np.int64))

    # 60-fps solo set for --protocol aistpp-bailando: same construction from 60-fps conversions,
    # 1200 frames, offsets doubled, beats every 30 frames (120 BPM at 60 fps).
    pool60 = []
    for name in pool_names:
        dst = os.path.join(raw, name + "_60fps.npy")
        if name.startswith("salsa_"):
            who, k = name.split("_")[1:]
            convert(args.binary, os.path.join(args.data, "cmu-salsa", f"{who}_{k}_scaled.bvh"), dst, True, 60)
        else:
            convert(args.binary, os.path.join(aist_dir, name[5:] + ".pkl"), dst, False, 60)
        pool60.append(np.load(dst))
    for i in range(N_SOLO):
        stem = f"clip_{i:02d}"
        gt = build_clip(pool60, i, 0, T_SOLO60)
        p_start, p_off = (i + 7) % len(pool60), 2 * ((37 * i) % 200)
        pred = perturb(build_clip(pool60, p_start, p_off, T_SOLO60), 1000 + i, 60)
        save(os.path.join(args.out, "solo60", "gt", stem + ".npy"), gt)
        save(os.path.join(args.out, "solo60", "pred", stem + ".npy"), pred)
    np.save(os.path.join(args.out, "beats60.npy"), np.arange(0, T_SOLO60, 30, dtype=np.int64))
    with open(os.path.join(args.out, "manifest.json"), "w") as f:
        json.dump(manifest, f, indent=1)
    print(f"set: {N_SOLO}+{N_SOLO} solo clips x {T_SOLO} frames, {len(takes)}+{len(takes)} group scenes x "
          f"{T_GROUP} frames (N = 2/3), {pair['gt']}+{pair['pred']} duet pairs x {T_DUET} frames; 60-fps solo set "
          f"{N_SOLO}+{N_SOLO} x {T_SOLO60} frames -> {args.out}",
          file=sys.stderr)


if __name__ == "__main__":
    main()
