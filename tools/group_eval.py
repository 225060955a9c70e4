#!/usr/bin/env python3
"""Group (TCDiff++) evaluation on the held-out group set; run by tools/group_eval.sh.

Held-out material (never trained on): the song `feelings`, the formation families circle and
diamond, and the salsa takes 13 and 14 plus modern 05_07 (`dancegen dataset build --pairing
group ... --hold-out ... --hold-out-shape circle diamond`, configs/tcdiffpp_small.toml).

For every selected held-out sample (N = 2, 3 and 5) and seed, each configuration dances the
sample's song span; the controlled ones follow the sample's own trajectories as a formation
file (a keyframe every second). Metrics:
- from `dancegen eval`: collision share, smallest root distance, TIF, GMC per scene; per-dancer
  FID_k / Div_k against the held-out *real* solo tracks, BAS against the clip's beats, PFC, FSR;
  for N = 2, GMR / GMC / TIF against the held-out real salsa couples;
- here: boundary jerk at the window joins and the largest root step within ±5 frames of a
  join, trajectory error against the requested path and the share of dances whose final
  left-to-right order is the requested one;
- the physical plausibility figures (`dancegen eval --metrics physical`) of every dancer, and
  of the held-out real solo tracks (the CMU salsa read at its true 60 fps);
- a contact sheet (tools/contact_sheet.sh): the first clip's full-system dance (first seed) and
  the held-out real salsa couple 13, at the same moments.

Standard library only (3.11+). Subcommand-free: one run does everything, reusing finished
generations in OUT.
"""

import argparse
import json
import math
import os
import shutil
import statistics
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from solo_eval import (  # noqa: E402  (shared .npy I/O, jerk, formatting, physical helpers)
    boundary_jerk_ratio,
    contact_section,
    fmt,
    make_contact_sheet,
    mean_joint_jerk,
    physical_note,
    physical_over,
    physical_table,
    rates_note,
    read_npy,
    stats,
    write_npy,
    write_report,
)

FPS = 30
KEYFRAME_EVERY = 30  # frames between formation keyframes taken from a sample's trajectories
MIN_SEPARATION_M = 0.45  # dancegen_refine::formation::MIN_SEPARATION_M
TELEPORT_M = 0.25  # a root step larger than this in one frame is a teleport (issue 43)
JOIN_BAND = 5  # frames either side of a join searched for a root jump (group.md §4)
LOW_PASS_SIGMA = 8.0  # dataset group composer's low-pass σ (frames), for placing B1
HELD_TAKES = ["60_13_scaled", "61_13_scaled", "60_14_scaled", "61_14_scaled"]
HELD_SOLO = HELD_TAKES + ["05_07"]
# True capture rates of the held-out takes whose BVH header states another (docs/data-rates.md:
# the CMU salsa at 60 fps, its headers say 120); the others are read at their header's rate.
SOURCE_FPS = {stem: 60 for stem in HELD_TAKES}

GROUP_ARGS = []  # --group-args, split (module-wide: every group `generate` gets them)

# (key, label, controlled by a formation, `--sampler` or None for the model's default).
CONFIGS = [
    ("full", "TCDiff++ (full system: the default parallel sampler, formation control, separation)",
     True, None),
    ("lgds", "LGDS (`--sampler lgds`), formation control", True, "lgds"),
    ("free", "free dance (no formation; the model chooses; the default sampler)", False, None),
    ("b1", "B1: N independent solo dances (models/lodgepp-small) placed on the formation",
     True, None),
]
# Ablation rows: (key, label, switch); each is the full system (formation control, default
# sampler) with the bundle of configs/ablations/tcdiffpp_<key>_500.toml, all at the same
# 500-step budget next to their own full-system control `full_500`.
ABLATIONS = [
    ("full_500", "full system, 500 steps (the ablations' control)", "none"),
    ("no_fp", "w/o fusion projection", "fusion_projection = false"),
    ("no_fa", "w/o footwork adaptor", "footwork = false"),
    ("no_dpe", "w/o positioning embedding", "positioning = false"),
    ("no_dl", "w/o distance loss", "[model.loss] distance = 0"),
    ("fpres", "full system with a residual fusion projection (experiment)", "fusion_residual = true"),
]


def log(msg):
    print(f"[group-eval {time.strftime('%H:%M:%S', time.gmtime())}] {msg}", file=sys.stderr)


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"failed: {' '.join(cmd)}\n{r.stderr}")
    return r.stdout


# ----------------------------------------------------------------------------- geometry


def order_left_to_right(pos):
    return sorted(range(len(pos)), key=lambda i: (pos[i][0], i))


def gaussian(x, sigma):
    r = int(3 * sigma)
    w = [math.exp(-0.5 * (k / sigma) ** 2) for k in range(-r, r + 1)]
    n = len(x)
    out = []
    for t in range(n):
        s = ws = 0.0
        for k in range(-r, r + 1):
            i = min(max(t + k, 0), n - 1)  # ends held
            s += w[k + r] * x[i]
            ws += w[k + r]
        out.append(s / ws)
    return out


def min_jerk(a, b, tau):
    s = tau**3 * (10 - 15 * tau + 6 * tau * tau)
    return [a[0] + (b[0] - a[0]) * s, a[1] + (b[1] - a[1]) * s]


def requested_paths(formation, start_s, frames):
    """[dancer][frame] of the formation (all dancers given at every keyframe here)."""
    keys = formation["keyframes"]
    n = len(keys[0]["positions"])
    at = [round(k["t"] * FPS) for k in keys]
    f0 = round(start_s * FPS)
    out = [[None] * frames for _ in range(n)]
    for d in range(n):
        for w in range(len(keys) - 1):
            fa, fb = at[w], at[w + 1]
            for f in range(fa, fb + 1):
                if 0 <= f - f0 < frames:
                    tau = (f - fa) / (fb - fa) if fb > fa else 1.0
                    out[d][f - f0] = min_jerk(keys[w]["positions"][d], keys[w + 1]["positions"][d], tau)
    return out


# ----------------------------------------------------------------------------- inputs


