#!/usr/bin/env python3
"""Helper of tools/holistic_eval.sh (needs numpy: run it with /usr/bin/python3).

Subcommands:
  model     name, window tokens, overlap tokens, frames per token, default guidance and steps of
            a SoulNet bundle (model.toml)
  stub      --dry-run "generation": a held-out clip's real body, its synthetic fingers and face,
            shifted per seed and cut / tiled to a length, written as generate's .npy and .json
  body24    (T, 52, 3) SMPL-H joints -> (T, 24, 3) SMPL-shaped joints `dancegen eval` reads
  halfbeats the music beats of every clip (and the song) shifted by half the median beat interval
  report    collect the `dancegen eval` and `holistic_probe` JSON files, compute the boundary-jerk
            ratio at the generator's window joins and the finger / face motion statistics, and
            write the Markdown report

Body joints for `dancegen eval`: SMPL-H joints 0-21 are SMPL's; SMPL's hand joints 22 / 23 are
taken as the mean of the four finger base joints (index1, middle1, pinky1, ring1) of each hand
(SMPL-H 22, 25, 28, 31 left and 37, 40, 43, 46 right, `dancegen_motion::skeleton::SMPLH52_NAMES`).

The boundary-jerk ratio is `dancegen_metrics::longform::boundary_jerk_ratio` (±2-frame band,
mean joint jerk over the 24 joints), evaluated at the frames where `dancegen_soulnet::pipeline`
starts each new window's new tokens (`Generated::joins` × frames per token) instead of at
multiples of `dancegen eval --window`; a parity check against eval's own value at 150-frame
boundaries is reported.
"""

import argparse
import datetime
import json
import math
import os
import statistics
import sys
import tomllib

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from solo_eval import (  # noqa: E402  (the physical figures and contact sheet of every report)
    contact_section,
    genre_clips,
    physical_note,
    physical_over,
    physical_subset,
    physical_table,
    rates_note,
)

FPS = 30.0
BOUNDARY_BAND = 2  # dancegen_metrics::longform::BOUNDARY_BAND
LEFT_BASES = [22, 25, 28, 31]  # left_index1, left_middle1, left_pinky1, left_ring1
RIGHT_BASES = [37, 40, 43, 46]  # right_index1, right_middle1, right_pinky1, right_ring1
FROZEN_FRACTION = 0.1  # a joint / weight whose std is under 10 % of the synthetic data's
NOT_FROZEN_RATIO = 0.5  # target: mean std at least half the synthetic data's


# ----------------------------------------------------------------------------- small helpers


def load(path):
    with open(path) as f:
        return json.load(f)


def opt_load(path):
    try:
        return load(path)
    except (OSError, ValueError):
        return None


def save_npy(path, a):
    tmp = path + ".tmp.npy"
    np.save(tmp, a)
    os.replace(tmp, path)


def write_report(path, lines):
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write("\n".join(lines) + "\n")
    os.replace(tmp, path)
    print(f"wrote {path}")


def stats(vals):
    vals = [v for v in vals if v is not None and not (isinstance(v, float) and math.isnan(v))]
    if not vals:
        return None, None, 0
    m = statistics.fmean(vals)
    s = statistics.stdev(vals) if len(vals) > 1 else None
    return m, s, len(vals)


def fmt(m, s=None, digits=3, scale=1.0):
    if m is None:
        return "n/a"
    m = m * scale
    big = abs(m) >= 1e5
    f = (lambda v: f"{v:.3g}") if big else (lambda v: f"{v:.{digits}f}")
    if s is None:
        return f(m)
    return f"{f(m)} ± {f(s * scale)}"


def fmt_stats(vals, digits=3, scale=1.0):
    m, s, _ = stats(vals)
    return fmt(m, s, digits, scale)


def mean_def(vals):
    vals = [v for v in vals if v is not None]
    return statistics.fmean(vals) if vals else None


# ----------------------------------------------------------------------------- model / windows


def model_info(model_dir):
    with open(os.path.join(model_dir, "model.toml"), "rb") as f:
        cfg = tomllib.load(f)
    s = cfg.get("sampling", {})
    return {
        "name": cfg.get("name", "?"),
        "window_tokens": int(cfg.get("generator", {}).get("window_tokens", 32)),
        "overlap_tokens": int(s.get("overlap_tokens", 8)),  # SamplingDefaults::default
        "fpt": 1 << int(cfg.get("vq", {}).get("down_t", 2)),  # VqTable::frames_per_token
        "cond_scale": float(s.get("cond_scale", 4.0)),
        "steps": int(s.get("steps", 18)),
        "quantizer": cfg.get("vq", {}).get("quantizer", "?"),
        "foot_ik": bool(s.get("foot_ik", True)),  # SamplingDefaults::default
    }


def window_starts(n, w, overlap):
    """dancegen_soulnet::pipeline::window_starts."""
    if n <= w:
        return [0]
    starts = [0]
    step = w - min(overlap, w - 1)
    while True:
        last = starts[-1]
        if last + w >= n:
            break
        starts.append(min(last + step, n - w))
    return starts


