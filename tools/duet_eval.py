#!/usr/bin/env python3
"""Helper of tools/duet_eval.sh (Python standard library only).

Subcommands:
  clips   the duet manifest's clips as shell-readable lines (held-out clips with their song cut,
          and all real clips for the FID reference set)
  model   block length and name of a ReactDance model directory (model.toml)
  stub    --dry-run "generation": a real follower moved by a few cm (plumbing only)
  meta    write the run's header facts (key=value arguments) as JSON
  report  collect the `dancegen eval` JSON files, recompute the boundary-jerk ratio at each
          sampler's real seams, and write the Markdown report

Boundary jerk: `dancegen eval --window N` (N = the model's block, 60 latent tokens × 4 frames =
240) already returns a ratio (in-band jerk / rest, `dancegen_metrics::longform`), and for BLC the
seams are exactly those multiples of N, so eval's value is used as is. The autoregressive
ablation's seams are not evenly spaced (windows every N/2 after the first, the last one aligned
to the end), so for it the ratio is recomputed here with the same definition (the functions of
tools/solo_eval.py, checked against eval's own per-clip values at multiples of N in every run,
see the parity note in the report).
"""

import argparse
import json
import math
import os
import statistics
import sys
import tomllib
from array import array

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from solo_eval import (  # noqa: E402  (shared .npy I/O, jerk, formatting, physical helpers)
    boundary_jerk_ratio,
    contact_section,
    fmt,
    load,
    mean_joint_jerk,
    motion,
    opt_load,
    physical_note,
    physical_over,
    physical_table,
    rates_note,
    stats,
    write_npy,
    write_report,
)

# name, label, sampler (decides the seams)
CONFIGS = [
    ("full", "ReactDance (full system: BLC + layer-wise guidance; foot lock, beat alignment, "
     "separation)", "blc"),
    ("no_foot_lock", "w/o foot lock (`--no-foot-lock`; the follower's root glides as generated)",
     "blc"),
    ("no_separation", "w/o couple separation (`--no-separation`; the model's raw placement)",
     "blc"),
    ("no_beat_align", "w/o beat alignment (`--no-beat-align`; the follower's timing as generated)",
     "blc"),
    ("single_cfg", "single-scale CFG (`--guidance 2.0`, s = 1 on every level)", "blc"),
    ("autoregressive", "autoregressive sampling (`--sampler autoregressive`, w/o BLC)",
     "autoregressive"),
    ("m64", "trained with window stride 64 (not 4)", "blc"),
    ("no_pm", "autoencoder w/o progressive masking", "blc"),
]
CONFIG = {c[0]: c for c in CONFIGS}
# Issue 16's duet targets (its "Done when" table).
ISSUE16_FID_K = 245.0
ISSUE16_BED = 0.47
METRICS = ("fid_k", "fid_g", "div_k", "div_g", "pfc", "mpjpe", "freeze", "boundary_jerk",
           "fid_cd", "div_cd", "bed", "ipr", "contact_range")


# ----------------------------------------------------------------------------- subcommands


def cmd_clips(args):
    """held-out lines: stem start song frames follower.npz leader.npz (to --heldout);
    all real clips: stem follower.npz leader.npz (to --all)."""
    m = load(args.manifest)
    base = os.path.dirname(os.path.abspath(args.manifest))

    def song_path(p):
        if os.path.isabs(p):
            return p
        for d in (args.root, base):  # the builder records paths relative to the repo root
            if os.path.exists(os.path.join(d, p)):
                return os.path.realpath(os.path.join(d, p))
        sys.exit(f"{p}: song not found (relative to {args.root} or {base})")

    clips = m["clips"]
    stems = [c["name"] for c in clips]
    if len(set(stems)) != len(stems):
        sys.exit("duplicate clip names in the manifest")
    held = set(m["held_out"])
    missing = held - set(stems)
    if missing:
        sys.exit(f"held-out clips missing from the clip list: {sorted(missing)}")
    with open(args.heldout, "w") as fh, open(args.all, "w") as fa:
        for c in clips:
            mot, lead = (os.path.join(base, c[k]) for k in ("motion", "leader"))
            for p in (mot, lead):
                if not os.path.exists(p):
                    sys.exit(f"{c['name']}: {p} missing")
            for s in (c["name"], mot, lead):
                if any(ch.isspace() for ch in s):
                    sys.exit(f"whitespace in {s!r} (the driver reads space-separated lines)")
            fa.write(f"{c['name']} {mot} {lead}\n")
            if c["name"] in held:
                song = song_path(c["source_song"])
                if any(ch.isspace() for ch in song):
                    sys.exit(f"whitespace in {song!r}")
                fh.write(f"{c['name']} {c['song_start_s']!r} {song} {c['frames']} {mot} "
                         f"{lead}\n")