def select_clips(dataset, per_n, out):
    m = json.load(open(os.path.join(dataset, "manifest.json")))
    chosen = {2: [], 3: [], 5: []}
    for c in sorted(m["clips"], key=lambda c: c["name"]):
        g = c.get("group")
        if not c["motion"].startswith("held_out/") or not g or g["dancers"] not in chosen:
            continue
        if len(chosen[g["dancers"]]) >= per_n:
            continue
        shape, tr = read_npy(os.path.join(dataset, g["trajectories"]))
        n, t = shape[0], shape[1]
        frames = list(range(0, t, KEYFRAME_EVERY))
        if frames[-1] != t - 1:
            frames.append(t - 1)
        keys = []
        ok = True
        for f in frames:
            pos = [[tr[(d * t + f) * 2], tr[(d * t + f) * 2 + 1]] for d in range(n)]
            for a in range(n):
                for b in range(a + 1, n):
                    if math.dist(pos[a], pos[b]) < MIN_SEPARATION_M + 0.01:
                        ok = False
            keys.append({"t": round(c["song_start_s"] + f / FPS, 6), "positions": pos})
        if not ok:  # a real couple closer than the formation rule allows: not a valid request
            continue
        fpath = os.path.join(out, "formations", c["name"] + ".json")
        os.makedirs(os.path.dirname(fpath), exist_ok=True)
        json.dump({"keyframes": keys}, open(fpath, "w"))
        chosen[g["dancers"]].append({
            "name": c["name"], "dancers": n, "frames": t, "song": c["source_song"],
            "start": c["song_start_s"], "end": c["song_start_s"] + t / FPS,
            "formation": fpath, "music": os.path.join(dataset, c["music"]),
            "shapes": g["shapes"], "timing": g["timing"],
        })
    return [c for n in (2, 3, 5) for c in chosen[n]]


def windows(n_frames, length, stride):
    return list(range(0, n_frames - length + 1, stride))


def real_references(binary, data, out):
    """Held-out real solo tracks cut into 300-frame clips, and the real couples 13 and 14 as
    (2, 300, 24, 3) scenes."""
    solo_dir = os.path.join(out, "real", "solo")
    couple_dir = os.path.join(out, "real", "couples")
    # The real clips are converted once; an earlier run that read them at other rates (before
    # SOURCE_FPS: the salsa at its headers' 120 fps, twice too fast) is converted again.
    stamp = os.path.join(out, "real", "source_fps.json")
    want = {stem: SOURCE_FPS.get(stem) for stem in HELD_SOLO}
    if os.path.isdir(os.path.join(out, "real")):
        try:
            have = json.load(open(stamp))
        except (OSError, ValueError):
            have = None
        if have != want:
            log("real references: converted at other rates before; converting them again")
            shutil.rmtree(os.path.join(out, "real"))
    os.makedirs(solo_dir, exist_ok=True)
    os.makedirs(couple_dir, exist_ok=True)
    full = {}
    for stem in HELD_SOLO:
        src = os.path.join(data, "cmu-salsa", stem + ".bvh")
        if not os.path.exists(src):
            src = os.path.join(data, "cmu-dance", "modern", stem + ".bvh")
        dst = os.path.join(out, "real", stem + ".npy")
        if not os.path.exists(dst):
            rate = ["--source-fps", str(SOURCE_FPS[stem])] if stem in SOURCE_FPS else []
            run([binary, "convert", src, "--to", "smpl24"] + rate + ["--fps", "30", "-o", dst,
                                                                     "-q"])
        shape, a = read_npy(dst)
        full[stem] = (shape[0], a)
        for s in windows(shape[0], 300, 150):
            p = os.path.join(solo_dir, f"{stem}_{s:05d}.npy")
            if not os.path.exists(p):
                write_npy(p, a[s * 72:(s + 300) * 72], shape=(300, 24, 3))
    for take in ("13", "14"):
        (ta, a), (tb, b) = full[f"60_{take}_scaled"], full[f"61_{take}_scaled"]
        for s in windows(min(ta, tb), 300, 150):
            p = os.path.join(couple_dir, f"couple_{take}_{s:05d}.npy")
            if not os.path.exists(p):
                write_npy(p, list(a[s * 72:(s + 300) * 72]) + list(b[s * 72:(s + 300) * 72]),
                          shape=(2, 300, 24, 3))
    with open(stamp, "w") as f:
        json.dump(want, f)
    return solo_dir, couple_dir


# ----------------------------------------------------------------------------- generation


def generate(binary, cfg, clip, seed, model, solo_model, out, steps, controlled=True,
             sampler=None):
    d = os.path.join(out, "gen", cfg, f"seed{seed}")
    os.makedirs(d, exist_ok=True)
    scene = os.path.join(d, clip["name"] + ".npy")
    meta = os.path.join(d, clip["name"] + ".json")
    if os.path.exists(scene) and os.path.exists(meta):
        return scene, meta
    base = ["--start", f"{clip['start']:.4f}", "--end", f"{clip['end']:.4f}", "--seed", str(seed),
            "--progress", "none", "-q"]
    if steps:
        base += ["--steps", str(steps)]
    extra = GROUP_ARGS if cfg != "b1" else []
    t0 = time.time()
    if cfg == "b1":
        n = clip["dancers"]
        formation = json.load(open(clip["formation"]))
        want = requested_paths(formation, clip["start"], clip["frames"])
        dancers = []
        for k in range(n):
            p = os.path.join(d, f"{clip['name']}_solo{k}.npy")
            if not os.path.exists(p):
                run([binary, "generate", clip["song"], "--system", "solo", "--model", solo_model,
                     "-o", p] + base[:4] + ["--seed", str(seed * 10 + k)] + base[6:])
            shape, a = read_npy(p)
            t = min(shape[0], clip["frames"])
            x = gaussian([a[f * 72] for f in range(t)], LOW_PASS_SIGMA)
            z = gaussian([a[f * 72 + 2] for f in range(t)], LOW_PASS_SIGMA)
            placed = []
            for f in range(t):
                w = want[k][f] or want[k][f - 1]
                dx, dz = w[0] - x[f], w[1] - z[f]
                fr = list(a[f * 72:(f + 1) * 72])
                for j in range(24):
                    fr[3 * j] += dx
                    fr[3 * j + 2] += dz
                placed.extend(fr)
            dancers.append((t, placed))
        t = min(x[0] for x in dancers)
        flat = []
        for _, p in dancers:
            flat.extend(p[:t * 72])
        write_npy(scene, flat, shape=(n, t, 24, 3))
        traj = [[[p[f * 72], p[f * 72 + 2]] for f in range(t)] for _, p in dancers]
        errs, finals = [], []
        for tr, wt in zip(traj, want):
            e = [math.dist(tr[f], wt[f]) for f in range(t) if wt[f] is not None]
            errs += e
            finals.append(e[-1])
        json.dump({
            "start_order": order_left_to_right([tr[0] for tr in traj]),
            "end_order": order_left_to_right([tr[-1] for tr in traj]),
            "trajectory_error_mean_m": statistics.fmean(errs),
            "trajectory_error_final_m": statistics.fmean(finals),
            "seconds": time.time() - t0,
        }, open(meta, "w"))
        return scene, meta
    cmd = [binary, "generate", clip["song"], "--system", "group", "--dancers",
           str(clip["dancers"]), "--model", model, "-o", scene, "-o", meta] + base + extra
    if controlled:
        cmd += ["--formation", clip["formation"]]
    if sampler:
        cmd += ["--sampler", sampler]
    run(cmd)
    m = json.load(open(meta))
    slim = {k: m.get(k) for k in ("start_order", "end_order", "trajectory_error_mean_m",
                                  "trajectory_error_final_m")}
    slim["seconds"] = time.time() - t0
    json.dump(slim, open(meta, "w"))  # the joints are in the .npy already
    return scene, meta