def join_frames(frames, window_tokens, overlap, fpt):
    """Frames where pipeline::generate's windows after the first start being new
    (`Generated::joins`, in tokens, times frames per token)."""
    n = -(-frames // fpt)
    w = min(window_tokens, n)
    starts = window_starts(n, w, overlap)
    joins = [starts[k - 1] + w for k in range(1, len(starts))]
    return [j * fpt for j in joins if 0 < j * fpt < frames]


def mean_joint_jerk(p):
    """dancegen_metrics::longform::mean_joint_jerk of (T, J, 3) joints (J = 24)."""
    p = p.astype(np.float64)
    if len(p) < 4:
        return np.zeros(0)
    d = p[3:] - 3 * p[2:-1] + 3 * p[1:-2] - p[:-3]
    return FPS ** 3 * np.linalg.norm(d, axis=-1).mean(axis=1)


def boundary_jerk_ratio(jerk, boundaries):
    """dancegen_metrics::longform::boundary_jerk_ratio on precomputed jerk samples."""
    n = len(jerk)
    band = np.zeros(n, dtype=bool)
    for b in boundaries:
        lo, hi = max(b - 2 * BOUNDARY_BAND, 0), min(b, n - 1)
        if n == 0 or lo > hi:
            continue
        band[lo:hi + 1] = True
    if not band.any() or band.all():
        return None
    rest = jerk[~band].mean()
    if rest == 0.0:
        return None
    return float(jerk[band].mean() / rest)


# ----------------------------------------------------------------------------- motion helpers


def body24(j52):
    if j52.ndim != 3 or j52.shape[1:] != (52, 3):
        raise SystemExit(f"expected (T, 52, 3) joints, got {j52.shape}")
    out = np.empty((j52.shape[0], 24, 3), dtype=np.float32)
    out[:, :22] = j52[:, :22]
    out[:, 22] = j52[:, LEFT_BASES].mean(axis=1)
    out[:, 23] = j52[:, RIGHT_BASES].mean(axis=1)
    return out


def parts_of_json(path):
    """(finger axis-angles (T, 30, 3), face weights (T, 52)) of a generated .json."""
    d = load(path)
    poses = np.asarray(d["smplh_poses_axis_angle"], dtype=np.float64)
    face = np.asarray(d["face"]["weights"], dtype=np.float64)
    t = face.shape[0]
    poses = poses.reshape(t, 52, 3)
    return poses[:, 22:52], face


def parts_of_npz(path):
    d = np.load(path)
    return d["hands"].astype(np.float64).reshape(-1, 30, 3), d["face"].astype(np.float64)


def part_stds(hands, face):
    """Per finger joint std over time of its rotation angle (30,), per weight std (52,)."""
    ang = np.linalg.norm(hands, axis=-1)
    return ang.std(axis=0), face.std(axis=0)


# ----------------------------------------------------------------------------- subcommands


def cmd_model(args):
    m = model_info(args.model)
    print(m["name"], m["window_tokens"], m["overlap_tokens"], m["fpt"], m["cond_scale"],
          m["steps"])


def cmd_stub(args):
    gt = np.load(args.gt24).astype(np.float32)
    hol = np.load(args.holistic)
    mot = np.load(args.motion)
    frames_src = min(len(gt), len(hol["face"]), len(mot["poses"]))
    shift = (args.seed * 37) % frames_src
    idx = (np.arange(args.frames) + shift) % frames_src
    j = gt[idx]
    out = np.zeros((args.frames, 52, 3), dtype=np.float32)
    out[:, :22] = j[:, :22]
    # Fingers: spread along the wrist -> SMPL hand direction (plumbing only, not a real hand).
    for wrist, hand, base in ((20, 22, 22), (21, 23, 37)):
        v = j[:, hand] - j[:, wrist]
        for f in range(5):
            for k in range(3):
                lateral = np.array([0.0, 0.0, 0.01 * (f - 2)], dtype=np.float32)
                out[:, base + f * 3 + k] = j[:, wrist] + v * (1.0 + 0.35 * k) + lateral
    np.save(args.out, out)
    poses = np.concatenate([mot["poses"][idx][:, :66],
                            hol["hands"][idx].reshape(args.frames, 90)], axis=1)
    face = hol["face"][idx]
    names = [f"w{k}" for k in range(face.shape[1])]
    with open(args.json, "w") as f:
        json.dump({"stub": True, "shape": [args.frames, 52, 3],
                   "smplh_poses_axis_angle": poses.astype(np.float32).ravel().tolist(),
                   "face": {"names": names, "weights": face.astype(np.float32).tolist()}}, f)


def cmd_body24(args):
    """Every (T, 52, 3) .npy under src (recursively) to dst, unless dst is newer."""
    n = 0
    for root, _, files in os.walk(args.src):
        for fn in files:
            if not fn.endswith(".npy"):
                continue
            s = os.path.join(root, fn)
            d = os.path.join(args.dst, os.path.relpath(s, args.src))
            if os.path.exists(d) and os.path.getmtime(d) >= os.path.getmtime(s):
                continue
            os.makedirs(os.path.dirname(d), exist_ok=True)
            save_npy(d, body24(np.load(s)))
            n += 1
    print(n)


def half_shift(beats):
    if len(beats) < 2:
        return 0
    return int(math.floor(float(np.median(np.diff(beats))) / 2 + 0.5))


def cmd_halfbeats(args):
    os.makedirs(args.out, exist_ok=True)
    info = {}
    for ln in open(args.clips):
        p = ln.split()
        if not p:
            continue
        stem, frames = p[0], int(p[3])
        b = np.load(os.path.join(args.beats, stem + ".npy"))
        h = half_shift(b)
        s = b + h
        save_npy(os.path.join(args.out, stem + ".npy"), s[s < frames].astype(np.int64))
        info[stem] = h
    b = np.load(os.path.join(args.beats, "song.npy"))
    h = half_shift(b)
    frames = int(open(os.path.join(args.beats, "song_frames.txt")).read())
    s = b + h
    save_npy(os.path.join(args.out, "song.npy"), s[s < frames].astype(np.int64))
    info["song"] = h
    with open(os.path.join(args.out, "shift.json"), "w") as f:
        json.dump(info, f, indent=1)


# ----------------------------------------------------------------------------- report


def cmd_report(args):
    out = args.out
    meta = load(os.path.join(out, "meta.json"))
    seeds = args.seeds.split()
    guidances = args.guidances.split()
    clip_rows = [ln.split() for ln in open(os.path.join(out, "clips.txt")) if ln.strip()]
    clips = [r[0] for r in clip_rows]
    if os.path.exists(os.path.join(meta["model_abs"], "model.toml")):
        mi = model_info(meta["model_abs"])
    else:  # dry run without a model: configs/soulnet_small_*.toml's values
        mi = {"name": "(dry run: no model)", "window_tokens": 32, "overlap_tokens": 8, "fpt": 4,
              "cond_scale": 4.0, "steps": 18, "quantizer": "?", "foot_ik": True}
    wt, ov, fpt = mi["window_tokens"], mi["overlap_tokens"], mi["fpt"]
    n_train = len([f for f in os.listdir(os.path.join(out, "gt_train")) if f.endswith(".npy")])
    n_all = n_train + len(clips)
    ev = os.path.join(out, "eval")
    parity = [0.0, 0]
    half = load(os.path.join(out, "beats_half", "shift.json"))

    def per_clip_bj(eval_json):
        return {os.path.splitext(os.path.basename(r["file"]))[0]: r.get("boundary_jerk")
                for r in (eval_json or {}).get("per_clip", [])}

    def joins_ratio(path, eval_json=None, frames_for_joins=None):
        """Boundary-jerk ratio at the generator's joins (and the parity check vs eval)."""
        p = np.load(path)
        jerk = mean_joint_jerk(p)
        t = len(p) if frames_for_joins is None else frames_for_joins
        joins = join_frames(t, wt, ov, fpt)
        r = boundary_jerk_ratio(jerk, joins)
        if eval_json is not None:
            theirs = per_clip_bj(eval_json).get(os.path.splitext(os.path.basename(path))[0])
            mine = boundary_jerk_ratio(jerk, list(range(150, len(p), 150)))
            if (mine is None) != (theirs is None):
                parity[0] = math.inf
            elif mine is not None:
                parity[0] = max(parity[0], abs(mine - theirs) / max(abs(theirs), 1e-12))
            parity[1] += 1
        return r, len(joins)

    # ---- synthetic held-out fingers and face (the reference for "not frozen")
    syn_h, syn_f = [], []
    for c in clips:
        h, f = parts_of_npz(os.path.join(meta["dataset_abs"], "held_out", "holistic", c + ".npz"))
        a, b = part_stds(h, f)
        syn_h.append(a)
        syn_f.append(b)
    syn_h, syn_f = np.mean(syn_h, axis=0), np.mean(syn_f, axis=0)

    def parts_summary(json_paths):
        """Mean per-joint finger-angle std, mean per-weight face std, and near-frozen counts
        (per-joint stds averaged over the files)."""
        hs, fs = [], []
        for p in json_paths:
            h, f = parts_of_json(p)
            a, b = part_stds(h, f)
            hs.append(a)
            fs.append(b)
        if not hs:
            return None
        h, f = np.mean(hs, axis=0), np.mean(fs, axis=0)
        hm, fm = syn_h > 1e-6, syn_f > 1e-6
        return {
            "finger_std": float(h.mean()), "face_std": float(f.mean()),
            "finger_frozen": int((h[hm] < FROZEN_FRACTION * syn_h[hm]).sum()),
            "finger_n": int(hm.sum()),
            "face_frozen": int((f[fm] < FROZEN_FRACTION * syn_f[fm]).sum()),
            "face_n": int(fm.sum()),
            "finger_min_ratio": float((h[hm] / syn_h[hm]).min()) if hm.any() else None,
            "face_min_ratio": float((f[fm] / syn_f[fm]).min()) if fm.any() else None,
        }

    def bas_of(d, prefix, names):
        vals = []
        for c in names:
            j = opt_load(os.path.join(d, f"{prefix}_{c}.json"))
            vals.append(None if j is None else j.get("bas"))
        return mean_def(vals)

    # ---- real held-out body
    rj = load(os.path.join(ev, "real", "clip.json"))
    real = {k: rj.get(k) for k in ("pfc", "fsr", "freeze", "inverted")}
    real["bas"] = bas_of(os.path.join(ev, "real"), "bas", clips)
    real["bas_half"] = bas_of(os.path.join(ev, "real"), "bas_half", clips)
    real["bj"] = mean_def([joins_ratio(os.path.join(out, "gt", c + ".npy"), rj)[0]
                           for c in clips])
    tr = load(os.path.join(ev, "real", "fid_train.json"))
    tra = load(os.path.join(ev, "real", "fid_train_all.json"))
    hoa = load(os.path.join(ev, "real", "fid_heldout_all.json"))
    SET = ("fid_k", "fid_g", "div_k", "div_g")

    # ---- generated, per seed
    seg, lng, setm, done, done_long = {}, {}, {}, [], []
    seg_parts, long_parts = [], []
    bas_pairs = []  # per (seed, clip): BAS on the true beats above BAS on the shifted ones
    bas_pairs_long = []  # per seed, whole song
    njoins_seg, njoins_long = [], []
    for s in seeds:
        ed = os.path.join(ev, f"seed{s}")
        fj, fa, cj = (opt_load(os.path.join(ed, f)) for f in ("fid.json", "fid_all.json",
                                                                 "clip.json"))
        if fj is not None and fa is not None and cj is not None:
            done.append(s)
            for k in SET:
                setm.setdefault(k, []).append(fj.get(k))
                setm.setdefault(k + "_all", []).append(fa.get(k))
            row = {k: cj.get(k) for k in ("pfc", "fsr", "freeze", "inverted")}
            row["bas"] = bas_of(ed, "bas", clips)
            row["bas_half"] = bas_of(ed, "bas_half", clips)
            for c in clips:
                a = opt_load(os.path.join(ed, f"bas_{c}.json"))
                b = opt_load(os.path.join(ed, f"bas_half_{c}.json"))
                if a and b and a.get("bas") is not None and b.get("bas") is not None:
                    bas_pairs.append(a["bas"] > b["bas"])
            rs = [joins_ratio(os.path.join(out, "body", f"seed{s}", c + ".npy"), cj) for c in clips]
            row["bj"] = mean_def([r for r, _ in rs])
            row["bj52"] = mean_def([joins_ratio(os.path.join(out, "gen", f"seed{s}", c + ".npy"))[0]
                                    for c in clips])
            njoins_seg.append(sum(n for _, n in rs))
            for k, v in row.items():
                seg.setdefault(k, []).append(v)
            seg_parts.append(parts_summary(
                [os.path.join(out, "gen", f"seed{s}", c + ".json") for c in clips]))
        lj = opt_load(os.path.join(ed, "long.json"))
        lh = opt_load(os.path.join(ed, "long_half.json"))
        if lj is not None:
            done_long.append(s)
            row = {k: lj.get(k) for k in ("bas", "pfc", "fsr", "freeze", "inverted")}
            row["bas_half"] = None if lh is None else lh.get("bas")
            if row["bas"] is not None and row["bas_half"] is not None:
                bas_pairs_long.append(row["bas"] > row["bas_half"])
            r, nj = joins_ratio(os.path.join(out, "body", f"seed{s}", "long", "song.npy"), lj)
            row["bj"] = r
            row["bj52"] = joins_ratio(os.path.join(out, "gen", f"seed{s}", "long", "song.npy"))[0]
            njoins_long.append(nj)
            for k, v in row.items():
                lng.setdefault(k, []).append(v)
            long_parts.append(parts_summary(
                [os.path.join(out, "gen", f"seed{s}", "long", "song.json")]))

    # ---- CFG sweep (seed 0 of the sweep)
    cfg_rows = []
    for g in guidances:
        ed = os.path.join(ev, f"cfg{g}")
        cj = opt_load(os.path.join(ed, "clip.json"))
        fa = opt_load(os.path.join(ed, "fid_all.json"))
        if cj is None:
            cfg_rows.append((g, None))
            continue
        paths = [os.path.join(out, "gen", f"cfg{g}", c + ".json") for c in clips]
        cfg_rows.append((g, {
            "bas": bas_of(ed, "bas", clips), "bas_half": bas_of(ed, "bas_half", clips),
            "freeze": cj.get("freeze"), "fsr": cj.get("fsr"),
            "fid_k_all": None if fa is None else fa.get("fid_k"),
            "fid_g_all": None if fa is None else fa.get("fid_g"),
            "parts": parts_summary([p for p in paths if os.path.exists(p)]),
            "reused": os.path.exists(os.path.join(out, "gen", f"cfg{g}", "REUSED")),
        }))

    # ---- with and without the MMR loss (section 7)
    mmr_cmp = []
    for name, mdir in meta.get("mmr_sets", []):
        row, nseeds = {}, 0
        for s in seeds:
            ed = os.path.join(ev, "mmr", name, f"seed{s}")
            fj, fa, cj = (opt_load(os.path.join(ed, f)) for f in ("fid.json", "fid_all.json",
                                                                     "clip.json"))
            if fj is None or fa is None or cj is None:
                continue
            nseeds += 1
            vals = {k: fj.get(k) for k in ("fid_k", "fid_g")}
            vals.update({k + "_all": fa.get(k) for k in SET})
            vals.update({k: cj.get(k) for k in ("fsr", "freeze", "pfc")})
            vals["bas"] = bas_of(ed, "bas", clips)
            vals["bas_half"] = bas_of(ed, "bas_half", clips)
            vals["bj"] = mean_def([joins_ratio(os.path.join(out, "mmr", "body", name, f"seed{s}",
                                                            c + ".npy"))[0] for c in clips])
            ps = parts_summary([os.path.join(out, "mmr", "gen", name, f"seed{s}", c + ".json")
                                for c in clips])
            vals["finger_std"] = ps["finger_std"] if ps else None
            vals["face_std"] = ps["face_std"] if ps else None
            mg = opt_load(os.path.join(out, "probe", f"mmr_gen_{name}_seed{s}.json"))
            vals["ms"] = mg.get("matching_score_eq8") if mg else None
            vals["ms_code"] = mg.get("matching_score_released_code") if mg else None
            for k, v in vals.items():
                row.setdefault(k, []).append(v)
        mmr_cmp.append((name, mdir, nseeds, row))

    # ---- times
    times = {}
    tpath = os.path.join(out, "times.tsv")
    if os.path.exists(tpath):
        last = {}
        for ln in open(tpath):
            p = ln.rstrip("\n").split("\t")
            if len(p) >= 4:
                last[(p[0], p[1], p[3])] = (float(p[2]), int(p[4]) if len(p) > 4 else None)
        for (kind, key, _), (t, fr) in last.items():
            if key in (guidances if kind == "cfg" else seeds):
                times.setdefault(kind, []).append((t, fr))

    # ---- probe
    mmr = opt_load(os.path.join(out, "probe", "mmr.json"))
    recon = opt_load(os.path.join(out, "probe", "recon.json"))

    def err_of(name):
        p = os.path.join(out, "probe", name + ".err")
        if not os.path.exists(p):
            return None
        t = open(p).read().strip()
        last = t.splitlines()[-1].strip() if t else ""
        if "missing field" in last and "TOML parse error" in t:
            last += ("; holistic_probe's own held-out `[data]` table lacks keys `TrainConfig` "
                     "requires (a bug in `crates/dancegen-train/examples/holistic_probe.rs`, "
                     "`held_out()`)")
        return last

    # ================================================================= render
    L = []
    w = L.append
    w("# Holistic evaluation (SoulNet) on the held-out song")
    w("")
    if args.dry_run:
        w("> **DRY RUN — NOT MODEL OUTPUT.** The \"generated\" motion is the held-out real body "
          "with the held-out synthetic fingers and face, shifted per seed "
          "(`tools/holistic_eval.sh --dry-run`); the finger *positions* are a made-up spread. "
          "These numbers only test the plumbing. The MMR probe needs the model and is skipped; "
          "the reconstruction probe is real.")
        w("")
    w(f"Generated by `{meta['command']}` on {meta['date']} (commit `{meta['commit']}`"
      f"{', with uncommitted changes in the working tree' if meta.get('dirty') else ''}); "
      f"model `{meta['model_dir']}` (model.toml name `{mi['name']}`, generator windows of "
      f"{wt} tokens × {fpt} frames = {wt * fpt} frames, {ov} tokens carried over between "
      f"windows, default guidance {mi['cond_scale']:g}, {mi['steps']} decoding steps); binary "
      f"`{meta['binary']}`; probe `{meta['probe']}`; machine: {meta['nproc']} cores, "
      f"{meta['load']}; wall time {meta['wall']} (the `dancegen generate` calls behind this "
      f"report took {sum(t for v in times.values() for t, _ in v) / 60:.1f} min; outputs of an "
      "earlier run of the same model are reused, which can make the wall time shorter).")
    w("")
    w(f"Seeds: {' '.join(seeds)}"
      + (f" (finished: {' '.join(done) or 'none'})" if len(done) < len(seeds) else "")
      + f". Data set `{meta['dataset']}`: {len(clips)} held-out clips "
      f"({', '.join('`' + c + '`' for c in clips)}; CMU salsa takes 13 and 14, both partners), "
      f"all paired with `{meta['song']}` ({meta['song_seconds']} s) at the manifest's "
      "`song_start_s`–`song_end_s`; the generated segments dance exactly these cuts "
      "(`dancegen generate SONG --system holistic --start S --end E --seed N`). Values with ± "
      "are mean ± standard deviation over seeds (n − 1); a seed's value is the mean over its "
      f"clips. {meta.get('seed_note', '')}".rstrip())
    failed = open(os.path.join(out, "failed.txt")).read().strip() \
        if os.path.exists(os.path.join(out, "failed.txt")) else ""
    if failed:
        w("")
        w(f"**Failed generations** (see `{meta['out']}/failed.txt`):")
        w("")
        for ln in failed.splitlines()[:12]:
            w(f"- {ln}")
    w("")

    # ---- 1. generation
    w("## 1. Generation")
    w("")
    w("| output | files | frames (mean) | seconds per file (mean) | range |")
    w("|---|---|---|---|---|")
    kinds = [("seg", "held-out segment (default guidance)"),
             ("long", "whole song (default guidance)"),
             ("cfg", "held-out segment, guidance sweep (seed 0)")]
    kinds += [(k, f"held-out segment, MMR comparison: {k[4:]} the loss")
              for k in sorted(times) if k.startswith("mmr_")]
    for kind, label in kinds:
        v = times.get(kind, [])
        if not v:
            w(f"| {label} | 0 | n/a | n/a | n/a |")
            continue
        ts = [t for t, _ in v]
        fr = [f for _, f in v if f]
        w(f"| {label} | {len(v)} | {statistics.fmean(fr) if fr else float('nan'):.0f} | "
          f"{statistics.fmean(ts):.1f} | {min(ts):.1f}–{max(ts):.1f} |")
    w("")
    w("Wall time of each `dancegen -q generate ... -o x.npy -o x.json` process (model loading, "
      "music analysis and both files included) on this machine while it was shared as stated "
      "above. Outputs of an earlier run of the same command and model are reused (FRESH=1 "
      "regenerates); their times are the ones recorded when they were made.")
    w("")

    # ---- 2. body
    w(f"## 2. Body on real held-out motion ({len(clips)} clips × {len(done)} seeds)")
    w("")
    w("The generated SMPL-H joints become SMPL-24-shaped joints (0–21 as they are; 22 / 23 = "
      "the mean of each hand's index1, middle1, pinky1 and ring1 base joints, SMPL-H 22, 25, "
      "28, 31 and 37, 40, 43, 46) and go through `dancegen eval` exactly as in "
      "`tools/solo_eval.sh`: FID / Div with `--protocol finedance-lodge` (22 joints, so the two "
      "hand joints do not enter), per-clip metrics with `--protocol none --fps 30`, BAS "
      "`--bas-variant bailando` against the beats of each clip's cut (the beat column of the "
      "song's `dancegen features`, the beats `generate` conditions on).")
    w("")
    w("| motion | FID_k (4 held-out) ↓ | FID_g (4 held-out) ↓ | Div_k | Div_g | "
      f"FID_k ({n_all} real) ↓ | FID_g ({n_all} real) ↓ | Div_k | Div_g |")
    w("|---|---|---|---|---|---|---|---|---|")
    w(f"| real held-out motion | n/a | n/a | {fmt(tr.get('div_k_gt'), None, 2)} | "
      f"{fmt(tr.get('div_g_gt'), None, 2)} | {fmt(hoa.get('fid_k'), None, 2)} | "
      f"{fmt(hoa.get('fid_g'), None, 2)} | {fmt(hoa.get('div_k'), None, 2)} | "
      f"{fmt(hoa.get('div_g'), None, 2)} |")
    w(f"| real: the {n_train} training clips (calibration) | {fmt(tr.get('fid_k'), None, 2)} | "
      f"{fmt(tr.get('fid_g'), None, 2)} | {fmt(tr.get('div_k'), None, 2)} | "
      f"{fmt(tr.get('div_g'), None, 2)} | {fmt(tra.get('fid_k'), None, 2)} | "
      f"{fmt(tra.get('fid_g'), None, 2)} | {fmt(tra.get('div_k'), None, 2)} | "
      f"{fmt(tra.get('div_g'), None, 2)} |")
    w("| SoulNet (generated segments) | " + " | ".join(
        fmt_stats(setm.get(k, []), 2) for k in
        ("fid_k", "fid_g", "div_k", "div_g", "fid_k_all", "fid_g_all", "div_k_all",
         "div_g_all")) + " |")
    w("")
    w(f"Div columns follow their FID reference's normalisation. (a) = the {len(clips)} held-out "
      f"clips (what the issue asks; degenerate: real training salsa already scores FID_k "
      f"{fmt(tr.get('fid_k'), None, 2)} against it), (b) = all {n_all} real clips of the data "
      f"set ({n_train} training + {len(clips)} held-out), as in `docs/solo-eval.md`.")
    w("")
    cols = [("bas", "BAS ↑", 4, 1.0), ("bas_half", "BAS, beats + ½ beat", 4, 1.0),
            ("pfc", "PFC ↓", 3, 1.0), ("fsr", "Foot skating (FSR) % ↓", 2, 100.0),
            ("freeze", "Freeze % ↓", 2, 100.0), ("inverted", "Upside down % ↓", 2, 100.0)]
    w("| motion | " + " | ".join(c[1] for c in cols) + " |")
    w("|---|" + "---|" * len(cols))
    w("| real held-out motion | " + " | ".join(fmt(real.get(k), None, d, sc)
                                            for k, _, d, sc in cols) + " |")
    w(f"| SoulNet, held-out segments ({len(done)} seeds) | " + " | ".join(
        fmt_stats(seg.get(k, []), d, sc) for k, _, d, sc in cols) + " |")
    w(f"| SoulNet, whole song ({len(done_long)} seeds) | " + " | ".join(
        fmt_stats(lng.get(k, []), d, sc) for k, _, d, sc in cols) + " |")
    w("")
    w(f"PFC is `dancegen eval`'s physical foot contact score (Lodge's, ×10⁴ as eval prints "
      f"it); FSR the share of frames with a skating foot; freeze the share of 1-s windows whose "
      f"mean joint speed is under 5 % of the clip's median. \"BAS, beats + ½ beat\" scores the "
      f"same motion against the clip's beats moved later by half its median beat interval "
      f"({', '.join(f'{c} {half.get(c)}' for c in clips)} frames; whole song "
      f"{half.get('song')}): a dance that hits the beats scores higher on the true beats. "
      f"Clip by clip, the generated segments score higher on the true beats in "
      f"{sum(bas_pairs)} of {len(bas_pairs)} (seed, clip) pairs, and the whole-song dances in "
      f"{sum(bas_pairs_long)} of {len(bas_pairs_long)} seeds.")
    fg, _, _ = stats(seg.get("fsr", []))
    pg, _, _ = stats(seg.get("pfc", []))
    if fg is not None and real.get("fsr") and real.get("pfc"):
        w("")
        w(f"Foot skating: the generated segments skate in {fg * 100:.1f} % of frames against "
          f"the real motion's {real['fsr'] * 100:.1f} % ({fg / real['fsr']:.1f}×), PFC "
          f"{pg:.2f} against {real['pfc']:.2f} ({pg / real['pfc']:.1f}×), with the foot lock "
          "`generate` applies by default (the solo system's root lock"
          + (" and leg IK" if mi["foot_ik"] else ", without leg IK (`[sampling] foot_ik = false`)")
          + " on the body; post-processing, not part of SoulNet; before it was added the first "
          "model skated in 82 % of frames).")
    w("")

    # ---- physical plausibility (+ the contact sheet)
    w("### Physical plausibility")
    w("")
    prow = [(f"real held-out motion ({len(clips)} clips)",
             physical_over([os.path.join(ev, "real", "physical.json")])),
            (f"real: the {n_train} training clips",
             physical_over([os.path.join(ev, "real", "physical_train.json")]))]
    # The training clips of the held-out clips' genre(s), when the data set has others too.
    manifest = os.path.join(meta["dataset_abs"], "manifest.json")
    held_genres = {c["genre"] for c in (opt_load(manifest) or {}).get("clips", [])
                   if c["name"] in clips}
    same = genre_clips(manifest, held_genres) - set(clips)
    train = {os.path.splitext(f)[0] for f in os.listdir(os.path.join(out, "gt_train"))}
    if same & train and same & train != train:
        prow.append((f"real: the {len(same & train)} {' / '.join(sorted(held_genres))} training "
                     "clips (the held-out clips' genre)",
                     physical_subset(os.path.join(ev, "real", "physical_train.json"), same)))
    prow.append((f"SoulNet, held-out segments ({len(done)} seed{'s' if len(done) != 1 else ''})",
                 physical_over([os.path.join(ev, f"seed{s}", "physical.json") for s in done])))
    prow.append((f"SoulNet, whole song ({len(done_long)} "
                 f"seed{'s' if len(done_long) != 1 else ''})",
                 physical_over([os.path.join(ev, f"seed{s}", "physical_long.json")
                                for s in done_long])))
    for g, r in cfg_rows:
        if r is not None:
            prow.append((f"SoulNet, held-out segments, guidance {g} "
                         f"({'the default; ' if r['reused'] else ''}seed 0)",
                         physical_over([os.path.join(ev, f"cfg{g}", "physical.json")])))
    for name, mdir, _, _ in mmr_cmp:
        prow.append((f"{'with' if name == 'with' else 'without'} the MMR loss (`{mdir}`, "
                     "held-out segments)",
                     physical_over([os.path.join(ev, "mmr", name, f"seed{s}", "physical.json")
                                    for s in seeds])))
    physical_table(w, prow)
    physical_note(w, rates_note(os.path.join(meta["dataset_abs"], "manifest.json")),
                  "The body as in the tables above (SMPL-24-shaped joints; `dancegen eval "
                  "--protocol none --fps 30 --metrics physical`); generated rows are mean ± "
                  "standard deviation over the seeds (the guidance rows: seed 0 alone).")
    contact_section(w, os.path.join(out, "contact.json"), args.report, "### Contact sheet")

    # ---- 3. boundary jerk
    w("## 3. Boundary jerk at window joins")
    w("")
    w(f"`dancegen_soulnet::pipeline` makes {wt}-token windows ({wt * fpt} frames); each next "
      f"window starts {ov} tokens before the end of what is made (those tokens are inpainted as "
      f"known) and the last window is moved back to end at the song's end. The joins — the "
      f"first new frame of each window after the first, `(start_prev + {wt}) × {fpt}` — are "
      f"recomputed by `tools/holistic_eval.py` (a port of `pipeline::window_starts`), and the "
      f"ratio of `dancegen_metrics::longform::boundary_jerk_ratio` (mean joint jerk of the 24 "
      f"joints in a ±{BOUNDARY_BAND}-frame band around the joins / elsewhere) is computed there; "
      f"`dancegen eval --window N` only places boundaries at multiples of N, which misses "
      f"these joins (the first is at {wt * fpt}, then every {(wt - ov) * fpt} frames, the last "
      f"one closer). Parity check: at 150-frame boundaries the helper reproduces `dancegen "
      f"eval`'s `boundary_jerk` on all {parity[1]} clips within {parity[0]:.1e} (relative). "
      "Real motion has no joins: its value at the same frames shows the metric's noise.")
    w("")
    w("| motion | joins per file (mean) | boundary-jerk ratio at the joins ↓ (target < 1.5) | "
      "same, all 52 SMPL-H joints (fingers included) |")
    w("|---|---|---|---|")
    nj_real = statistics.fmean([len(join_frames(int(r[3]), wt, ov, fpt)) for r in clip_rows])
    w(f"| real held-out motion (at the joins of its length) | {nj_real:.1f} | "
      f"{fmt(real['bj'], None, 3)} | n/a (no real fingers) |")
    w(f"| SoulNet, held-out segments | "
      f"{(statistics.fmean(njoins_seg) / len(clips)) if njoins_seg else float('nan'):.1f} | "
      f"{fmt_stats(seg.get('bj', []), 3)} | {fmt_stats(seg.get('bj52', []), 3)} |")
    w(f"| SoulNet, whole song | "
      f"{statistics.fmean(njoins_long) if njoins_long else float('nan'):.0f} | "
      f"{fmt_stats(lng.get('bj', []), 3)} | {fmt_stats(lng.get('bj52', []), 3)} |")
    w("")
    w("The 52-joint column uses the same definition with the mean over all 52 generated "
      "joints (world positions), so a jump of the fingers at a join shows too.")
    w("")

    # ---- 4. fingers and face
    w("## 4. Fingers and face: not frozen")
    w("")
    w("Per finger joint (the 30 SMPL-H finger joints): the standard deviation over time of its "
      "rotation angle (the norm of its axis-angle, radians, `smplh_poses_axis_angle` of the "
      "generated .json), averaged over the joints; per ARKit weight: its standard deviation "
      "over time, averaged over the 52 weights (`face.weights`). Per-joint values are averaged "
      "over the files first. The reference is the synthetic held-out data the model's fingers "
      f"and face were trained like (`{meta['dataset']}/held_out/holistic/*.npz`: `hands`, "
      f"`face`). \"Near-frozen\" counts joints / weights whose std is under "
      f"{FROZEN_FRACTION:.0%} of the synthetic data's for the same joint / weight, among those "
      f"the synthetic data moves at all ({int((syn_h > 1e-6).sum())} of 30 finger joints, "
      f"{int((syn_f > 1e-6).sum())} of 52 ARKit weights; the others are constant in it, so the "
      "52-weight mean is diluted the same way on both sides).")
    w("")
    w("| motion | finger angle std (rad) | ratio to synthetic | near-frozen finger joints | "
      "face weight std | ratio to synthetic | near-frozen face weights |")
    w("|---|---|---|---|---|---|---|")
    hm, fm = syn_h > 1e-6, syn_f > 1e-6
    w(f"| synthetic held-out data ({len(clips)} clips) | {syn_h.mean():.4f} | 1 | 0 of "
      f"{int(hm.sum())} | {syn_f.mean():.4f} | 1 | 0 of {int(fm.sum())} |")

    def parts_row(label, ps):
        ps = [p for p in ps if p]
        if not ps:
            w(f"| {label} | n/a | n/a | n/a | n/a | n/a | n/a |")
            return None
        fh = [p["finger_std"] for p in ps]
        ff = [p["face_std"] for p in ps]
        rh = [v / syn_h.mean() for v in fh]
        rf = [v / syn_f.mean() for v in ff]
        w(f"| {label} | {fmt_stats(fh, 4)} | {fmt_stats(rh, 2)} | "
          f"{fmt_stats([p['finger_frozen'] for p in ps], 1)} of {ps[0]['finger_n']} | "
          f"{fmt_stats(ff, 4)} | {fmt_stats(rf, 2)} | "
          f"{fmt_stats([p['face_frozen'] for p in ps], 1)} of {ps[0]['face_n']} |")
        return stats(rh)[0], stats(rf)[0]

    seg_ratio = parts_row(f"SoulNet, held-out segments ({len(done)} seeds)", seg_parts)
    long_ratio = parts_row(f"SoulNet, whole song ({len(done_long)} seeds)", long_parts)
    w("")
    w(f"Target used here: the generated mean std is at least {NOT_FROZEN_RATIO:.0%} of the "
      "synthetic data's, for the fingers and for the face (the issue names no number; the "
      "near-frozen counts show whether a few joints stand still).")
    w("")

    # ---- 5. CFG
    w("## 5. BAS against the guidance scale (CFG)")
    w("")
    w(f"Seed 0, the {len(clips)} held-out segments, `--guidance G` (the masked transformer's "
      f"classifier-free guidance; the model's default is {mi['cond_scale']:g}, 1 = no "
      "guidance). A row whose G is the default reuses the seed-0 segments of section 2.")
    w("")
    w(f"| G | BAS ↑ | BAS, beats + ½ beat | BAS − shifted | FID_k ({n_all} real) ↓ | "
      f"FID_g ({n_all} real) ↓ | FSR % | freeze % | finger angle std | face weight std |")
    w("|---|---|---|---|---|---|---|---|---|---|")
    for g, r in cfg_rows:
        if r is None:
            w(f"| {g} | n/a (not generated) | | | | | | | | |")
            continue
        d = None if r["bas"] is None or r["bas_half"] is None else r["bas"] - r["bas_half"]
        p = r["parts"] or {}
        w(f"| {g}{' (default)' if r['reused'] else ''} | {fmt(r['bas'], None, 4)} | "
          f"{fmt(r['bas_half'], None, 4)} | {fmt(d, None, 4)} | {fmt(r['fid_k_all'], None, 2)} | "
          f"{fmt(r['fid_g_all'], None, 2)} | {fmt(r['fsr'], None, 2, 100.0)} | "
          f"{fmt(r['freeze'], None, 2, 100.0)} | {fmt(p.get('finger_std'), None, 4)} | "
          f"{fmt(p.get('face_std'), None, 4)} |")
    w("")
    w("One seed per G on 4 clips: differences of a few hundredths of BAS are within the "
      "seed-to-seed spread of section 2.")
    w("")

    # ---- 6. MMR and reconstruction
    w("## 6. Music–motion retrieval (MMR) and part reconstruction")
    w("")
    w("`holistic_probe` (`crates/dancegen-train/examples/holistic_probe.rs`): "
      f"`{meta['probe_cmd_mmr']}` and `{meta['probe_cmd_recon']}`.")
    w("")
    if mmr is not None:
        w(f"Retrieval of the music by motion on the real held-out dances ({mmr.get('clips')} "
          f"clips cut into {mmr.get('windows')} non-overlapping {mmr.get('window_frames')}-frame "
          "windows; each motion window ranks all music windows by Euclidean distance of the "
          "MMR latents; the body is real, fingers and face synthetic):")
        w("")
        w("| R@1 ↑ | chance R@1 | R@3 ↑ | chance R@3 | MMR matching score, Eq. 8 (1-s segments) | "
          "matching score, released-code variant (one music latent per clip) |")
        w("|---|---|---|---|---|---|")
        w(f"| {fmt(mmr.get('r1'), None, 3)} | {fmt(mmr.get('chance_r1'), None, 3)} | "
          f"{fmt(mmr.get('r3'), None, 3)} | {fmt(mmr.get('chance_r3'), None, 3)} | "
          f"{fmt(mmr.get('matching_score_eq8'), None, 4)} | "
          f"{fmt(mmr.get('matching_score_released_code'), None, 4)} |")
        w("")
        r1, c1, r3, c3 = (mmr.get(k) for k in ("r1", "chance_r1", "r3", "chance_r3"))
        if None not in (r1, c1, r3, c3):
            w(f"R@1 is {r1 / c1:.1f}× chance and R@3 {r3 / c3:.1f}× chance. With "
              f"{mmr.get('windows')} windows one more or one fewer hit moves R@1 by "
              f"{1 / max(mmr.get('windows') or 1, 1):.3f}.")
            w("")
        gen_ms = [opt_load(os.path.join(out, "probe", f"mmr_gen_seed{s}.json")) for s in seeds]
        gen_ms = [g for g in gen_ms if g]
        if gen_ms:
            m8 = [g["matching_score_eq8"] for g in gen_ms]
            mc = [g["matching_score_released_code"] for g in gen_ms]
            w(f"The generated held-out segments ({len(gen_ms)} seeds; `holistic_probe mmr-gen`, "
              "the .json re-encoded to the 675-value vector, the same 1-s segments and music): "
              f"matching score (Eq. 8) {fmt_stats(m8, 4, 1.0)}, released-code variant "
              f"{fmt_stats(mc, 4, 1.0)} — against {fmt(mmr.get('matching_score_eq8'), None, 4)} "
              "and "
              f"{fmt(mmr.get('matching_score_released_code'), None, 4)} for the real pairs. "
              "Lower is closer. An MMR that does not retrieve held-out music (above) cannot tell "
              "a well-matched dance from another, so this score says little here.")
    else:
        e = err_of("mmr")
        w(f"**MMR probe not run or failed**{': ' + e if e else ''} "
          f"(see `{meta['out']}/probe/mmr.err`).")
    w("")
    w("Reconstruction of the held-out clips by each part autoencoder run (body: root-relative "
      "joint error on the real held-out motion, 21 joints; fingers: joint error relative to the "
      "wrist on the synthetic fingers; both from the heading-canonical `ric` positions of the "
      "vector; face: mean absolute ARKit weight error on the synthetic face):")
    w("")
    missing = meta.get("vq_missing", [])
    if recon:
        w("| run | quantizer | levels | codes | training steps | body MPJPE mm ↓ | "
          "finger MPJPE mm ↓ | face L1 ↓ |")
        w("|---|---|---|---|---|---|---|---|")
        for r in recon:
            steps = "?"
            try:
                with open(os.path.join(r["run"], "model.toml"), "rb") as f:
                    steps = tomllib.load(f).get("steps", "?")
            except OSError:
                pass
            rel = os.path.relpath(r["run"], meta["root"])
            w(f"| `{rel}` | {r.get('quantizer')} | {r.get('levels')} | {r.get('nb_code')} | "
              f"{steps} | {fmt(r.get('body_mpjpe_mm'), None, 1)} | "
              f"{fmt(r.get('finger_mpjpe_mm'), None, 2)} | {fmt(r.get('face_l1'), None, 4)} |")
        w("")
        qs = {}
        for r in recon:
            qs.setdefault(str(r.get("quantizer")).lower(), r)
        if "hrvq" in qs and len(qs) > 1:
            h = qs["hrvq"]
            others = [r for q, r in qs.items() if q != "hrvq"]
            bits, ok = [], {}
            for key, part, d, unit in (("finger_mpjpe_mm", "hands", 2, " mm"),
                                       ("face_l1", "face", 4, ""),
                                       ("body_mpjpe_mm", "body", 1, " mm")):
                best = min(others, key=lambda r: r.get(key, math.inf))
                hv, bv = h.get(key, math.inf), best.get(key, math.inf)
                ok[part] = hv < bv
                rel_d = (hv - bv) / bv * 100 if bv not in (0, math.inf) else float("nan")
                bits.append(f"{part}: HRVQ {fmt(hv, None, d)}{unit} vs the best other "
                            f"({best.get('quantizer')}) {fmt(bv, None, d)}{unit}, "
                            f"{rel_d:+.0f} % — HRVQ {'better' if ok[part] else 'not better'}")
            verdict_hf = ("holds" if ok["hands"] and ok["face"] else
                          "holds for the hands only" if ok["hands"] else
                          "holds for the face only" if ok["face"] else "does not hold")
            w(f"**The paper's direction (HRVQ best on hands and face) {verdict_hf} here**: "
              + "; ".join(bits) + ". One training run per quantizer, so run-to-run noise is "
              "not measured: treat differences of a few percent as unresolved.")
        else:
            w("**The paper's direction (HRVQ best on hands and face) cannot be checked here**: "
              "only " + ", ".join(f"`{q}`" for q in qs) + " runs were measured"
              + (f"; missing runs: {', '.join('`' + m + '`' for m in missing)}" if missing else "")
              + ". Train the VQ and RVQ variants (`configs/ablations/soulnet_vq_rvq.toml`, "
              "`configs/ablations/soulnet_vq_vq.toml`: the same autoencoder with `quantizer = "
              "\"rvq\"` / `\"vq\"`) and re-run.")
    else:
        e = err_of("recon")
        w(f"**Reconstruction probe not run or failed**{': ' + e if e else ''} "
          f"(see `{meta['out']}/probe/recon.err`).")
        if missing:
            w("")
            w("Missing runs: " + ", ".join(f"`{m}`" for m in missing) + ".")
    if recon and missing:
        w("")
        w("Runs not found (skipped): " + ", ".join(f"`{m}`" for m in missing) + ".")
    w("")

    # ---- 7. MMR loss
    w("## 7. With and without the MMR loss")
    w("")
    if mmr_cmp and all(n > 0 for _, _, n, _ in mmr_cmp):
        w("The same generator trained without and with SoulNet's training-time MMR alignment "
          "loss (`[model] mmr_loss_weight` of task `soulnet_magm`), each generating the "
          f"{len(clips)} held-out segments for seeds {' '.join(seeds)}, measured as in sections "
          "2–4:")
        w("")
        cols7 = [("bas", "BAS ↑", 4, 1.0), ("bas_half", "BAS, beats + ½ beat", 4, 1.0),
                 ("fid_k", f"FID_k ({len(clips)} held-out) ↓", 2, 1.0),
                 ("fid_g", f"FID_g ({len(clips)} held-out) ↓", 2, 1.0),
                 ("fid_k_all", f"FID_k ({n_all} real) ↓", 2, 1.0),
                 ("fid_g_all", f"FID_g ({n_all} real) ↓", 2, 1.0),
                 ("div_k_all", "Div_k", 2, 1.0), ("div_g_all", "Div_g", 2, 1.0),
                 ("fsr", "FSR % ↓", 2, 100.0), ("freeze", "freeze % ↓", 2, 100.0),
                 ("bj", "boundary jerk at joins ↓", 3, 1.0),
                 ("finger_std", "finger angle std", 4, 1.0),
                 ("face_std", "face weight std", 4, 1.0),
                 ("ms", "MMR matching score (Eq. 8) ↓", 3, 1.0),
                 ("ms_code", "matching score, released-code variant", 3, 1.0)]
        w("| generator | model | seeds | " + " | ".join(c[1] for c in cols7) + " |")
        w("|---|---|---|" + "---|" * len(cols7))
        for name, mdir, n, row in mmr_cmp:
            label = "with the MMR loss" if name == "with" else "without the MMR loss"
            w(f"| {label} | `{mdir}` | {n} | " + " | ".join(
                fmt_stats(row.get(k, []), d, sc) for k, _, d, sc in cols7) + " |")
        w("")
        a = {name: stats(row.get("bas", []))[:2] for name, _, _, row in mmr_cmp}
        if a.get("with", (None,))[0] is not None and a.get("without", (None,))[0] is not None:
            (m1, s1), (m0, s0) = a["with"], a["without"]
            small = abs(m1 - m0) < max(s1 or 0.0, s0 or 0.0)
            w(f"BAS with the loss {m1:.4f} vs without {m0:.4f}: "
              f"{'higher' if m1 > m0 else 'not higher'} with it"
              f"{' (the difference is smaller than one seed std)' if small else ''}. The loss "
              "is meant to pull the generated dance's MMR motion latent towards its music, which "
              "the matching score columns measure (judged by the shipped MMR, which both "
              "generators were conditioned on).")
            w("")
    else:
        if meta.get("mmr_requested"):
            w(f"**Not measured in this run**: `MMR_LOSS_MODEL={meta['mmr_requested']}` was given "
              "but no complete comparison was made (a bundle missing or its generations "
              "failed).")
        elif meta.get("mmr_loss_implemented"):
            w("**Not measured in this run.** The training-time MMR alignment loss exists in the "
              "code (`[model] mmr_loss_weight` of task `soulnet_magm`, off by default; "
              "`configs/ablations/soulnet_generator_mmr_loss.toml` trains the shipped generator "
              "with it), but no bundle trained with it was given to this script "
              "(`MMR_LOSS_MODEL=DIR`, and `MMR_BASE_MODEL=DIR` for the matching model without "
              "it), so this section has no numbers.")
        else:
            w("**Not measured: the training-time MMR alignment loss is not implemented in this "
              "version.** The generator (`dancegen_soulnet::generator::PartGenerator::loss`, task "
              "`soulnet_magm`) is trained with the masked and residual cross-entropies only; the "
              "MMR network is used as the music condition (its music latent) and for the "
              "measurements of section 6, not as a loss. There is therefore no \"with MMR loss\" "
              "model to compare, and this section has no numbers.")
        w("")

    # ---- targets
    def verdict(ok):
        return "n/a" if ok is None else ("✅ met" if ok else "❌ not met")

    w("## Targets")
    w("")
    w("| target | value | verdict |")
    w("|---|---|---|")
    for where, data in (("whole song", lng), ("held-out segments", seg)):
        m, s, _ = stats(data.get("bj", []))
        w(f"| boundary jerk at the window joins < 1.5 ({where}) | {fmt(m, s, 3)} | "
          f"{verdict(None if m is None else m < 1.5)} |")
    for label, ratio in (("held-out segments", seg_ratio), ("whole song", long_ratio)):
        if ratio is None:
            w(f"| fingers not frozen ({label}) | n/a | n/a |")
            w(f"| face not frozen ({label}) | n/a | n/a |")
            continue
        rh, rf = ratio
        w(f"| fingers not frozen: angle std ≥ {NOT_FROZEN_RATIO:.0%} of the synthetic data's "
          f"({label}) | {fmt(rh, None, 2)} × | {verdict(rh >= NOT_FROZEN_RATIO)} |")
        w(f"| face not frozen: weight std ≥ {NOT_FROZEN_RATIO:.0%} of the synthetic data's "
          f"({label}) | {fmt(rf, None, 2)} × | {verdict(rf >= NOT_FROZEN_RATIO)} |")
    for where, data in (("held-out segments", seg), ("whole song", lng)):
        a, sa, _ = stats(data.get("bas", []))
        b, sb, _ = stats(data.get("bas_half", []))
        ok = None if a is None or b is None else a > b
        note = ""
        if ok is not None and abs(a - b) < max(sa or 0.0, sb or 0.0):
            note = " (difference smaller than one seed std)"
        w(f"| BAS above the same motion against beats shifted by half a beat ({where}) | "
          f"{fmt(a, sa, 4)} vs {fmt(b, sb, 4)}{note} | {verdict(ok)} |")
    w(f"| (reference) real held-out motion: BAS vs half-beat-shifted | "
      f"{fmt(real.get('bas'), None, 4)} vs {fmt(real.get('bas_half'), None, 4)} | — |")
    w("")
    a, _, _ = stats(seg.get("bas", []))
    b, _, _ = stats(seg.get("bas_half", []))
    al, _, _ = stats(lng.get("bas", []))
    bl, _, _ = stats(lng.get("bas_half", []))
    if None not in (a, b, real.get("bas"), real.get("bas_half")):
        w(f"The beat margins are small next to the real motion's: BAS minus half-beat-shifted "
          f"BAS is {a - b:+.4f} on the segments"
          + (f" and {al - bl:+.4f} on the whole song" if None not in (al, bl) else "")
          + f", {real['bas'] - real['bas_half']:+.4f} for the real held-out motion (whose "
          "beats the warp put there). The targets are checked on means over seeds; see the "
          "clip-by-clip counts in section 2.")
        w("")

    # ---- caveats
    w("## What this does not show")
    w("")
    w("- **Hands and face are synthetic.** No real finger or face capture is paired with this "
      "music: the fingers and face of the training and held-out data are generated "
      "(`docs/holistic-data.md`). \"Not frozen\" compares movement with that synthetic data; it "
      "says nothing about whether the fingers and face look like a real dancer's. Only the "
      "body (sections 2–3) is measured against real motion.")
    w(f"- **{len(clips)} held-out clips only**, from two CMU takes (two dancers each) and one "
      "song; the retrieval numbers rest on "
      f"{mmr.get('windows') if mmr else 'a few dozen'} windows.")
    w(f"- **FID on few clips is noisy**: against the {len(clips)} held-out clips the features' "
      "per-dimension spread is near zero and FID explodes (see the calibration row); against "
      f"all {n_all} real clips it rests on few samples and favours closeness to the training "
      "clips. Compare with the calibration row, not with published numbers.")
    w("- **Pseudo-paired music.** The real motion was time-warped onto the song's beats "
      "(±15 % speed), so the real BAS is partly made by the warp.")
    w("- **The MMR does not generalise**: held-out retrieval is at chance (section 6), so its "
      "matching scores rank dances by resemblance to the training clips more than by their fit "
      "to the music.")
    if not (mmr_cmp and all(n > 0 for _, _, n, _ in mmr_cmp)):
        w("- **No MMR-loss comparison** in this run (section 7).")
    w("- The VQ / RVQ / HRVQ comparison holds only for runs trained with the same steps and "
      "data (see the table's steps column).")
    w("")
    write_report(args.report, L)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("model")
    p.add_argument("model")
    p.set_defaults(func=cmd_model)
    p = sub.add_parser("stub")
    p.add_argument("--gt24", required=True)
    p.add_argument("--holistic", required=True)
    p.add_argument("--motion", required=True)
    p.add_argument("--frames", type=int, required=True)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("-o", "--out", required=True)
    p.add_argument("--json", required=True)
    p.set_defaults(func=cmd_stub)
    p = sub.add_parser("body24")
    p.add_argument("src")
    p.add_argument("dst")
    p.set_defaults(func=cmd_body24)
    p = sub.add_parser("halfbeats")
    p.add_argument("--clips", required=True)
    p.add_argument("--beats", required=True)
    p.add_argument("--out", required=True)
    p.set_defaults(func=cmd_halfbeats)
    p = sub.add_parser("report")
    p.add_argument("--out", required=True)
    p.add_argument("--seeds", required=True)
    p.add_argument("--guidances", required=True)
    p.add_argument("--dry-run", action="store_true")
    p.add_argument("--report", required=True)
    p.set_defaults(func=cmd_report)
    a = ap.parse_args()
    a.func(a)


if __name__ == "__main__":
    main()