def model_info(d):
    with open(os.path.join(d, "model.toml"), "rb") as f:
        cfg = tomllib.load(f)
    if cfg.get("kind") != "reactdance":
        raise SystemExit(f"{d}/model.toml: kind {cfg.get('kind')!r}, not a ReactDance model")
    fpt = 2 ** cfg["autoencoder"]["down_t"]
    block = cfg["denoiser"]["block_tokens"]
    s = cfg.get("sampling", {})
    return {"window": block * fpt, "fpt": fpt, "block_tokens": block,
            "steps": s.get("steps", "?"), "guidance": s.get("guidance", "?"),
            "name": cfg.get("name", "?")}


def cmd_model(args):
    """Tab-separated: window fpt block_tokens steps guidance name."""
    i = model_info(args.model)
    print("\t".join(str(i[k]) for k in ("window", "fpt", "block_tokens", "steps", "guidance",
                                          "name")))


def cmd_stub(args):
    """The real follower, moved horizontally by (seed + 1) × 3 cm in x and z."""
    frames, a = motion(args.src)
    d = 0.03 * (args.seed + 1)
    out = array("f", a)
    for i in range(0, len(out), 3):
        out[i] += d
        out[i + 2] += d
    write_npy(args.out, out, "<f4", (frames, 24, 3))


def cmd_meta(args):
    meta = {}
    for kv in args.pairs:
        k, _, v = kv.partition("=")
        meta[k] = v
    with open(args.out, "w") as f:
        json.dump(meta, f, indent=1)


# ----------------------------------------------------------------------------- seams