def split(scene, d):
    shape, a = read_npy(scene)
    n, t = shape[0], shape[1]
    os.makedirs(d, exist_ok=True)
    out = []
    for k in range(n):
        p = os.path.join(d, f"{os.path.basename(scene)[:-4]}_d{k}.npy")
        write_npy(p, a[k * t * 72:(k + 1) * t * 72], shape=(t, 24, 3))
        out.append(p)
    return out


def joins(frames, window=150):
    """LGDS / parallel: window w covers [w·W/2, w·W/2 + W); new frames begin at W, 3W/2, ..."""
    return list(range(window, frames, window // 2))


def scene_motion_stats(scene):
    shape, a = read_npy(scene)
    n, t = shape[0], shape[1]
    jerks, jumps = [], []
    for k in range(n):
        p = a[k * t * 72:(k + 1) * t * 72]
        jerks.append(boundary_jerk_ratio(mean_joint_jerk(p, t), joins(t)))
        for b in joins(t):
            for f in range(max(b - JOIN_BAND, 1), min(b + JOIN_BAND, t - 1) + 1):
                jumps.append(math.dist((p[f * 72], p[f * 72 + 2]), (p[(f - 1) * 72], p[(f - 1) * 72 + 2])))
    return [j for j in jerks if j is not None], (max(jumps) if jumps else None)


def runs(args):
    """(key, model, controlled, sampler) of every configuration to dance: the main ones and the
    ablations whose bundles were given."""
    out = [(k, args.model, ctl, smp) for k, _, ctl, smp in CONFIGS
           if not args.only or k in args.only]
    bad = [a for a in args.ablation if "=" not in a]
    if bad:
        raise SystemExit(f"--ablation {bad[0]}: expected KEY=BUNDLE_DIR, e.g. no_fp=target/ablations/no_fp_500")
    given = dict(a.split("=", 1) for a in args.ablation)
    unknown = set(given) - {k for k, _, _ in ABLATIONS}
    if unknown:
        raise SystemExit(f"--ablation: unknown key(s) {sorted(unknown)}; "
                         f"known: {[k for k, _, _ in ABLATIONS]}")
    for k, _, _ in ABLATIONS:
        if k in given:
            if not os.path.exists(os.path.join(given[k], "model.toml")):
                raise SystemExit(f"--ablation {k}={given[k]}: no model.toml there")
            out.append((k, given[k], True, None))
    return out


def pose_spread_cm(flat, t):
    """Motion energy of one dancer: mean distance (cm) of its pelvis-relative joints from their
    own mean over the clip; a frozen pose scores 0."""
    rel = [[flat[f * 72 + 3 * j + c] - flat[f * 72 + c] for j in range(24) for c in range(3)]
           for f in range(t)]
    mean = [statistics.fmean(col) for col in zip(*rel)]
    total = 0.0
    for r in rel:
        for j in range(24):
            total += math.dist(r[3 * j:3 * j + 3], mean[3 * j:3 * j + 3])
    return 100.0 * total / (24 * t)


def scene_spread(scene):
    shape, a = read_npy(scene)
    n, t = shape[0], shape[1]
    return statistics.fmean(pose_spread_cm(a[k * t * 72:(k + 1) * t * 72], t) for k in range(n))


def seed_difference_cm(scene_a, scene_b):
    """Mean distance (cm) between the pelvis-relative joints of two seeds' dances of one clip."""
    (sa, a), (sb, b) = read_npy(scene_a), read_npy(scene_b)
    n, t = min(sa[0], sb[0]), min(sa[1], sb[1])
    total, count = 0.0, 0
    for k in range(n):
        for f in range(0, t, 3):  # every third frame: enough for a mean
            oa, ob = (k * sa[1] + f) * 72, (k * sb[1] + f) * 72
            for j in range(1, 24):
                pa = [a[oa + 3 * j + c] - a[oa + c] for c in range(3)]
                pb = [b[ob + 3 * j + c] - b[ob + c] for c in range(3)]
                total += math.dist(pa, pb)
                count += 1
    return 100.0 * total / count


def root_step_max(scene):
    """The largest horizontal root move (m) of any dancer between two consecutive frames,
    anywhere in the scene (a teleport is > 0.25 m at 30 fps, 7.5 m/s)."""
    shape, a = read_npy(scene)
    n, t = shape[0], shape[1]
    best = 0.0
    for k in range(n):
        p = a[k * t * 72:(k + 1) * t * 72]
        for f in range(1, t):
            best = max(best, math.dist((p[f * 72], p[f * 72 + 2]), (p[(f - 1) * 72], p[(f - 1) * 72 + 2])))
    return best


def closest_pair_cm(scene):
    """How alike the two most alike dancers of a scene are: for every pair, the mean distance
    (cm) between their pelvis-relative joints over the clip; the smallest pair."""
    shape, a = read_npy(scene)
    n, t = shape[0], shape[1]
    rel = []
    for k in range(n):
        p = a[k * t * 72:(k + 1) * t * 72]
        rel.append([[p[f * 72 + 3 * j + c] - p[f * 72 + c] for c in range(3)]
                    for f in range(0, t, 3) for j in range(1, 24)])
    return min(100.0 * statistics.fmean(math.dist(u, v) for u, v in zip(rel[x], rel[y]))
               for x in range(n) for y in range(x + 1, n))


def half_beats(clip, out):
    """The clip's music beats (the last channel of its (T, 35) features) moved half the median
    beat interval later, as a .npy of frame indices: BAS against these says how much of a
    dancer's BAS is the beat and how much is chance."""
    path = os.path.join(out, "beats_half", clip["name"] + ".npy")
    if not os.path.exists(path):
        shape, a = read_npy(clip["music"])
        t, d = shape[0], shape[1]
        beats = [f for f in range(t) if a[f * d + d - 1] > 0.5]
        gaps = [b - a_ for a_, b in zip(beats, beats[1:])]
        half = int(math.floor(statistics.median(gaps) / 2 + 0.5)) if gaps else 0
        os.makedirs(os.path.dirname(path), exist_ok=True)
        write_npy(path, [b + half for b in beats if b + half < t], descr="<i8")
    return path


def evaluate(binary, args, clips, out):
    solo_gt, couples_gt = real_references(binary, args.data, out)
    results = {}
    for cfg, model, controlled, sampler in runs(args):
        for seed in args.seeds:
            log(f"{cfg} seed {seed}")
            scenes, dancers, metas, bas, bas_margin = [], [], [], [], []
            for c in clips:
                scene, meta = generate(binary, cfg, c, seed, model, args.solo_model, out,
                                       args.steps, controlled, sampler)
                scenes.append((c, scene))
                metas.append((c, json.load(open(meta))))
                parts = split(scene, os.path.join(out, "split", cfg, f"seed{seed}"))
                dancers += parts
                j = os.path.join(out, "split", cfg, f"seed{seed}", c["name"] + "_bas.json")
                run([binary, "eval", "--fps", "30", "--pred"] + parts +
                    ["--beats", c["music"], "--metrics", "bas", "--json", j, "-q"])
                bas.append(json.load(open(j)).get("bas"))
                hj = j[:-len("_bas.json")] + "_bas_half.json"
                run([binary, "eval", "--fps", "30", "--pred"] + parts +
                    ["--beats", half_beats(c, out), "--metrics", "bas", "--json", hj, "-q"])
                for on, off in zip(json.load(open(j))["per_clip"], json.load(open(hj))["per_clip"]):
                    if on.get("bas") is not None and off.get("bas") is not None:
                        bas_margin.append(on["bas"] - off["bas"])
            ej = os.path.join(out, "eval", f"{cfg}_seed{seed}_dancers.json")
            sj = os.path.join(out, "eval", f"{cfg}_seed{seed}_scenes.json")
            os.makedirs(os.path.dirname(ej), exist_ok=True)
            run([binary, "eval", "--fps", "30", "--pred"] + dancers + ["--gt", solo_gt,
                 "--metrics", "fid_k,div_k,pfc,fsr", "--json", ej, "-q"])
            # The same FID_k / Div_k under the solo evaluation's protocol (root-relative joints
            # from a zero start): positions as given make the reference's kinetic features
            # depend on where a dancer stands (`dancegen_metrics::kinetic`, the acceleration
            # precedence bug), so a free dancer placed away from the real tracks' mocap origin
            # scored thousands whatever it danced.
            ejr = os.path.join(out, "eval", f"{cfg}_seed{seed}_dancers_rr.json")
            run([binary, "eval", "--protocol", "finedance-lodge", "--pred"] + dancers +
                ["--gt", solo_gt, "--metrics", "fid_k,div_k", "--json", ejr, "-q"])
            run([binary, "eval", "--fps", "30", "--pred"] + [s for _, s in scenes] +
                ["--metrics", "gmc,tif,collision,min_distance", "--json", sj, "-q"])
            pj = os.path.join(out, "eval", f"{cfg}_seed{seed}_physical.json")
            run([binary, "eval", "--fps", "30", "--pred"] + dancers +
                ["--metrics", "physical", "--json", pj, "-q"])
            n2 = [s for c, s in scenes if c["dancers"] == 2]
            cj = os.path.join(out, "eval", f"{cfg}_seed{seed}_couples.json")
            if n2:
                run([binary, "eval", "--fps", "30", "--pred"] + n2 + ["--gt", couples_gt,
                     "--metrics", "gmr,gmc,tif", "--json", cj, "-q"])
            jerk, jump, step = [], [], []
            spread = [scene_spread(s) for _, s in scenes]
            pairs = {"contrast": [], "unison": []}
            for c, s in scenes:
                bj, rj = scene_motion_stats(s)
                jerk += bj
                if rj is not None:
                    jump.append(rj)
                step.append(root_step_max(s))
                if c["timing"] in pairs:
                    pairs[c["timing"]].append(closest_pair_cm(s))
            results[(cfg, seed)] = {
                "dancers": json.load(open(ej)),
                "dancers_rr": json.load(open(ejr)),
                "scenes": json.load(open(sj)),
                "couples": json.load(open(cj)) if n2 else None,
                "bas": [b for b in bas if b is not None],
                "jerk": jerk,
                "jump": jump,
                "root_step": max(step),
                "bas_margin": bas_margin,
                "closest_contrast": mean_or_none(pairs["contrast"]),
                "closest_unison": mean_or_none(pairs["unison"]),
                "spread": statistics.fmean(spread),
                "scene_paths": [s for _, s in scenes],
                "dancer_paths": dancers,
                "physical": pj,
                "metas": metas,
            }
    rj = os.path.join(out, "eval", "real_couples.json")
    run([binary, "eval", "--fps", "30", "--pred", couples_gt, "--gt", couples_gt,
         "--metrics", "gmc,tif,collision,min_distance", "--json", rj, "-q"])
    rs = os.path.join(out, "eval", "real_solo.json")
    run([binary, "eval", "--fps", "30", "--pred", solo_gt, "--gt", solo_gt, "--metrics",
         "div_k,pfc,fsr",
         "--json", rs, "-q"])
    real_solo = json.load(open(rs))
    rsr = os.path.join(out, "eval", "real_solo_rr.json")
    run([binary, "eval", "--protocol", "finedance-lodge", "--pred", solo_gt, "--gt", solo_gt,
         "--metrics", "div_k", "--json", rsr, "-q"])
    real_solo["div_k_rr"] = json.load(open(rsr)).get("div_k")
    rp = os.path.join(out, "eval", "real_solo_physical.json")
    run([binary, "eval", "--fps", "30", "--pred", solo_gt, "--metrics", "physical", "--json", rp,
         "-q"])
    real_solo["physical_json"] = rp
    spreads = []
    for f in sorted(os.listdir(solo_gt)):
        shape, a = read_npy(os.path.join(solo_gt, f))
        spreads.append(pose_spread_cm(a, shape[0]))
    real_solo["spread"] = statistics.fmean(spreads)
    return results, json.load(open(rj)), real_solo


# ----------------------------------------------------------------------------- report


def per_seed(results, cfg, seeds, f):
    return [f(results[(cfg, s)]) for s in seeds]


def mean_or_none(v):
    v = [x for x in v if x is not None]
    return statistics.fmean(v) if v else None


def end_order_ok(clips, r):
    ok = []
    for c, m in r["metas"]:
        f = json.load(open(c["formation"]))
        last = f["keyframes"][-1]["positions"]
        ok.append(1.0 if m.get("end_order") == order_left_to_right(last) else 0.0)
    return mean_or_none(ok)


def report(args, clips, results, real_couples, real_solo, started, load_note):
    seeds = args.seeds
    L = []
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip()
    dirty = subprocess.run(["git", "status", "--porcelain"], capture_output=True,
                           text=True).stdout.strip()
    L.append("# Group evaluation (TCDiff++) on the held-out group set")
    L.append("")
    L.append(f"Generated by `bash tools/group_eval.sh` on {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())} "
             f"(commit `{commit}`{', with uncommitted changes' if dirty else ''}); model "
             f"`{os.path.relpath(args.model)}`"
             f"{'; group dances with `' + ' '.join(GROUP_ARGS) + '`' if GROUP_ARGS else ''}"
             f"{'; steps ' + str(args.steps) if args.steps else ''}; machine: 2 cores, {load_note}; wall time "
             f"{(time.time() - started) / 60:.0f} min.")
    L.append("")
    L.append("**Everything here is measured on held-out material the model never saw**: the song "
             "`feelings`, the formation families circle and diamond, and the held-out takes "
             "(salsa 13 and 14, modern 05_07). The group data are *composed* from real solo and "
             "couple motion (`dancegen dataset build --pairing group`, "
             "crates/dancegen-dataset/src/group/); there is no recorded group dance here, so "
             "nothing below is compared with the TCDiff++ paper's numbers.")
    L.append("")
    names = ", ".join(f"{c['name']} ({'/'.join(c['shapes'])}, {c['timing']})" for c in clips)
    L.append(f"Clips ({len(clips)}, 10 s each, N = 2, 3 and 5): {names}. Seeds: "
             f"{' '.join(map(str, seeds))}. The controlled configurations get each clip's own "
             f"root trajectories as a FORMATION.json (a keyframe every {KEYFRAME_EVERY} frames, "
             "minimum-jerk between), and are measured against the requested path those "
             "keyframes give.")
    L.append("")
    header = ("| configuration | collision % ↓ | min distance m | TIF % ↓ | GMC | FID_k ↓ | Div_k | "
              "FID_k root-relative ↓ | Div_k root-relative | BAS ↑ | PFC ↓ | FSR ↓ | boundary jerk ↓ | max root step near a join m ↓ | "
              "trajectory error mean / final m ↓ | end order as requested % |")

    def col(cfg, f, digits, scale=1.0):
        m, s, _ = stats(per_seed(results, cfg, seeds, f))
        return fmt(m, s, digits, scale)

    def table(rows):
        L.append(header)
        L.append("|" + "---|" * 16)
        for cfg, label in rows:
            if (cfg, seeds[0]) not in results:
                continue
            L.append(row(cfg, label))

    def row(cfg, label):
        sc = lambda r, k: r["scenes"].get(k)  # noqa: E731
        mind = col(cfg, lambda r: min(x["min_distance"] for x in r["scenes"]["per_clip"]), 2)
        traj = "n/a"
        order = "n/a"
        if cfg != "free":
            tm = col(cfg, lambda r: mean_or_none([m.get("trajectory_error_mean_m") for _, m in r["metas"]]), 3)
            tf = col(cfg, lambda r: mean_or_none([m.get("trajectory_error_final_m") for _, m in r["metas"]]), 3)
            traj = f"{tm} / {tf}"
            order = col(cfg, lambda r: end_order_ok(clips, r), 0, 100.0)
        jerk = "n/a (solo seams)" if cfg == "b1" else col(cfg, lambda r: mean_or_none(r["jerk"]), 3)
        return "| " + " | ".join([
            label,
            col(cfg, lambda r: sc(r, "collision"), 2, 100.0),
            mind,
            col(cfg, lambda r: sc(r, "tif"), 2, 100.0),
            col(cfg, lambda r: sc(r, "gmc"), 1),
            col(cfg, lambda r: r["dancers"].get("fid_k"), 1),
            col(cfg, lambda r: r["dancers"].get("div_k"), 2),
            col(cfg, lambda r: r["dancers_rr"].get("fid_k"), 1),
            col(cfg, lambda r: r["dancers_rr"].get("div_k"), 2),
            col(cfg, lambda r: mean_or_none(r["bas"]), 3),
            col(cfg, lambda r: r["dancers"].get("pfc"), 3),
            col(cfg, lambda r: r["dancers"].get("fsr"), 3),
            jerk,
            col(cfg, lambda r: max(r["jump"]) if r["jump"] else None, 3),
            traj,
            order,
        ]) + " |"

    table([(k, label) for k, label, _, _ in CONFIGS])
    L.append(f"| real held-out solo tracks / couples (reference) | "
             f"{fmt(real_couples.get('collision'), None, 2, 100.0)} (couples) | "
             f"{fmt(min(x['min_distance'] for x in real_couples['per_clip']), None, 2)} (partners) | "
             f"{fmt(real_couples.get('tif'), None, 2, 100.0)} (couples) | "
             f"{fmt(real_couples.get('gmc'), None, 1)} | n/a | {fmt(real_solo.get('div_k'), None, 2)} | "
             f"n/a | {fmt(real_solo.get('div_k_rr'), None, 2)} | "
             f"n/a | {fmt(real_solo.get('pfc'), None, 3)} | {fmt(real_solo.get('fsr'), None, 3)} | "
             "n/a | n/a | n/a | n/a |")
    L.append("")
    L.append("Mean ± standard deviation over the seeds (n − 1). Collision % = share of frames in "
             f"which two dancers' roots are closer than {MIN_SEPARATION_M} m or their capsule "
             "bodies intersect (`dancegen eval` `collision`); TIF % counts only the capsule "
             "intersections (our definition; never compare it with the paper's). Min distance: "
             "the smallest root distance of any scene of the seed. FID_k / Div_k: every "
             "generated dancer as one clip against the held-out real solo tracks cut into 10 s "
             "clips, positions as given (`--protocol none`). The reference's kinetic features "
             "carry its acceleration precedence bug (kept to match published numbers; "
             "`dancegen_metrics::kinetic`), which makes them depend on where a dancer stands, so "
             "these FID_k / Div_k also measure the stage position against the real tracks' mocap "
             "origin: a free dancer the model places elsewhere scores thousands whatever it "
             "dances. FID_k / Div_k root-relative: the same clips under the solo evaluation's "
             "protocol (`--protocol finedance-lodge`: zero-start, joints relative to the root, "
             "22 joints), which measures the dance and not the place. BAS: Bailando's, each dancer against its clip's beats. PFC as `dancegen eval` reports it (EDGE × 10⁴). Boundary "
             "jerk: mean joint jerk in the band before each window join over the rest "
             "(`dancegen_metrics::longform`'s band; joins at frames 150, 225, …). Real couples are partners, so their distances and "
             "intersections are contact, not collisions.")
    L.append("")
    if ("lgds", seeds[0]) in results and ("full", seeds[0]) in results:
        g0 = lambda cfg, f: stats(per_seed(results, cfg, seeds, f))[0]  # noqa: E731
        jerk_of = lambda r: mean_or_none(r["jerk"])  # noqa: E731
        jump_of = lambda r: max(r["jump"]) if r["jump"] else None  # noqa: E731
        coll_of = lambda r: r["scenes"].get("collision")  # noqa: E731
        L.append(f"**Sampler.** The full system's row uses the default sampler, the parallel one "
                 f"(`SamplingConfig::default`, models/tcdiffpp-small/model.toml); the LGDS row is "
                 f"the same dances with `--sampler lgds`. Boundary jerk {fmt(g0('full', jerk_of), None, 2)} "
                 f"(parallel) against {fmt(g0('lgds', jerk_of), None, 2)} (LGDS); largest root step "
                 f"near a join {fmt(g0('full', jump_of), None, 3)} m against "
                 f"{fmt(g0('lgds', jump_of), None, 3)} m; collisions "
                 f"{fmt(g0('full', coll_of), None, 2, 100.0)} % against "
                 f"{fmt(g0('lgds', coll_of), None, 2, 100.0)} %.")
        L.append("")
    # physical plausibility (+ the contact sheet)
    L.append("## Physical plausibility (every dancer)")
    L.append("")
    prow = []
    for cfg, label in [(k, label) for k, label, _, _ in CONFIGS] + \
            [(k, label) for k, label, _ in ABLATIONS]:
        if (cfg, seeds[0]) in results:
            prow.append((label, physical_over([results[(cfg, s)]["physical"] for s in seeds
                                               if (cfg, s) in results])))
    prow.append(("real held-out solo tracks (salsa 13 and 14, modern 05_07; 10 s clips)",
                 physical_over([real_solo["physical_json"]])))
    physical_table(L.append, prow)
    physical_note(
        L.append,
        "Here the real tracks are converted from the BVH files by this script "
        "(`dancegen convert --to smpl24 --source-fps 60 --fps 30` for the salsa, the header's "
        "rate for 05_07). "
        + rates_note(os.path.join(args.dataset, "manifest.json"),
                     "the group data set (the model's training data)"),
        "Every dancer of every clip as one clip (`dancegen eval --fps 30 --metrics physical` on "
        "the dancers split from the scenes); rows are mean ± standard deviation over the seeds.")
    contact_section(L.append, os.path.join(args.out, "contact.json"), args.report,
                    "### Contact sheet")
    # motion energy
    L.append("## Motion energy and dependence on the seed")
    L.append("")
    L.append("| configuration | pose spread cm | difference between seeds cm |")
    L.append("|---|---|---|")
    allrows = [(k, label) for k, label, _, _ in CONFIGS] + [(k, label) for k, label, _ in ABLATIONS]
    for cfg, label in allrows:
        if (cfg, seeds[0]) not in results:
            continue
        spread = col(cfg, lambda r: r["spread"], 2)
        diffs = []
        if len(seeds) > 1 and (cfg, seeds[1]) in results:
            for a, b in zip(results[(cfg, seeds[0])]["scene_paths"],
                            results[(cfg, seeds[1])]["scene_paths"]):
                diffs.append(seed_difference_cm(a, b))
        L.append(f"| {label} | {spread} | {fmt(mean_or_none(diffs), None, 2)} |")
    L.append(f"| real held-out solo tracks (10 s clips) | {fmt(real_solo.get('spread'), None, 2)} | n/a |")
    L.append("")
    L.append(f"Pose spread: each dancer's mean distance of its pelvis-relative joints from their own "
             f"mean over the clip, averaged over dancers and clips (a frozen pose scores 0). "
             f"Difference between seeds: mean distance between the pelvis-relative joints of seeds "
             f"{seeds[0]} and {seeds[1] if len(seeds) > 1 else '-'} dancing the same clip. A "
             "diffusion model that uses its noise input dances differently per seed.")
    L.append("")
    # N = 2 against the real couples
    L.append("## N = 2 against the held-out real salsa couples (takes 13 and 14, 10 s windows)")
    L.append("")
    L.append("| configuration | GMR ↓ | GMC | TIF % |")
    L.append("|---|---|---|---|")
    for cfg, label, _, _ in CONFIGS:
        if (cfg, seeds[0]) not in results or results[(cfg, seeds[0])]["couples"] is None:
            continue
        c = lambda f: fmt(*stats(per_seed(results, cfg, seeds, f))[:2], 2)  # noqa: E731
        L.append(f"| {label} | {c(lambda r: r['couples'].get('gmr'))} | "
                 f"{c(lambda r: r['couples'].get('gmc'))} | "
                 f"{fmt(*stats(per_seed(results, cfg, seeds, lambda r: r['couples'].get('tif')))[:2], 2, 100.0)} |")
    L.append(f"| real couples | 0 (itself) | {fmt(real_couples.get('gmc'), None, 2)} | "
             f"{fmt(real_couples.get('tif'), None, 2, 100.0)} |")
    L.append("")
    # by N
    L.append("## Collisions and control by group size (full system)")
    L.append("")
    L.append("| N | collision % | trajectory error mean m | end order as requested % |")
    L.append("|---|---|---|---|")
    for n in (2, 3, 5):
        idx = [i for i, c in enumerate(clips) if c["dancers"] == n]
        if not idx or ("full", seeds[0]) not in results:
            continue
        col_n = lambda r: mean_or_none([r["scenes"]["per_clip"][i]["collision"] for i in idx])  # noqa: E731
        tr_n = lambda r: mean_or_none([r["metas"][i][1].get("trajectory_error_mean_m") for i in idx])  # noqa: E731

        def ord_n(r):
            sub = {"metas": [r["metas"][i] for i in idx]}
            return end_order_ok([clips[i] for i in idx], sub)
        m = lambda f, d, s=1.0: fmt(*stats(per_seed(results, "full", seeds, f))[:2], d, s)  # noqa: E731
        L.append(f"| {n} | {m(col_n, 2, 100.0)} | {m(tr_n, 3)} | {m(ord_n, 0, 100.0)} |")
    L.append("")
    ran = [(k, label, sw) for k, label, sw in ABLATIONS if (k, seeds[0]) in results]
    L.append("## Ablations (500 training steps each, against their own 500-step control)")
    L.append("")
    if ran:
        L.append("Each row is a model trained from scratch on the same data, seed and budget "
                 "(configs/ablations/tcdiffpp_<key>_500.toml: 500 steps, a quarter of the "
                 "shipped model's, because five full runs do not fit a session on 2 cores), "
                 "danced like the full system above (formation control, the default sampler, "
                 "separation). Compare the rows with each other and with their control, not "
                 "with the shipped model. Switches: " +
                 "; ".join(f"{label}: `{sw}`" for k, label, sw in ran if sw != "none") + ".")
        L.append("")
        table([(k, label) for k, label, _ in ran])
    missing = [(label, sw) for k, label, sw in ABLATIONS if (k, seeds[0]) not in results]
    if missing:
        if ran:
            L.append("")
        L.append("Not run (no bundle given to the evaluation, so these rows are missing rather "
                 "than estimated): " + "; ".join(label for label, _ in missing) + ". "
                 "docs/group-ablations.md holds the last measured ablation table and how to "
                 "make it again.")
    L.append("")
    # targets
    L.append("## Targets (issue #17)")
    L.append("")
    g = lambda cfg, f: stats(per_seed(results, cfg, seeds, f))[0] if (cfg, seeds[0]) in results else None  # noqa: E731
    coll = g("full", lambda r: r["scenes"].get("collision"))
    coll_b1 = g("b1", lambda r: r["scenes"].get("collision"))
    tr = g("full", lambda r: mean_or_none([m.get("trajectory_error_mean_m") for _, m in r["metas"]]))
    jump = g("full", lambda r: max(r["jump"]) if r["jump"] else None)
    jerk = g("full", lambda r: mean_or_none(r["jerk"]))
    fid = g("full", lambda r: r["dancers"].get("fid_k"))
    fid_b1 = g("b1", lambda r: r["dancers"].get("fid_k"))
    fid_rr_b1 = g("b1", lambda r: r["dancers_rr"].get("fid_k"))

    def verdict(ok):
        return "n/a" if ok is None else ("met" if ok else "**not met**")

    rows = [
        ("collisions in < 1 % of frames", coll, coll is not None and coll < 0.01, 100.0),
        ("fewer collisions than B1", coll, None if coll_b1 is None or coll is None else coll < coll_b1, 100.0),
        ("trajectory error < 0.15 m mean", tr, tr is not None and tr < 0.15, 1.0),
        ("no root step > 0.25 m per frame near a join", jump, jump is not None and jump <= 0.25, 1.0),
        ("boundary jerk < 1.5", jerk, jerk is not None and jerk < 1.5, 1.0),
        ("per-dancer FID_k ≤ B1's + 10 %", fid, None if fid is None or fid_b1 is None else fid <= 1.1 * fid_b1, 1.0),
    ]
    L.append("| target | full system | verdict |")
    L.append("|---|---|---|")
    for name, v, ok, scale in rows:
        L.append(f"| {name} | {fmt(v, None, 3, scale)} | {verdict(ok)} |")
    L.append("")
    issue43_targets(L.append, results, seeds, real_solo, fid_b1, fid_rr_b1)
    write_report(args.report, L)


def worst_dancer(results, cfg, seeds, key, worst=max):
    """The worst value of a physical figure over every dancer of every seed (per_clip rows)."""
    v = []
    for s in seeds:
        j = json.load(open(results[(cfg, s)]["physical"])) if (cfg, s) in results else {}
        v += [r[key] for r in j.get("per_clip", []) if r.get(key) is not None]
    return worst(v) if v else None


def issue43_targets(w, results, seeds, real_solo, fid_b1, fid_rr_b1):
    """The "Done when" of issue 43 (the group model out of its collapse), for the full system
    (formation control) and the free dance side by side."""
    cfgs = [c for c in ("full", "free") if (c, seeds[0]) in results]
    if not cfgs:
        return
    real = json.load(open(real_solo["physical_json"]))
    real_spread = real_solo.get("spread")
    rm = lambda k: statistics.fmean(  # noqa: E731
        [r[k] for r in real.get("per_clip", []) if r.get(k) is not None] or [float("nan")])
    lc, jk, fs, fl = rm("leg_cross"), rm("jerk"), rm("foot_slide"), rm("float")
    floor = [r["floor_median"] for r in real.get("per_clip", []) if r.get("floor_median") is not None]
    flo, fhi = min(floor) - 0.03, max(floor) + 0.03

    def num(x, d=3):
        return "n/a" if x is None else f"{x:.{d}f}"

    def cell(v, ok, d=3):
        return f"{num(v, d)} ({'n/a' if v is None or ok is None else 'met' if ok else '**not met**'})"

    def figures(cfg):
        g = lambda f: stats(per_seed(results, cfg, seeds, f))[0]  # noqa: E731
        diffs = []
        if len(seeds) > 1:
            for a, b in zip(results[(cfg, seeds[0])]["scene_paths"],
                            results[(cfg, seeds[1])]["scene_paths"]):
                diffs.append(seed_difference_cm(a, b))
        spread, diff = g(lambda r: r["spread"]), mean_or_none(diffs)
        contrast, unison = g(lambda r: r["closest_contrast"]), g(lambda r: r["closest_unison"])
        fid, coll = g(lambda r: r["dancers"].get("fid_k")), g(lambda r: r["scenes"].get("collision"))
        fid_rr = g(lambda r: r["dancers_rr"].get("fid_k"))
        step = max(results[(cfg, s)]["root_step"] for s in seeds if (cfg, s) in results)
        margins = [m for s in seeds if (cfg, s) in results for m in results[(cfg, s)]["bas_margin"]]
        worst_margin = min(margins) if margins else None
        tr = g(lambda r: mean_or_none([m.get("trajectory_error_mean_m") for _, m in r["metas"]]))
        order = g(lambda r: end_order_ok(None, r)) if cfg == "full" else None
        wd = lambda k, f=max: worst_dancer(results, cfg, seeds, k, f)  # noqa: E731
        lo, hi = wd("floor_median", min), wd("floor_median")
        return [
            cell(spread, None if spread is None or real_spread is None else spread >= 0.7 * real_spread, 2),
            cell(diff, None if diff is None else diff >= 5.0, 2),
            cell(contrast, None if contrast is None else contrast >= 3.0, 2),
            num(unison, 2),
            cell(fid, None if fid is None or fid_b1 is None else fid <= fid_b1, 1),
            cell(fid_rr, None if fid_rr is None or fid_rr_b1 is None else fid_rr <= fid_rr_b1, 1),
            cell(None if coll is None else 100 * coll, None if coll is None else coll <= 0.01, 2),
            cell(step, step <= TELEPORT_M),
            cell(worst_margin, None if worst_margin is None else worst_margin >= 0.03),
            f"{sum(m >= 0.03 for m in margins)} of {len(margins)}" if margins else "n/a",
            cell(tr, None if tr is None else tr <= 0.05) if cfg == "full" else "-",
            cell(None if order is None else 100 * order, None if order is None else order >= 1.0, 0)
            if cfg == "full" else "-",
            *[cell(v, None if v is None else ok(v)) for v, ok in [
                (wd("leg_cross"), lambda v: v <= lc + 2),
                (wd("jerk"), lambda v: v <= 1.5 * jk),
                (wd("foot_slide"), lambda v: v <= 1.5 * fs),
                (wd("float"), lambda v: v <= fl + 5)]],
            f"{num(lo)} .. {num(hi)} ({'n/a' if lo is None else 'met' if lo >= flo and hi <= fhi else '**not met**'})",
        ]

    names = [
        ("pose spread cm", f"≥ {num(None if real_spread is None else 0.7 * real_spread, 2)} (0.7 × real)"),
        ("seeds differ cm (seeds 0 and 1)", "≥ 5"),
        ("closest pair of dancers cm, contrast scenes", "≥ 3"),
        ("closest pair of dancers cm, unison scenes (reported)", "-"),
        ("FID_k (positions as given)", f"≤ B1's {num(fid_b1, 1)}"),
        ("FID_k root-relative", f"≤ B1's {num(fid_rr_b1, 1)}"),
        ("collisions % of frames", "≤ 1"),
        ("largest root step in one frame m (every dancer and seed)", f"≤ {TELEPORT_M}"),
        ("BAS − BAS against half-beat-shifted beats, worst dancer", "≥ 0.03"),
        ("  dancers with that margin ≥ 0.03", "-"),
        ("trajectory error mean m", "≤ 0.05"),
        ("end order as requested %", "100"),
        ("leg_cross %, worst dancer", f"≤ {lc + 2:.1f} (real + 2 points)"),
        ("jerk m/s³, worst dancer", f"≤ {1.5 * jk:.0f} (1.5 × real)"),
        ("foot_slide m/s, worst dancer", f"≤ {1.5 * fs:.3f} (1.5 × real)"),
        ("float %, worst dancer", f"≤ {fl + 5:.1f} (real + 5 points)"),
        ("floor_median m, every dancer", f"{flo:.3f} .. {fhi:.3f} (real ± 3 cm)"),
    ]
    cols = {c: figures(c) for c in cfgs}
    label = {"full": "full system (formation control)", "free": "free dance"}
    w("## Targets (issue 43: the group model out of its collapse)")
    w("")
    w("| target | bound | " + " | ".join(label[c] for c in cfgs) + " |")
    w("|---|---|" + "---|" * len(cfgs))
    for k, (name, bound) in enumerate(names):
        w(f"| {name} | {bound} | " + " | ".join(cols[c][k] for c in cfgs) + " |")
    w("")
    w("Physical bounds are the held-out real solo tracks' mean over their clips (the last row of "
      "the physical table; the floor: their range); each figure is the worst single dancer over "
      "every clip and seed. The largest root step here is over these 10 s clips; the 90 s songs "
      "with 2 to 5 dancers are `cargo test -p dancegen-generate --test group_root_steps`.")
    w("")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", required=True)
    ap.add_argument("--dataset", required=True)
    ap.add_argument("--data", required=True, help="../shared/data")
    ap.add_argument("--model", required=True)
    ap.add_argument("--solo-model", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--report", required=True)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--per-n", type=int, default=4)
    ap.add_argument("--steps", type=int, default=None)
    ap.add_argument("--load-note", default="")
    ap.add_argument("--only", nargs="*", default=[], metavar="KEY",
                    help="main configurations to run (default all: " +
                    " ".join(k for k, _, _, _ in CONFIGS) + ")")
    ap.add_argument("--group-args", default="",
                    help="extra `dancegen generate` arguments for the group dances, e.g. "
                    "'--guidance 1' (the report names them)")
    ap.add_argument("--contact-png", default="",
                    help="where to draw the contact sheet (none without it)")
    ap.add_argument("--ablation", nargs="*", default=[], metavar="KEY=BUNDLE",
                    help="ablation bundles to add as rows, e.g. no_fp=target/ablations/no_fp")
    args = ap.parse_args()
    GROUP_ARGS[:] = args.group_args.split()
    runs(args)  # checks --ablation before any work
    started = time.time()
    os.makedirs(args.out, exist_ok=True)
    clips = select_clips(args.dataset, args.per_n, args.out)
    if not clips:
        raise SystemExit(f"{args.dataset}: no held-out group clips with N = 2, 3 or 5")
    log(f"{len(clips)} clips: {' '.join(c['name'] for c in clips)}")
    results, real_couples, real_solo = evaluate(args.bin, args, clips, args.out)
    contact(args, clips, results)
    report(args, clips, results, real_couples, real_solo, started, args.load_note)


def contact(args, clips, results):
    """The contact sheet: the first clip danced by the full system (first seed) and the held-out
    real salsa couple 13 (takes 60_13 / 61_13 from their start), at the same moments."""
    info = os.path.join(args.out, "contact.json")
    if os.path.exists(info):
        os.remove(info)
    seed = args.seeds[0]
    if not args.contact_png:
        return
    if ("full", seed) not in results:
        log("no contact sheet: the full system was not run")
        return
    c = clips[0]
    gen = [p for p in results[("full", seed)]["dancer_paths"]
           if os.path.basename(p).startswith(c["name"] + "_d")]
    real = [os.path.join(args.out, "real", f"{t}.npy") for t in ("60_13_scaled", "61_13_scaled")]
    caption = (f"TCDiff++ (`{os.path.relpath(args.model)}`, full system, seed {seed}) dancing "
               f"the held-out clip `{c['name']}` ({c['dancers']} dancers, "
               f"{os.path.basename(c['song'])} from {c['start']:.1f} s), and the held-out real "
               "salsa couple 13 (takes 60_13 and 61_13 from their start, at 60 fps)")
    make_contact_sheet(args.bin, args.contact_png, info, caption,
                       [(f"generated {c['name']} (full, seed {seed})", gen),
                        ("real couple 13", real)],
                       os.path.join(args.out, "contact"))


if __name__ == "__main__":
    main()