def seams(sampler, frames, window, fpt, block_tokens):
    """First frames of new content, as `dancegen_reactdance::blc::sample_latent` places it."""
    if sampler == "blc" or sampler == "grid":  # disjoint blocks of `block_tokens` tokens
        return list(range(window, frames, window))
    k = -(-frames // fpt)  # latent tokens: ceil(T / frames per token)
    t = block_tokens
    if k <= t:
        return []
    hop = t // 2
    starts = []
    i = 0
    while i * hop + t < k:
        starts.append(i * hop)
        i += 1
    starts.append(k - t)
    # window i (≥ 1) adds the tokens from the end of the sequence so far, starts[i-1] + t
    out = sorted({(starts[i - 1] + t) * fpt for i in range(1, len(starts))})
    return [b for b in out if 0 < b < frames]


# ----------------------------------------------------------------------------- report


def mean_def(vals):
    vals = [v for v in vals if v is not None]
    return statistics.fmean(vals) if vals else None


def cmd_report(args):
    out = args.out
    seeds = args.seeds.split()
    lines = [ln.split() for ln in open(os.path.join(out, "clips.txt")) if ln.strip()]
    clips = [p[0] for p in lines]
    lo, hi = min(int(p[3]) for p in lines), max(int(p[3]) for p in lines)
    n_all = sum(1 for ln in open(os.path.join(out, "all.txt")) if ln.strip())
    meta = load(os.path.join(out, "meta.json"))
    # configs.tsv: name status model_dir window fpt block_tokens steps guidance model_name
    cinfo = {}
    for ln in open(os.path.join(out, "configs.tsv")):
        p = ln.rstrip("\n").split("\t")
        if len(p) >= 9:
            cinfo[p[0]] = {"status": p[1], "model": p[2], "window": int(p[3] or 0),
                           "fpt": int(p[4] or 0), "block": int(p[5] or 0), "steps": p[6],
                           "guidance": p[7], "name": p[8]}
    wanted = args.configs.split()
    configs = [c for c in CONFIGS if c[0] in wanted]
    run = [c for c in configs if cinfo.get(c[0], {}).get("status") == "ok"]
    skipped = [c for c in configs if c not in run]
    parity = [0.0, 0]  # largest relative difference to eval's boundary_jerk, clips compared

    def stem(p):
        return os.path.splitext(os.path.basename(p))[0]

    def bjerk(paths, sampler, info, ev):
        """Per-clip ratio at the sampler's seams; parity with eval's value on eval's grid."""
        by_stem = {stem(r["file"]): r.get("boundary_jerk") for r in ev["per_clip"]}
        vals = []
        for p in paths:
            frames, a = motion(p)
            jerk = mean_joint_jerk(a, frames)
            mine = boundary_jerk_ratio(jerk, seams("grid", frames, info["window"], 0, 0))
            theirs = by_stem.get(stem(p))
            if (mine is None) != (theirs is None):
                parity[0] = math.inf
            elif mine is not None:
                parity[0] = max(parity[0], abs(mine - theirs) / max(abs(theirs), 1e-12))
            parity[1] += 1
            if sampler == "blc":
                vals.append(theirs)
            else:
                vals.append(boundary_jerk_ratio(
                    jerk, seams(sampler, frames, info["window"], info["fpt"], info["block"])))
        return mean_def(vals)

    # ---- real held-out followers (evaluated once, at the full model's block grid)
    rj = load(os.path.join(out, "eval", "real", "eval.json"))
    real = {k: rj.get(k) for k in METRICS}
    real_window = int(meta.get("real_window", 240))

    # ---- generated: per config, per seed (seeds whose generation failed are missing)
    data, done = {}, {}
    for name, _, sampler in run:
        data[name], done[name] = {}, []
        info = cinfo[name]
        for s in seeds:
            ej = opt_load(os.path.join(out, "eval", name, f"seed{s}", "eval.json"))
            if ej is None:
                continue
            done[name].append(s)
            row = {k: ej.get(k) for k in METRICS}
            paths = [os.path.join(out, "gen", name, f"seed{s}", c + ".npy") for c in clips]
            row["boundary_jerk"] = bjerk(paths, sampler, info, ej)
            for k, v in row.items():
                data[name].setdefault(k, []).append(v)
    # parity on the real clips too
    bjerk([os.path.join(out, "gt", c + ".npy") for c in clips], "blc",
          {"window": real_window, "fpt": 0, "block": 0}, rj)

    # ---- render
    L = []
    w = L.append
    w("# Duet evaluation (ReactDance) on the held-out couples")
    w("")
    if args.dry_run:
        w("> **DRY RUN — NOT MODEL OUTPUT.** Each \"generated\" follower is the real held-out "
          "follower moved by (seed + 1) × 3 cm in x and z (`tools/duet_eval.sh --dry-run`); "
          "these numbers only test the plumbing. Translation-invariant metrics (pelvis-aligned "
          "MPJPE, BED, PFC, freeze, boundary jerk, ...) equal the real row.")
        w("")
    w(f"Generated by `{meta['command']}` on {meta['date']} (commit `{meta['commit']}`"
      f"{', with uncommitted changes in the working tree' if meta.get('dirty') == 'true' else ''}"
      f"); binary `{meta['binary']}`; machine: {meta['nproc']} cores, {meta['load']}; wall time "
      f"{meta['wall']}.")
    w("")
    seed_note = meta.get("seed_note", "")
    w(f"Seeds: {' '.join(seeds)} (each configuration generates every held-out clip once per "
      f"seed). {seed_note}".rstrip())
    w("")
    w("| configuration | model | model.toml name | block (frames) | sampling |")
    w("|---|---|---|---|---|")
    for name, label, _ in configs:
        i = cinfo.get(name)
        if i is None:
            continue
        if i["status"] == "ok" and i["name"].startswith("("):  # dry run: no model read
            w(f"| {label} | `{i['model']}` | {i['name'][1:-1]} | {i['window']} | n/a |")
        elif i["status"] == "ok":
            steps = meta.get("steps") or f"{i['steps']} (model's)"
            w(f"| {label} | `{i['model']}` | `{i['name']}` | {i['window']} | steps {steps}, "
              f"model guidance {i['guidance']} |")
        else:
            w(f"| {label} | `{i['model']}` | — | — | **skipped: {i['status']}** |")
    w("")
    if skipped:
        w("**Not evaluated:** " + "; ".join(
            f"{label} ({cinfo.get(n, {}).get('status', 'not configured')})"
            for n, label, _ in skipped) + ". Train the model (or set its directory: "
          "`MODEL_M64`, `MODEL_NO_PM`) and re-run; finished generations of the other "
          "configurations are reused.")
        w("")
    failed = [f"{n} (seeds done: {' '.join(done[n]) or 'none'})" for n, *_ in run
              if len(done[n]) < len(seeds)]
    if failed:
        w(f"**Incomplete:** generation failed or was not run for: {'; '.join(failed)} — see "
          f"`{meta['out']}/failed.txt`. Those rows average the seeds that finished.")
        w("")

    def label_of(name, label):
        n = len(done[name])
        return label if n == len(seeds) else f"{label} ({n} of {len(seeds)} seeds)"

    cols = [
        ("fid_k", "FID_k ↓", 2, 1.0),
        ("fid_g", "FID_g ↓", 2, 1.0),
        ("div_k", "Div_k", 2, 1.0),
        ("div_g", "Div_g", 2, 1.0),
        ("fid_cd", "FID_cd ↓", 2, 1.0),
        ("div_cd", "Div_cd", 2, 1.0),
        ("bed", "BED ↑", 4, 1.0),
        ("ipr", "IPR % ↓", 2, 100.0),
        ("contact_range", "Contact range %", 1, 100.0),
        ("mpjpe", "MPJPE mm ↓", 1, 1000.0),
        ("pfc", "PFC ↓", 3, 1.0),
        ("freeze", "Freeze % ↓", 2, 100.0),
        ("boundary_jerk", "Boundary jerk ↓", 3, 1.0),
    ]
    w(f"## Results ({len(clips)} held-out clips × {len(seeds)} "
      f"seed{'s' if len(seeds) != 1 else ''} per configuration)")
    w("")
    w("| configuration | " + " | ".join(c[1] for c in cols) + " |")
    w("|---|" + "---|" * len(cols))
    rows = [("real followers (held-out, reference)", {k: (v, None) for k, v in real.items()})]
    for name, label, _ in run:
        rows.append((label_of(name, label), {k: stats(v)[:2] for k, v in data[name].items()}))
    for b_out, b_label in zip(args.baseline, args.baseline_label):
        # An earlier run's full system (another model) on the same clips: its eval JSON as it
        # was written, boundary jerk at its BLC grid (eval's value).
        b = {}
        b_seeds = []
        for s in seeds:
            ej = opt_load(os.path.join(b_out, "eval", "full", f"seed{s}", "eval.json"))
            if ej is None:
                continue
            b_seeds.append(s)
            for k in METRICS:
                b.setdefault(k, []).append(ej.get(k))
        if not b_seeds:
            sys.exit(f"--baseline {b_out}: no eval/full/seed*/eval.json for seeds {seeds}")
        rows.append((f"before: {b_label} (`{b_out}`, seeds {' '.join(b_seeds)})",
                     {k: stats(v)[:2] for k, v in b.items()}))
    for label, vals in rows:
        cells = [fmt(*vals.get(k, (None, None)), d, sc) for k, _, d, sc in cols]
        w(f"| {label} | " + " | ".join(cells) + " |")
    w("")
    w("Mean ± standard deviation over the seeds (n − 1; one seed: the mean alone). Each seed's "
      "value is `dancegen eval`'s over its 4 clips (FID/Div: of the set, the others: the mean "
      "over the clips, PFC: EDGE's mean × 10⁴).")
    w("")

    # ---- physical plausibility of the followers (+ the contact sheet)
    n_train = sum(1 for f in os.listdir(os.path.join(out, "gt_train")) if f.endswith(".npy")) \
        if os.path.isdir(os.path.join(out, "gt_train")) else 0
    w("## Physical plausibility (followers)")
    w("")
    prow = [(f"real followers (the {len(clips)} held-out clips)",
             physical_over([os.path.join(out, "eval", "real", "physical.json")])),
            (f"real followers (the {n_train} training clips)",
             physical_over([os.path.join(out, "eval", "real", "physical_train.json")]))]
    for name, label, _ in run:
        prow.append((label_of(name, label), physical_over(
            [os.path.join(out, "eval", name, f"seed{s}", "physical.json") for s in done[name]])))
    for b_out, b_label in zip(args.baseline, args.baseline_label):
        prow.append((f"before: {b_label} (`{b_out}`)", physical_over(
            [os.path.join(b_out, "eval", "full", f"seed{s}", "physical.json") for s in seeds])))
    physical_table(w, prow)
    physical_note(w, rates_note(meta.get("manifest")),
                  "The followers alone (`dancegen eval --pred DIR --fps 30 --metrics physical`, "
                  f"no leader), {len(clips)} held-out clips per seed; generated rows are mean ± "
                  "standard deviation over the seeds"
                  + ("; \"-\": a baseline run that did not measure the figures." if args.baseline
                     else "."))
    contact_section(w, os.path.join(out, "contact.json"), args.report, "### Contact sheet")

    # ---- targets
    def verdict(ok):
        return "n/a" if ok is None else ("✅ met" if ok else "❌ not met")

    def checks(name):
        d = data.get(name, {})
        # Issue 16's two duet targets: half of each gap to the real followers closed from its
        # starting point (BED 0.30, FID_k 447).
        m, s, _ = stats(d.get("fid_k", []))
        out_ = [(f"FID_k ≤ {ISSUE16_FID_K} (issue 16; real followers: "
                 f"{fmt(real['fid_k'], None, 2)})", fmt(m, s, 2),
                 None if m is None else m <= ISSUE16_FID_K)]
        m, s, _ = stats(d.get("bed", []))
        out_.append((f"BED ≥ {ISSUE16_BED} (issue 16; real followers: "
                     f"{fmt(real['bed'], None, 4)})", fmt(m, s, 4),
                     None if m is None else m >= ISSUE16_BED))
        m, s, _ = stats(d.get("boundary_jerk", []))
        out_.append((f"boundary-jerk ratio < 1.5 (real followers: "
                 f"{fmt(real['boundary_jerk'], None, 3)})", fmt(m, s, 3),
                 None if m is None else m < 1.5))
        m, s, _ = stats(d.get("ipr", []))
        lim = None if real["ipr"] is None else real["ipr"] + 0.02
        out_.append((f"IPR < real + 2 points = {fmt(lim, None, 2, 100.0)} % (real "
                     f"{fmt(real['ipr'], None, 2, 100.0)} %)", fmt(m, s, 2, 100.0) + " %",
                     None if m is None or lim is None else m < lim))
        return out_

    w("## Targets")
    w("")
    if "full" in data:
        full = checks("full")
        met = sum(1 for c in full if c[2])
        w(f"**Full system: {met} of {len(full)} targets met** (checked by the script on the "
          "means over seeds):")
        w("")
        w("| target | full system | verdict |")
        w("|---|---|---|")
        for t, v, ok in full:
            w(f"| {t} | {v} | {verdict(ok)} |")
        w("")
    else:
        w("The full system was not evaluated (see above): no verdict.")
        w("")
    others = [c for c in run if c[0] != "full"]
    if others:
        w("The same checks for the ablations (for comparison; the targets are for the full "
          "system):")
        w("")
        w("| target | " + " | ".join(c[0] for c in others) + " |")
        w("|---|" + "---|" * len(others))
        per = {c[0]: checks(c[0]) for c in others}
        for i, (t, _, _) in enumerate(checks(others[0][0])):
            cells = []
            for c in others:
                _, v, ok = per[c[0]][i]
                cells.append("n/a" if ok is None else f"{'✅' if ok else '❌'} {v}")
            w(f"| {t.split(' (')[0]} | " + " | ".join(cells) + " |")
        w("")

    # ---- how to read
    w("## How to read")
    w("")
    w(f"- **Task**: each held-out clip ({', '.join('`' + c + '`' for c in clips)}: CMU salsa "
      "takes 60/61 × 13/14, each couple in both role assignments) gives its real leader and "
      "its song cut (`song_start_s` of the manifest) to "
      "`dancegen generate SONG --start S --leader LEADER.npz --model DIR --seed N [flags] "
      "-o follower.npy`; the follower has the leader's length and lives in the leader's world "
      f"frame. Metrics: `dancegen eval --pred GEN --leader LEADERS --gt GT --gt-leader "
      f"GT_LEADERS --fps 30 --window <block> --metrics {','.join(METRICS)}` (protocol `none`: "
      "world positions as generated, frame time 1/30).")
    w(f"- **Reference set**: FID_k, FID_g, FID_cd and the features' normalisation use all "
      f"{n_all} real follower clips of the data set with their real leaders ({n_all - len(clips)} "
      f"training + {len(clips)} held-out): the {len(clips)} held-out clips alone would make a "
      "degenerate FID (zero spread in some feature dimensions). The set includes the training "
      "clips, so it favours motion close to the training data, and it includes the held-out "
      "clips themselves, so the real row's FID is optimistic. Compare configurations with each "
      "other and with the real row, not with published numbers.")
    w("- **MPJPE** compares each generated follower with the real follower of the same clip "
      "(the leader's actual partner), pelvis-aligned (SoulDance's definition), in millimetres: "
      "0 for the real row by construction. A follower can be good and far from this one take, "
      "so it is a loose reference.")
    w("- **Real row**: the 4 real held-out followers with their leaders, evaluated as if they "
      "were predictions (same command). It is the target level for every metric: the closer a "
      "configuration is to it, the better, also for the columns without an arrow.")
    w("- **FID_k / FID_g** (↓): Fréchet distance of the follower's kinetic / geometric features "
      "to the reference set's. **Div_k / Div_g**: mean pairwise distance of those features "
      "within the set (variety; closer to the real row is better).")
    w("- **FID_cd / Div_cd** (Duolando): the same on the 100-d cross-distance feature (time-"
      "mean distances between 10 key joints of the follower and 10 of the leader): how "
      "realistically the follower is placed relative to its leader.")
    w("- **BED** (↑, Duolando's Beat Echo Degree): how well the follower's motion beats echo "
      "the leader's (1 = every leader beat has a follower beat on it).")
    bed_all = os.path.join(out, "eval", "real_all_bed.json")
    if os.path.exists(bed_all):
        # Every real couple of the reference set, so the held-out couples' BED can be read in
        # scale (`dancegen eval --pred gt_all --leader gt_leader_all --metrics bed`).
        per = {os.path.splitext(os.path.basename(c["file"]))[0]: c.get("bed")
               for c in load(bed_all)["per_clip"]}
        def spread(vals):
            vals = [v for v in vals if v is not None]
            sd = f" ± {statistics.stdev(vals):.3f}" if len(vals) > 1 else ""
            return f"{statistics.fmean(vals):.3f}{sd} ({min(vals):.3f}–{max(vals):.3f})"
        rest = [v for c, v in per.items() if c not in clips]
        if rest:
            w(f"  For scale: the {len(rest)} other real couples of the reference set (the "
              f"training couples) have a BED of {spread(rest)}; the {len(clips)} held-out "
              f"couples {spread([per.get(c) for c in clips])}.")
    w("- **IPR** (↓): share of frames in which the two dancers' capsule bodies intersect (our "
      "definition: ReactDance's code is unreleased). Real salsa holds hands and dances close, "
      "and capsules are coarse, so the real row is not 0; the target allows 2 points above it. "
      "**Contact range**: share of frames within 0.3 m (a forearm) of touching; closer to the "
      "real row is better (too low: the follower drifts away; too high with a high IPR: it "
      "sticks to or walks through the leader).")
    w("- **PFC** (↓, EDGE's Physical Foot Contact) and **Freeze** (↓, share of 1-second windows "
      "whose mean joint speed is under 5 % of the clip's median) are solo-quality checks of "
      "the follower.")
    n_lo, n_hi = (len(seams("blc", n, real_window, 0, 0)) for n in (lo, hi))
    n_seams = f"{n_lo}" if n_lo == n_hi else f"{n_lo}–{n_hi}"
    gap = (f"{parity[0]:.1e}" if math.isfinite(parity[0]) else "∞ (a value undefined on one "
           "side only)")
    w(f"- **Boundary jerk** (↓; ≈ 1 = seams as smooth as the rest, ≫ 1 = pose jumps at the "
      f"seams): mean jerk within ±2 frames of the sampler's seams divided by the mean jerk "
      f"elsewhere. BLC (every configuration but autoregressive) has its seams at every "
      f"block of 60 latent tokens ({real_window} frames for the 4-frame tokens), exactly "
      f"`dancegen eval --window <block>`'s grid, so eval's value is used as is. The "
      f"autoregressive sampler's seams are where each window's new half begins (after the "
      f"first block, every half block, the last window aligned to the clip's end); "
      f"`tools/duet_eval.py` recomputes the ratio there with eval's definition (parity: at "
      f"eval's grid it reproduces eval's per-clip value on all {parity[1]} clips within "
      f"{gap}, relative). The real followers have no seams: their value, at the "
      f"{real_window}-frame grid, shows the metric's noise. The clips are {lo / 30:.0f}–"
      f"{hi / 30:.0f} s long, so they have only {n_seams} BLC seams each: a rough check.")
    w("- **m64** is the same system trained with sliding windows every 64 frames instead of "
      "every 4 (fewer, less overlapping training windows); **no_pm** trains the autoencoder "
      "without progressive masking; **single_cfg** replaces the layer-wise guidance (LDCFG, "
      "one scale per HFSQ level) by one scale s = 1 for every level; **no_separation** keeps "
      "the follower where the model put it. The separation (ours, not in the paper: "
      "`dancegen_refine::couple_separation`) moves the follower horizontally, by a smooth "
      "offset, out of the leader's capsule body wherever trunks, heads, arms or legs overlap; "
      "hands may touch. Its capsule body is the canonical one of the self-penetration "
      "measures, not IPR's coarser bone capsules. Its margin, smoothing and rounds were set "
      "before any run on these clips; its direction rule was not: pushing only along the "
      "closest points of the deepest overlap left 3–20 % of these clips' frames overlapping "
      "(IPR 20.3 %, seed 0), because an arm round the partner's back gets pushed through the "
      "partner and neighbouring frames cancel, so such pushes now step back along the "
      "pelvis-to-pelvis line. Every row but no_separation has the separation on.")
    w("- **no_foot_lock** leaves the follower's root as decoded. The foot lock (ours, not in the "
      "paper: `dancegen_lodgepp::planted_feet::lock_planted_feet_leashed`, run before the beat "
      "alignment and the separation) removes the horizontal glide of the support foot on "
      "frames where the model's contact channel and nearness to the floor both say planted, "
      "and gives that correction back with a 30-frame time constant, so the follower keeps the "
      "place the model gives it beside the leader. Why: the model decodes the follower's "
      "position relative to the leader, and real partners' relative motion cancels much of "
      "the leader's travel while the model's does not, so its followers glide (pelvis "
      "1.6 m/s against the real followers' 1.0 on these clips). Its rule and leash were chosen "
      "on four training couples (docs/solo-data-v2.md, round eight). No leg IK: pinning each "
      "contact run's feet raised MPJPE by 40 mm there and on these clips. Every row but "
      "no_foot_lock has the foot lock on.")
    w("")

    # ---- generation time
    w("## Generation time")
    w("")
    w("| configuration | clips timed | generation (s per clip) | whole `generate` call (s per "
      "clip) |")
    w("|---|---|---|---|")
    total = 0.0
    for name, label, _ in run:
        g, t = [], []
        tp = os.path.join(out, "gen", name, "times.tsv")
        last = {}
        if os.path.exists(tp):
            for ln in open(tp):
                p = ln.rstrip("\n").split("\t")
                if len(p) >= 5 and p[0] in seeds:
                    last[(p[0], p[1])] = p  # the last run of each output
        for p in last.values():
            if p[2] not in ("", "-"):
                g.append(float(p[2]))
            t.append(float(p[4]))
        total += sum(t)
        sd = (lambda v: f" ± {statistics.stdev(v):.2f}" if len(v) > 1 else "")
        w(f"| {label} | {len(t)} | {f'{statistics.fmean(g):.2f}' + sd(g) if g else 'n/a'} | "
          f"{f'{statistics.fmean(t):.2f}' + sd(t) if t else 'n/a'} |")
    w("")
    w("\"Generation\" is what `dancegen generate` prints as `generated in X s` (latent sampling, "
      f"decoding and the separation, for {lo}–{hi}-frame clips); the whole call adds model loading, music "
      "analysis and writing (process wall time). Other jobs shared the CPU (see the load in the "
      f"header). Total generation wall time behind this report: {total / 60:.1f} min (outputs "
      "of earlier runs with the same model files and flags are reused, so the run's wall time "
      "can be shorter).")
    w("")
    write_report(args.report, L)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("clips")
    p.add_argument("--manifest", required=True)
    p.add_argument("--root", required=True, help="repository root (song paths are relative)")
    p.add_argument("--heldout", required=True)
    p.add_argument("--all", required=True)
    p.set_defaults(func=cmd_clips)
    p = sub.add_parser("model")
    p.add_argument("model")
    p.set_defaults(func=cmd_model)
    p = sub.add_parser("stub")
    p.add_argument("--src", required=True)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("-o", "--out", required=True)
    p.set_defaults(func=cmd_stub)
    p = sub.add_parser("meta")
    p.add_argument("--out", required=True)
    p.add_argument("pairs", nargs="*", help="key=value")
    p.set_defaults(func=cmd_meta)
    p = sub.add_parser("report")
    p.add_argument("--out", required=True)
    p.add_argument("--seeds", required=True)
    p.add_argument("--configs", default=" ".join(c[0] for c in CONFIGS))
    p.add_argument("--dry-run", action="store_true")
    p.add_argument("--report", required=True)
    p.add_argument("--baseline", action="append", default=[],
                   help="an earlier run's OUT: its full system becomes a 'before' row")
    p.add_argument("--baseline-label", action="append", default=[])
    p.set_defaults(func=cmd_report)
    a = ap.parse_args()
    a.func(a)


if __name__ == "__main__":
    main()
