#!/usr/bin/env python3
"""Helper of tools/solo_eval.sh (Python standard library only).

Subcommands:
  clips   held-out clips of the manifest as shell-readable lines, and each clip's music beats
  stub    --dry-run "generation": a held-out motion cut / tiled to a length (plumbing only)
  model   window length and name of a Lodge++ model directory (model.toml)
  contact the report's contact sheet: generated and real motion drawn at the same moments
          (tools/contact_sheet.sh; also used by the duet and holistic scripts)
  report  collect the `dancegen eval` JSON files, compute the boundary-jerk ratio at the real
          window boundaries of each sampler, and write the Markdown report

The boundary-jerk ratio is recomputed here because `dancegen eval` places its boundaries at
multiples of one window length (`--window`, default 150 = EDGE's 5 s), while the seams of these
samplers are not evenly spaced (cue seams 4 frames inside each window, autoregressive and EDGE
strides); the definition is the one of
`dancegen_metrics::longform::boundary_jerk_ratio` (checked against eval's own values at
150-frame boundaries in every run, see `parity` in the report).
"""

import argparse
import ast
import datetime
import json
import math
import os
import statistics
import struct
import sys
import tomllib
from array import array

FPS = 30.0
BOUNDARY_BAND = 2  # dancegen_metrics::longform::BOUNDARY_BAND
BOUNDARY_FRAMES = 4  # dancegen_lodgepp::config::BOUNDARY_FRAMES (autoregressive context)

# name, label, generate flags, sampler (decides the window boundaries)
CONFIGS = [
    ("full", "Lodge++ (full system)", "", "lodgepp"),
    ("no_global", "w/o global network (`--sampler autoregressive`)", "--sampler autoregressive",
     "autoregressive"),
    ("no_foot_refine", "w/o foot refine block (`--no-foot-refine`)", "--no-foot-refine",
     "lodgepp"),
    ("no_pen_guidance", "w/o penetration guidance (`--no-penetration-guidance`)",
     "--no-penetration-guidance", "lodgepp"),
    ("no_foot_lock", "w/o foot lock + leg IK post-processing (`--no-foot-lock`; not part of Lodge++)",
     "--no-foot-lock", "lodgepp"),
    ("no_beat_align", "w/o beat alignment post-processing (`--no-beat-align`; not part of Lodge++; "
     "the seam measure for the full system, whose window seams the warp moves by a few frames)",
     "--no-beat-align", "lodgepp"),
    ("edge", "EDGE-style sampler (`--sampler edge`)", "--sampler edge", "edge"),
]
CONFIG = {c[0]: c for c in CONFIGS}


# ----------------------------------------------------------------------------- .npy


def read_npy_header(f, path):
    """The header dict of the .npy open as `f` (positioned at its start); `f` is left at the data."""
    if f.read(6) != b"\x93NUMPY":
        raise SystemExit(f"{path}: not an .npy file")
    major = f.read(2)[0]
    hlen = struct.unpack("<H" if major == 1 else "<I", f.read(2 if major == 1 else 4))[0]
    return ast.literal_eval(f.read(hlen).decode("latin1"))


def read_npy(path):
    """(shape, flat list of floats) of a little-endian .npy (f4, f8, i8, i4)."""
    with open(path, "rb") as f:
        header = read_npy_header(f, path)
        data = f.read()
    if header.get("fortran_order"):
        raise SystemExit(f"{path}: Fortran order not supported")
    code = {"<f4": "f", "<f8": "d", "<i8": "q", "<i4": "i"}.get(header["descr"])
    if code is None:
        raise SystemExit(f"{path}: dtype {header['descr']} not supported")
    a = array(code)
    a.frombytes(data)
    if sys.byteorder != "little":
        a.byteswap()
    return tuple(header["shape"]), a


def write_npy(path, values, descr="<f4", shape=None):
    code = {"<f4": "f", "<f8": "d", "<i8": "q"}[descr]
    a = array(code, values)
    if sys.byteorder != "little":
        a.byteswap()
    shape = shape if shape is not None else (len(a),)
    header = "{'descr': '%s', 'fortran_order': False, 'shape': %s, }" % (
        descr,
        "(%d,)" % shape[0] if len(shape) == 1 else str(tuple(shape)),
    )
    pad = 64 - (10 + len(header) + 1) % 64
    header = header + " " * pad + "\n"
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)) + header.encode("latin1"))
        f.write(a.tobytes())
    os.replace(tmp, path)


# ----------------------------------------------------------------------------- metrics


def write_report(path, lines):
    """Writes the report's lines through a temporary file, so a failed run leaves the old one."""
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write("\n".join(lines))
    os.replace(tmp, path)
    print(f"wrote {path}")


def mean_joint_jerk(p, frames):
    """dancegen_metrics::longform::mean_joint_jerk on a flat (T, 24, 3) array."""
    fl = 72
    scale = FPS**3
    out = []
    for t in range(frames - 3):
        a, b, c, d = (p[(t + k) * fl:(t + k + 1) * fl] for k in range(4))
        s = 0.0
        for j in range(0, fl, 3):
            x = d[j] - 3 * c[j] + 3 * b[j] - a[j]
            y = d[j + 1] - 3 * c[j + 1] + 3 * b[j + 1] - a[j + 1]
            z = d[j + 2] - 3 * c[j + 2] + 3 * b[j + 2] - a[j + 2]
            s += math.sqrt(x * x + y * y + z * z)
        out.append(scale * s / 24.0)
    return out


def boundary_jerk_ratio(jerk, boundaries):
    """dancegen_metrics::longform::boundary_jerk_ratio from precomputed jerk samples."""
    n = len(jerk)
    band = [False] * n
    for b in boundaries:
        lo, hi = max(b - 2 * BOUNDARY_BAND, 0), min(b, n - 1)
        if n == 0 or lo > hi:
            continue
        for t in range(lo, hi + 1):
            band[t] = True
    inside = [j for j, f in zip(jerk, band) if f]
    rest = [j for j, f in zip(jerk, band) if not f]
    if not inside or not rest or sum(rest) == 0.0:
        return None
    return (sum(inside) / len(inside)) / (sum(rest) / len(rest))


def boundaries(sampler, window, frames):
    """Frames where the placed sequence (pipeline::place_windows) changes source: the first
    frame of each new window and, for the Lodge++ sampler, also the two frames where generated
    frames meet the 4 + 4 shared boundary frames (window start + 4, previous window end − 4)."""
    if sampler == "lodgepp":  # disjoint windows, advance n, cue seams at ±4
        seams = []
        for b in range(window, frames, window):
            seams += [b - BOUNDARY_FRAMES, b, b + BOUNDARY_FRAMES]
        return [b for b in seams if 0 < b < frames]
    elif sampler == "autoregressive":  # advance n − 4, the first 4 frames repeat the context
        first, step = window, window - BOUNDARY_FRAMES
    elif sampler == "edge":  # advance n / 2; window i's first half is window i − 1's second
        first, step = window, window // 2
    elif sampler == "every150":  # what `dancegen eval` assumes
        first, step = 150, 150
    else:
        raise ValueError(sampler)
    return list(range(first, frames, step))


def motion(path):
    shape, a = read_npy(path)
    if len(shape) != 3 or shape[1:] != (24, 3):
        raise SystemExit(f"{path}: expected (T, 24, 3) joints, got {shape}")
    return shape[0], a


# ----------------------------------------------------------------------------- subcommands


def cmd_clips(args):
    m = json.load(open(args.manifest))
    # The beat one-hot (last column) of the song's EDGE-35 features: the beats generate uses.
    shape, feats = read_npy(args.features)
    rows, cols = shape
    beats = [t for t in range(rows) if feats[t * cols + cols - 1] > 0]
    os.makedirs(args.out, exist_ok=True)
    by_name = {c["name"]: c for c in m["clips"]}
    song = os.path.realpath(args.song)
    for name in m["held_out"]:
        c = by_name[name]
        if os.path.realpath(c["source_song"]) != song:
            sys.exit(f"{name}: paired with {c['source_song']}, not {args.song}")
        # dancegen generate: f0 = round(start · 30), beats in [f0, f1) shifted by f0.
        f0 = round(c["song_start_s"] * FPS)
        f1 = f0 + c["frames"]
        seg = [b - f0 for b in beats if f0 <= b < f1]
        write_npy(os.path.join(args.out, name + ".npy"), seg, "<i8")
        print(name, repr(c["song_start_s"]), repr(c["song_end_s"]), c["frames"],
              os.path.join(os.path.dirname(args.manifest), c["motion"]))
    write_npy(os.path.join(args.out, "song.npy"), beats, "<i8")
    with open(os.path.join(args.out, "song_frames.txt"), "w") as f:
        f.write(f"{rows}\n")


def cmd_stub(args):
    frames_src, a = motion(args.src)
    fl = 72
    shift = (args.seed * 37) % frames_src
    out = array("f")
    for t in range(args.frames):
        f = (t + shift) % frames_src
        out.extend(a[f * fl:(f + 1) * fl])
    write_npy(args.out, out, "<f4", (args.frames, 24, 3))


def cmd_model(args):
    with open(os.path.join(args.model, "model.toml"), "rb") as f:
        cfg = tomllib.load(f)
    window = cfg.get("pddm", {}).get("pddm", {}).get("window", 128)
    genres = cfg.get("genres", [])
    genre = args.genre if args.genre in genres else cfg.get("default_genre", "")
    print(window, cfg.get("name", "?"), genre)


def load(path):
    with open(path) as f:
        return json.load(f)


def stats(vals):
    vals = [v for v in vals if v is not None]
    if not vals:
        return None, None, 0
    m = statistics.fmean(vals)
    s = statistics.stdev(vals) if len(vals) > 1 else None  # one seed: no spread to show
    return m, s, len(vals)


def fmt(m, s, digits, scale=1.0):
    if m is None:
        return "n/a"
    m = m * scale
    big = abs(m) >= 1e5
    f = (lambda v: f"{v:.3g}") if big else (lambda v: f"{v:.{digits}f}")
    if s is None:
        return f(m)
    return f"{f(m)} ± {f(s * scale)}"


def opt_load(path):
    return load(path) if os.path.exists(path) else None


# ----------------------------------------------------------------------------- physical figures
# Shared with tools/duet_eval.py, tools/holistic_eval.py and tools/group_eval.py.

# `dancegen eval --metrics physical` keys in the reports' table: key, column header, digits.
PHYSICAL_COLS = [
    ("floor_median", "floor_median (m)", 3),
    ("float", "float (%)", 1),
    ("foot_slide", "foot_slide (m/s)", 3),
    ("jerk", "jerk (m/s³)", 0),
    ("jerk_p99", "jerk_p99 (m/s³)", 0),
    ("max_step", "max_step (m)", 3),
    ("spikes", "spikes (count)", 1),
    ("leg_cross", "leg_cross (%)", 1),
    ("lean", "lean (%)", 1),
    ("joint_speed", "joint_speed (m/s)", 3),
    ("pelvis_speed", "pelvis_speed (m/s)", 3),
    ("step_rate", "step_rate (1/s)", 2),
]


def physical_over(paths):
    """{key: (mean, std)} of the physical figures over the `dancegen eval --metrics physical`
    JSON files that exist (one per seed; one file: std None), or None when none exists (e.g. a
    baseline run made before the figures were measured)."""
    figs = [opt_load(p) for p in paths]
    figs = [f for f in figs if f is not None]
    if not figs:
        return None
    return {k: stats([f.get(k) for f in figs])[:2] for k, _, _ in PHYSICAL_COLS}


def physical_subset(path, stems):
    """{key: (value, None)} of the clips of one `--metrics physical` JSON whose file stems are in
    `stems`, combined as `dancegen eval` combines a set (the mean; max_step: the largest, spikes:
    the sum), or None without the file or such clips."""
    j = opt_load(path)
    rows = [r for r in (j or {}).get("per_clip", [])
            if os.path.splitext(os.path.basename(r["file"]))[0] in stems]
    if not rows:
        return None
    out = {}
    for k, _, _ in PHYSICAL_COLS:
        v = [r.get(k) for r in rows if r.get(k) is not None]
        out[k] = (None if not v else max(v) if k == "max_step" else sum(v) if k == "spikes"
                  else statistics.fmean(v), None)
    return out


def genre_clips(manifest_path, genres):
    """Names of the data set's clips of the given genres."""
    m = opt_load(manifest_path) if manifest_path else None
    return {c["name"] for c in (m or {}).get("clips", []) if c.get("genre") in genres}


def physical_table(w, rows):
    """Writes the physical plausibility table: rows (label, {key: (mean, std)} or None); a row
    without figures (None) shows "-" in every column."""
    w("| motion | " + " | ".join(h for _, h, _ in PHYSICAL_COLS) + " |")
    w("|---|" + "---|" * len(PHYSICAL_COLS))
    for label, vals in rows:
        cells = []
        for k, _, d in PHYSICAL_COLS:
            if vals is None:
                cells.append("-")
                continue
            m, s = vals.get(k, (None, None))
            if k == "spikes" and m is not None and s is None and float(m).is_integer():
                cells.append(str(int(m)))  # one count, not a mean over seeds
            else:
                cells.append(fmt(m, s, d))
        w(f"| {label} | " + " | ".join(cells) + " |")
    w("")


def rates_note(manifest_path, what="the data set"):
    """What the data set's manifest says about the capture rates its real clips were read at,
    with a warning when the CMU salsa was read at its BVH headers' 120 fps."""
    m = opt_load(manifest_path) if manifest_path else None
    takes = (m or {}).get("takes") or []
    if not takes:
        return (f"The manifest of {what} records no source rates (`takes`): check that it was "
                "built with `--source-fps ../shared/data/cmu-salsa=60`.")
    by = {}
    for t in takes:
        by.setdefault(t.get("genre", "?"), set()).add((t.get("source_fps"), t.get("rate_from")))
    parts = [f"{g} " + " and ".join(f"{r:g} fps ({frm})" for r, frm in sorted(v, key=str))
             for g, v in sorted(by.items())]
    note = (f"Rates {what} read its takes at (its manifest's `takes`; `given` = "
            "`dataset build --source-fps`, `header` = the file's own): " + "; ".join(parts) +
            "; every clip then resampled to 30 fps.")
    bad = [t for t in takes if t.get("genre") == "salsa" and t.get("source_fps") != 60]
    if bad:
        rates = ", ".join(sorted({f"{t.get('source_fps')}" for t in bad}))
        note += (f" **Warning: {len(bad)} salsa takes were read at {rates} fps, not 60: their "
                 "real rows move too fast. Rebuild the data set with "
                 "`--source-fps ../shared/data/cmu-salsa=60`.**")
    return note


def physical_note(w, rates, sets=""):
    """The paragraph under the physical table: what each column means, how sets and seeds are
    combined (`sets`: a sentence on this report's rows), at which rate the real motion is read
    (`rates`: e.g. rates_note())."""
    w("Figures of `dancegen eval --metrics physical` (definitions and thresholds in "
      "`crates/dancegen-metrics/src/physical.rs`) on world joints (metres, Y-up, floor at "
      "y = 0) at 30 fps. **floor_median**: median height of the lowest foot joint (ankles, "
      "toes) above the floor: 0 stands on it, > 0 hovers, < 0 sinks. **float**: share of frames "
      "in which no foot joint is within 5 cm of the floor. **foot_slide**: median horizontal "
      "speed of a foot joint while it touches the floor (ankle under 8 cm, toe under 5 cm); "
      "planted feet give 0. **jerk** / **jerk_p99**: mean and 99th percentile of the jerk "
      "(third time derivative of position) over joints and frames: jitter and pose jumps raise "
      "them. **max_step**: the largest single-frame move of any joint. **spikes**: frame steps "
      "in which some joint moves faster than 20 m/s (teleports, not movement). **leg_cross**: "
      "share of frames with crossed shins. **lean**: share of frames whose pelvis is more than "
      "0.3 m (horizontally) from the midpoint of its ankles. **joint_speed**: mean joint speed. "
      "**pelvis_speed**: mean horizontal pelvis speed (travel over the floor). **step_rate**: "
      "foot steps of both feet per second (real salsa: 1.6–2.3). A set's value is the mean over "
      "its clips, except max_step (the largest of its clips) and spikes (their sum, so it grows "
      f"with the number of clips). {sets} The real motion is read at its true frame rate: the "
      "CMU salsa at 60 fps, not the 120 fps its BVH headers state (docs/data-rates.md; at the "
      f"header's rate it would move and step twice as fast). {rates}".replace("  ", " ").rstrip())
    w("")


# ----------------------------------------------------------------------------- contact sheet
# tools/contact_sheet.sh, and the report's section showing it; shared like the figures above.

CONTACT_FPS = 30  # the joints .npy files of every evaluation


def npy_shape(path):
    with open(path, "rb") as f:
        return tuple(read_npy_header(f, path)["shape"])


def make_contact_sheet(binary, png, info, caption, rows, work, python=None):
    """Draws rows [(label, [joints .npy, ...])] (several files: one picture) at three moments,
    on whole seconds near 1/6, 1/2 and 5/6 of the shortest motion, with tools/contact_sheet.sh
    into `png`, and describes the sheet in `info` (JSON) for contact_section(). `info` is
    removed first and written only when the sheet was made, so a failed sheet leaves the report
    without a picture, never with an old one. Returns whether it was made."""
    import subprocess

    if os.path.exists(info):
        os.remove(info)
    frames_of = min(npy_shape(f)[0] for _, files in rows for f in files)
    secs = frames_of / CONTACT_FPS
    frames = [min(int(secs * k / 6 + 0.5) * CONTACT_FPS, frames_of - 1) for k in (1, 3, 5)]
    script = os.path.join(os.path.dirname(os.path.abspath(__file__)), "contact_sheet.sh")
    env = dict(os.environ, DANCEGEN=binary, WORK=work, FPS=str(CONTACT_FPS),
               PYTHON=python or sys.executable)
    specs = [f"{label}={'+'.join(files)}" for label, files in rows]
    r = subprocess.run(["bash", script, png, " ".join(map(str, frames))] + specs, env=env)
    if r.returncode != 0:
        print(f"contact sheet failed (exit {r.returncode}); the report has none", file=sys.stderr)
        return False
    with open(info, "w") as f:
        json.dump({"image": os.path.abspath(png), "caption": caption, "fps": CONTACT_FPS,
                   "frames": frames, "rows": [label for label, _ in rows],
                   "files": [files for _, files in rows]}, f, indent=1)
    return True


def cmd_contact(args):
    rows = []
    for spec in args.rows:
        label, _, files = spec.partition("=")
        if not files:
            sys.exit(f"{spec}: expected LABEL=FILE[+FILE...]")
        rows.append((label, files.split("+")))
    if not make_contact_sheet(args.bin, args.png, args.info, args.caption, rows, args.work):
        sys.exit(1)


def contact_section(w, info_path, report, heading="## Contact sheet"):
    """The report's contact sheet (made by make_contact_sheet), if there is one: the picture
    (linked relative to the report) and a caption of what it shows."""
    info = opt_load(info_path)
    if info is None or not os.path.exists(info["image"]):
        return
    rel = os.path.relpath(info["image"], os.path.dirname(os.path.abspath(report)))
    fps = info["fps"]
    secs = ", ".join(f"{f / fps:g}" for f in info["frames"])
    w(heading)
    w("")
    w(f"![{info['caption']}]({rel})")
    w("")
    w(f"{info['caption']}. Rows, top to bottom: {'; '.join(info['rows'])}. Columns: {secs} s "
      f"into the clip (frames {', '.join(map(str, info['frames']))} at {fps:g} fps), the same "
      "moments in every row. Drawn from the joints `dancegen eval` measured, as stick figures "
      "(`tools/contact_sheet.sh`, `dancegen render`); the shadow marks the floor under the "
      "dancer, so feet drawn above their shadow float.")
    w("")


def cmd_report(args):
    out = args.out
    seeds = args.seeds.split()
    window = args.window
    clips = [ln.split()[0] for ln in open(os.path.join(out, "clips.txt")) if ln.strip()]
    configs = [c for c in CONFIGS if c[0] in args.configs.split()]
    n_train = len([f for f in os.listdir(os.path.join(out, "gt_train")) if f.endswith(".npy")])
    n_all = n_train + len(clips)
    parity = [0.0, 0]  # largest relative difference, clips compared
    meta = load(os.path.join(out, "meta.json"))

    def stem(p):
        return os.path.splitext(os.path.basename(p))[0]

    def bjerk_set(paths, sampler, eval_json):
        """Boundary-jerk ratio per clip at the sampler's boundaries; the ratio at eval's
        150-frame boundaries is compared with eval's own per-clip value (parity check)."""
        by_stem = {stem(row["file"]): row.get("boundary_jerk") for row in eval_json["per_clip"]}
        vals = []
        for p in paths:
            frames, a = motion(p)
            jerk = mean_joint_jerk(a, frames)
            vals.append(boundary_jerk_ratio(jerk, boundaries(sampler, window, frames)))
            mine, theirs = boundary_jerk_ratio(jerk, boundaries("every150", window, frames)), \
                by_stem[stem(p)]
            if (mine is None) != (theirs is None):
                parity[0] = math.inf
            elif mine is not None:
                parity[0] = max(parity[0], abs(mine - theirs) / max(abs(theirs), 1e-12))
            parity[1] += 1
        return vals

    def mean_def(vals):
        vals = [v for v in vals if v is not None]
        return statistics.fmean(vals) if vals else None

    SET = ("fid_k", "fid_g", "div_k", "div_g")

    # ---- real data: the held-out motion (one "seed") and the training clips (FID calibration)
    ev = os.path.join(out, "eval")
    rj = load(os.path.join(ev, "real", "clip.json"))
    real = {k: rj.get(k) for k in ("pfc", "fsr", "penetration", "freeze", "inverted")}
    real_bas = {c: load(os.path.join(ev, "real", f"bas_{c}.json"))["bas"] for c in clips}
    real["bas"] = mean_def(list(real_bas.values()))
    gt_paths = [os.path.join(out, "gt", c + ".npy") for c in clips]
    real["boundary_jerk"] = mean_def(bjerk_set(gt_paths, "lodgepp", rj))
    tr = load(os.path.join(ev, "real", "fid_train.json"))  # training clips vs held-out
    tra = load(os.path.join(ev, "real", "fid_train_all.json"))  # training clips vs all real
    hoa = load(os.path.join(ev, "real", "fid_heldout_all.json"))  # held-out vs all real
    set_real = {
        "held": {"div_k": tr.get("div_k_gt"), "div_g": tr.get("div_g_gt")},
        "held_all": {k: hoa.get(k) for k in SET},
        "train": {k: tr.get(k) for k in SET},
        "train_all": {k: tra.get(k) for k in SET},
    }

    # ---- generated: per config, per seed (seeds whose generation failed are missing)
    def collect(run_out, run_configs):
        """Per-configuration metric lists of the run in `run_out` (this run, or --baseline's)."""
        seg, lng, setm, setm_all, done = {}, {}, {}, {}, {}
        for name, _, _, sampler in run_configs:
            seg[name], lng[name], setm[name], setm_all[name], done[name] = {}, {}, {}, {}, []
            for s in seeds:
                ed = os.path.join(run_out, "eval", name, f"seed{s}")
                fj, fa, cj = (opt_load(os.path.join(ed, f)) for f in
                              ("fid.json", "fid_all.json", "clip.json"))
                if fj is None or fa is None or cj is None:
                    continue
                done[name].append(s)
                for k in SET:
                    setm[name].setdefault(k, []).append(fj.get(k))
                    setm_all[name].setdefault(k, []).append(fa.get(k))
                row = {k: cj.get(k) for k in ("pfc", "fsr", "penetration", "freeze", "inverted")}
                row["bas"] = mean_def([load(os.path.join(ed, f"bas_{c}.json"))["bas"]
                                       for c in clips])
                paths = [os.path.join(run_out, "gen", name, f"seed{s}", "seg", c + ".npy")
                         for c in clips]
                row["boundary_jerk"] = mean_def(bjerk_set(paths, sampler, cj))
                for k, v in row.items():
                    seg[name].setdefault(k, []).append(v)
                lj = opt_load(os.path.join(ed, "long.json")) if args.long else None
                if lj is not None:
                    row = {k: lj.get(k)
                           for k in ("bas", "pfc", "fsr", "penetration", "freeze", "inverted")}
                    p = os.path.join(run_out, "gen", name, f"seed{s}", "long", "song.npy")
                    row["boundary_jerk"] = bjerk_set([p], sampler, lj)[0]
                    for k, v in row.items():
                        lng[name].setdefault(k, []).append(v)
        return seg, lng, setm, setm_all, done

    seg, lng, setm, setm_all, done = collect(out, configs)
    # Earlier runs to compare with, oldest first: (OUT, label, segments, 29-clip set, seeds).
    bases = []
    labels = args.baseline_label or []
    for i, b_out in enumerate(args.baseline or []):
        full_cfg = [c for c in CONFIGS if c[0] == "full"]
        b_seg, _, _, b_all, b_done = collect(b_out, full_cfg)
        if len(b_done["full"]) == 0:
            sys.exit(f"--baseline {b_out}: no evaluated full-system seed in it")
        label = labels[i] if i < len(labels) else "the earlier model"
        bases.append((b_out, label, b_seg["full"], b_all["full"], b_done["full"]))

    # ---- render
    L = []
    w = L.append
    w("# Solo evaluation (Lodge++) on the held-out song")
    w("")
    if args.dry_run:
        w("> **DRY RUN — NOT MODEL OUTPUT.** The \"generated\" motion is the held-out real motion "
          "copied and shifted (`tools/solo_eval.sh --dry-run`); these numbers only test the "
          "plumbing.")
        w("")
    w(f"Generated by `{meta['command']}` on {meta['date']} (commit `{meta['commit']}`"
      f"{', with uncommitted changes in the working tree' if meta.get('dirty') else ''}); "
      f"model `{meta['model_dir']}` (model.toml name `{meta['model_name']}`, PDDM window "
      f"{window} frames, genre `{meta['genre']}`, the model's default steps and guidance); "
      f"binary `{meta['binary']}`; machine: {meta['nproc']} cores, {meta['load']}; "
      f"wall time {meta['wall']}.")
    w("")
    w(f"Seeds: {' '.join(seeds)} (each configuration generated once per seed). "
      f"{meta.get('seed_note', '')}".rstrip())
    failed = [f"{name} (seeds done: {' '.join(done[name]) or 'none'})" for name, *_ in configs
              if len(done[name]) < len(seeds)]
    if failed:
        w("")
        w(f"**Incomplete:** generation failed or was not run for: {'; '.join(failed)} — see "
          f"`{meta['out']}/failed.txt`. Those rows average the seeds that finished.")
    w("")
    w("## What was measured")
    w("")
    w(f"- **Segments**: the {len(clips)} held-out real salsa clips "
      f"({', '.join('`' + c + '`' for c in clips)}; CMU takes 13 and 14, both partners) are "
      f"paired with `{meta['song']}` at `song_start_s`–`song_end_s` of the data set manifest "
      f"(`{meta['manifest']}`). Each configuration dances the same cut of the song: "
      "`dancegen generate SONG --start song_start_s --end song_end_s --seed S --genre "
      f"{meta['genre']} [flags] -o clip.npy`, so generated and real clips have the same length "
      "and music.")
    if args.long:
        w(f"- **Long form**: the whole song ({meta['song_seconds']} s) per configuration and "
          "seed. Freezing and boundary jerk matter most here (dozens of windows).")
    w("- **Real data**: the held-out motion itself (joints from `dancegen convert`), measured "
      "like the generated clips. The FSR and penetration targets compare against it.")
    w("- **Protocols**: FID / Div with `dancegen eval --protocol finedance-lodge` (Lodge++'s own "
      "protocol: 30 fps, zero-start root-relative joints, 22 joints, kinetic frame time 1/60, "
      "first 1024 frames, features normalised by the reference set's statistics). All per-clip "
      "metrics with `--protocol none --fps 30` (world positions as generated, frame time 1/30): "
      "PFC, FSR and penetration need world positions, not root-relative joints.")
    w(f"- **FID references**: (a) as asked, the {len(clips)} held-out real clips; (b) all "
      f"{n_all} real salsa clips of the data set ({n_train} training + {len(clips)} held-out; "
      "LODGE's FineDance protocol also takes the whole data set as the reference, anchors A.3). "
      "(a) is degenerate — see the calibration row and the caveats.")
    w("- **BAS**: `--bas-variant bailando` against the music beats of each clip's cut: the "
      "beat column of the song's EDGE-35 features (`dancegen features --fps 30`, librosa-exact "
      "tracker on the whole song) inside the cut, shifted to the cut's start — exactly the beats "
      "`dancegen generate` conditions on, and the beats the real motion was time-warped onto. "
      "Long form: all beats of the song.")
    man = {c["name"]: c for c in load(meta["manifest_abs"])["clips"]}
    diffs = [abs(real_bas[c] - man[c]["warp"]["bas_after"]) for c in clips
             if real_bas[c] is not None and "warp" in man.get(c, {})]
    if diffs:
        w(f"  Check: the real clips' BAS reproduces the `bas_after` the data set builder recorded "
          f"for them (largest difference {max(diffs):.1e}), so the beats are the ones the warp "
          f"aligned the motion to.")
    # The real BAS is a property of the pseudo-pairing (the warp that put the motion on its
    # song's beats), so it is shown for every real clip, not only the held-out ones.
    warps = {c: man[c]["warp"] for c in man if "warp" in man[c]}
    train_warps = [v for c, v in warps.items() if c not in clips]
    held_warps = [warps[c] for c in clips if c in warps]
    if train_warps and held_warps:
        def spread(key, ws):
            v = [x[key] for x in ws]
            sd = f" ± {statistics.stdev(v):.3f}" if len(v) > 1 else ""
            return f"{statistics.fmean(v):.3f}{sd} ({min(v):.3f}–{max(v):.3f})"
        w(f"  For scale, from the data set manifest: the same warp gave the {len(train_warps)} "
          f"training clips a BAS of {spread('bas_after', train_warps)} (before the warp "
          f"{spread('bas_before', train_warps)}), and the {len(held_warps)} held-out clips "
          f"{spread('bas_after', held_warps)} (before {spread('bas_before', held_warps)}). The "
          f"real row's BAS is that of these {len(held_warps)} pairings, so it is higher than what "
          f"the model saw on average.")
    w(f"- **Boundary jerk**: `dancegen eval --window N` puts its boundaries at multiples of N "
      f"(default 150, EDGE's 5 s windows), but these samplers' seams are not evenly spaced, so "
      f"the ratio is recomputed by "
      f"`tools/solo_eval.py` with the same definition "
      f"(`dancegen_metrics::longform::boundary_jerk_ratio`, ±{BOUNDARY_BAND}-frame band) at the "
      f"frames where each sampler's output changes source: Lodge++ and its two ablations at "
      f"every {window}-frame window start and {BOUNDARY_FRAMES} frames either side of it "
      f"(where the generated frames meet the shared boundary frames; the first report "
      f"looked only at the window starts and missed 1 m root jumps at these seams); "
      f"autoregressive at {window}, then every {window - BOUNDARY_FRAMES} "
      f"(each window repeats the previous one's last {BOUNDARY_FRAMES} frames); EDGE at "
      f"{window}, then every {window // 2} (half-overlapping windows). Real data is measured "
      f"at the Lodge++ seams (it has no seams, so its value shows the metric's noise). "
      f"Parity check: at 150-frame boundaries the helper reproduces `dancegen eval`'s "
      f"`boundary_jerk` on all {parity[1]} clips within {parity[0]:.1e} (relative).")
    w("- **Freezing**: share of 1-second windows whose mean joint speed is under 5 % of the "
      "clip's median speed (`dancegen eval` `freeze`).")
    w("- **Upside down**: share of frames whose neck is below the pelvis (`dancegen eval` "
      "`inverted`, `dancegen_metrics::posture`).")
    w("- Values are mean ± standard deviation over the seeds (n − 1); each seed's value is the "
      "mean over its clips (FID/Div: over that seed's set of clips).")
    w("")

    def label_of(name, label):
        n = len(done[name])
        return label if n == len(seeds) else f"{label} ({n} of {len(seeds)} seeds)"

    def table(cols, rows):
        """rows: (label, {key: (mean, std)} or {key: value})"""
        w("| configuration | " + " | ".join(c[1] for c in cols) + " |")
        w("|---|" + "---|" * len(cols))
        for label, vals in rows:
            cells = []
            for k, _, d, sc in cols:
                v = vals.get(k)
                if isinstance(v, tuple):
                    cells.append(fmt(v[0], v[1], d, sc))
                else:
                    cells.append(fmt(v, None, d, sc))
            w(f"| {label} | " + " | ".join(cells) + " |")
        w("")

    def gen_rows(data):
        rows = []
        for name, label, _, _ in configs:
            vals = {k: stats(v)[:2] for k, v in data[name].items()}
            rows.append((label_of(name, label), vals))
        return rows

    clip_cols = [
        ("bas", "BAS ↑", 4, 1.0),
        ("fsr", "FSR % ↓", 2, 100.0),
        ("pfc", "PFC ↓", 3, 1.0),
        ("penetration", "Penetration % ↓", 3, 1.0),
        ("freeze", "Freeze % ↓", 2, 100.0),
        ("inverted", "Upside down % ↓", 2, 100.0),
        ("boundary_jerk", "Boundary jerk ↓", 3, 1.0),
    ]
    w(f"## Held-out segments ({len(clips)} clips × {len(seeds)} seeds per configuration)")
    w("")
    table(clip_cols, [("real data (held-out motion)", real)] + gen_rows(seg))

    w("### FID and diversity (same segments)")
    w("")
    set_cols = [
        ("fid_k", f"FID_k ({len(clips)} held-out) ↓", 2, 1.0),
        ("fid_g", f"FID_g ({len(clips)} held-out) ↓", 2, 1.0),
        ("div_k", "Div_k", 2, 1.0),
        ("div_g", "Div_g", 2, 1.0),
        ("fid_k_all", f"FID_k ({n_all} real) ↓", 2, 1.0),
        ("fid_g_all", f"FID_g ({n_all} real) ↓", 2, 1.0),
        ("div_k_all", "Div_k", 2, 1.0),
        ("div_g_all", "Div_g", 2, 1.0),
    ]
    rows = []
    r = dict(set_real["held"])
    r.update({k + "_all": v for k, v in set_real["held_all"].items()})
    rows.append(("real data (held-out motion)", r))
    r = dict(set_real["train"])
    r.update({k + "_all": v for k, v in set_real["train_all"].items()})
    rows.append((f"real data: the {n_train} training clips (calibration)", r))
    for name, label, _, _ in configs:
        vals = {k: stats(v)[:2] for k, v in setm[name].items()}
        vals.update({k + "_all": stats(v)[:2] for k, v in setm_all[name].items()})
        rows.append((label_of(name, label), vals))
    table(set_cols, rows)
    w(f"Div columns follow their FID reference's normalisation. Real held-out motion: FID "
      f"against itself is 0 by construction (n/a), its Div is the reference set's own "
      f"diversity. The calibration row is real salsa the model was trained on: against the "
      f"{len(clips)} held-out clips it already scores "
      f"FID_k {fmt(set_real['train']['fid_k'], None, 2)} and FID_g "
      f"{fmt(set_real['train']['fid_g'], None, 2)}: reference (a) measures closeness to these "
      f"{len(clips)} clips (their per-dimension spread is tiny or zero), not realism. "
      f"Reference (b) contains the training clips, so it favours motion close to the training "
      f"set (a model that copied its training data would score near the calibration row).")
    w("")
    if args.long:
        w(f"## Long form: the whole song ({meta['song_seconds']} s), 1 dance × "
          f"{len(seeds)} seeds per configuration")
        w("")
        table(clip_cols, [("real data (the held-out segments, for reference)", real)]
              + gen_rows(lng))
        w("FID/Div are not computed for the long form: one dance per seed and configuration "
          "is one sample, and the real held-out motion comes as 16–20 s clips.")
        w("")

    # ---- physical plausibility (+ the contact sheet)
    def phys_gen(run_out, name, seed_list, fname):
        return physical_over([os.path.join(run_out, "eval", name, f"seed{x}", fname)
                              for x in seed_list])

    w("## Physical plausibility")
    w("")
    prow = [(f"real data (the {len(clips)} held-out clips)",
             physical_over([os.path.join(ev, "real", "physical.json")])),
            (f"real data (the {n_train} training clips)",
             physical_over([os.path.join(ev, "real", "physical_train.json")]))]
    same = genre_clips(meta.get("manifest_abs"), {meta["genre"]}) - set(clips)
    all_train = {os.path.splitext(f)[0] for f in os.listdir(os.path.join(out, "gt_train"))}
    if same & all_train and same & all_train != all_train:
        prow.append((f"real data (the {len(same & all_train)} {meta['genre']} training clips, "
                     "the genre asked for)",
                     physical_subset(os.path.join(ev, "real", "physical_train.json"), same)))
    prow += [(f"segments: {label_of(name, label)}",
              phys_gen(out, name, done[name], "physical.json")) for name, label, _, _ in configs]
    if args.long:
        prow += [(f"whole song: {label_of(name, label)}",
                  phys_gen(out, name, done[name], "physical_long.json"))
                 for name, label, _, _ in configs]
    physical_table(w, prow)
    physical_note(w, rates_note(meta.get("manifest_abs")),
                  f"Segments: the {len(clips)} held-out cuts per seed (`dancegen eval --pred DIR "
                  "--protocol none --fps 30 --metrics physical`)"
                  + (", whole song: the one dance per seed" if args.long else "")
                  + "; generated rows are mean ± standard deviation over the seeds.")
    contact_section(w, os.path.join(out, "contact.json"), args.report, "### Contact sheet")

    # ---- targets (computed)
    def verdict(ok):
        return "n/a" if ok is None else ("✅ met" if ok else "❌ not met")

    rows = []
    sets = [("segments", seg)] + ([("long form", lng)] if args.long else [])
    for where, data in sets:
        for name, label, _, _ in configs:
            m, s, _ = stats(data[name].get("boundary_jerk", []))
            rows.append((f"boundary-jerk ratio < 1.5 ({where}; real data "
                         f"{fmt(real['boundary_jerk'], None, 3)})", name, label,
                         fmt(m, s, 3), None if m is None else m < 1.5))
        for name, label, _, _ in configs:
            m, s, _ = stats(data[name].get("freeze", []))
            rows.append((f"freezing share < 5 % ({where})", name, label,
                         fmt(m, s, 2, 100.0) + " %", None if m is None else m < 0.05))
        for name, label, _, _ in configs:
            m, s, _ = stats(data[name].get("fsr", []))
            rows.append((f"FSR ≤ real data's {real['fsr'] * 100:.2f} % ({where})", name, label,
                         fmt(m, s, 2, 100.0) + " %", None if m is None else m <= real["fsr"]))
        if "full" in data and "no_pen_guidance" in data:
            a, sa, _ = stats(data["full"].get("penetration", []))
            b, sb, _ = stats(data["no_pen_guidance"].get("penetration", []))
            ok = None if a is None or b is None else a < b
            note = ""
            if a is not None and b is not None and abs(b - a) < max(sa or 0.0, sb or 0.0):
                note = " (difference smaller than one seed std)"
            kind = "seg" if where == "segments" else "long"
            pairs = [(os.path.join(out, "gen", "full", f"seed{x}", kind, f),
                      os.path.join(out, "gen", "no_pen_guidance", f"seed{x}", kind, f))
                     for x in seeds for f in (os.listdir(os.path.join(out, "gen", "full",
                                                                        f"seed{x}", kind))
                                              if os.path.isdir(os.path.join(out, "gen", "full",
                                                                            f"seed{x}", kind))
                                              else [])]
            same = sum(1 for x, y in pairs if os.path.exists(y)
                       and open(x, "rb").read() == open(y, "rb").read())
            if pairs and same:
                note += f" ({same} of {len(pairs)} generated files are byte-identical with " \
                        "and without guidance)"
            rows.append((f"penetration lower with guidance than without ({where})", "full",
                         "full vs w/o penetration guidance",
                         f"{fmt(a, sa, 3)} % vs {fmt(b, sb, 3)} %{note}", ok))
    if bases and "full" in seg:
        w("## Before and after")
        w("")
        w("The full system of this run against the full system of earlier runs, on the same "
          f"held-out segments, beats and {n_all} real clips:")
        w("")
        for b_out, label, _, _, b_done in bases:
            w(f"- {label}: `{b_out}` (seeds {' '.join(b_done)})")
        w("")
        cols = [("bas", "BAS ↑", 4, 1.0), ("fsr", "FSR % ↓", 2, 100.0),
                ("boundary_jerk", "Boundary jerk ↓", 3, 1.0),
                ("inverted", "Upside down % ↓", 2, 100.0),
                ("fid_k_all", f"FID_k ({n_all} real) ↓", 2, 1.0),
                ("div_k_all", "Div_k", 2, 1.0), ("fid_g_all", f"FID_g ({n_all} real) ↓", 2, 1.0)]
        r = dict(real)
        r.update({k + "_all": v for k, v in set_real["held_all"].items()})
        r["div_k_all"] = set_real["held_all"].get("div_k")
        rows_ba = [("real data (held-out motion)", r)]
        for _, label, b_seg, b_all, _ in bases:
            before = {k: stats(v)[:2] for k, v in b_seg.items()}
            before.update({k + "_all": stats(v)[:2] for k, v in b_all.items()})
            rows_ba.append((f"before: {label}", before))
        after = {k: stats(v)[:2] for k, v in seg["full"].items()}
        after.update({k + "_all": stats(v)[:2] for k, v in setm_all["full"].items()})
        rows_ba.append(("after: this run's model", after))
        table(cols, rows_ba)
        w("Physical plausibility of the same segments (see \"Physical plausibility\" above; "
          "\"-\": that run did not measure the figures):")
        w("")
        prow = [(f"real data (the {len(clips)} held-out clips)",
                 physical_over([os.path.join(ev, "real", "physical.json")]))]
        prow += [(f"before: {label}", phys_gen(b_out, "full", b_done, "physical.json"))
                 for b_out, label, _, _, b_done in bases]
        prow.append(("after: this run's model", phys_gen(out, "full", done["full"],
                                                         "physical.json")))
        physical_table(w, prow)
        w("Issue 16's targets: BAS ≥ 0.35, Div_k ≥ 4.5, FID_k (all real) ≤ 92; boundary jerk "
          "< 1.5 and FSR ≤ real.")
        w("")
    w("## Reading the numbers")
    w("")
    full = [r for r in rows if r[1] == "full"]
    met = sum(1 for r in full if r[4])
    w(f"**Full system: {met} of {len(full)} target checks met.** Targets of the issue, checked "
      "by the script on the means over seeds:")
    w("")
    w("| target | full system | verdict |")
    w("|---|---|---|")
    for t, _, _, val, ok in full:
        w(f"| {t} | {val} | {verdict(ok)} |")
    w("")
    others = [c for c in configs if c[0] != "full"]
    if others:
        w("The same checks for the ablations and the EDGE-style sampler (for comparison; the "
          "targets are for the full system):")
        w("")
        w("| target | " + " | ".join(c[1] for c in others) + " |")
        w("|---|" + "---|" * len(others))
        for t in dict.fromkeys(r[0] for r in rows if r[1] != "full"):
            cells = []
            for c in others:
                hit = [r for r in rows if r[0] == t and r[1] == c[0]]
                cells.append(f"{'✅' if hit[0][4] else '❌'} {hit[0][3]}" if hit and
                             hit[0][4] is not None else "n/a")
            w(f"| {t} | " + " | ".join(cells) + " |")
        w("")
    for where, data in sets:
        m, _, _ = stats(data.get("full", {}).get("bas", []))
        if m is not None:
            same = "on the same beats" if where == "segments" else "on its segments' beats"
            w(f"- BAS ({where}): full system {m:.4f} vs the real held-out motion's "
              f"{real['bas']:.4f} {same} ({'higher' if m > real['bas'] else 'lower'}).")
    # Issue 16: the full system should be at least as good as every ablation on BAS and FID_k.
    if "full" in seg and others:
        w("")
        w("**The full system against each other configuration** on BAS (higher is better) and "
          f"FID_k against the {n_all} real clips (lower is better), means over seeds; "
          "\"loses\" marks a configuration that beats the full system, with the gap in units of "
          "the larger of the two seed standard deviations:")
        w("")
        w("| configuration | BAS, segments | BAS, long form | FID_k |")
        w("|---|---|---|---|")
        pairs = [("bas", seg, 1), ("bas", lng, 1), ("fid_k", setm_all, -1)]
        for name, label, _, _ in others:
            cells = []
            for key, data, sign in pairs:
                fm, fs, _ = stats(data.get("full", {}).get(key, []))
                om, os_, _ = stats(data.get(name, {}).get(key, []))
                if fm is None or om is None:
                    cells.append("n/a")
                    continue
                gap = (om - fm) * sign
                spread = max(fs or 0.0, os_ or 0.0)
                units = f", {gap / spread:.1f} std" if spread > 0 else ""
                verdict = "full loses" if gap > 0 else "full wins or ties"
                cells.append(f"{om:.4g} vs {fm:.4g}: {verdict}{units if gap > 0 else ''}")
            w(f"| {label} | " + " | ".join(cells) + " |")
        w("")
        w("Where the full system loses, docs/solo-data-v2.md (the issue 16 record) says why.")
    w("")
    w("Caveats:")
    w("")
    w("- **Pseudo-paired data.** No data set pairs real dance with this music: the held-out "
      "real motion was time-warped (±15 % speed) so its kinematic beats land on the song's "
      "beats (DEVELOPERS.md, Training sets). Its BAS is partly put there by the warp, and "
      "FID/Div measure closeness to a few salsa clips, not to \"a dance for this song\".")
    w(f"- **Tiny reference sets.** With {len(clips)} reference clips the per-dimension std used "
      "to normalise the features is 0 (or nearly) in some dimensions, so FID and Div against "
      f"the held-out clips explode (see the calibration row); against the {n_all} real clips "
      "they are finite but still rest on few samples (72-d / 32-d features). Compare "
      "configurations with each other, not with published numbers.")
    w("- **Capsule penetration.** Penetration is our capsule-body approximation of Lodge++'s "
      "mesh-based self-penetration ratio (percent of forearm/hand samples inside another body "
      "part; `dancegen_metrics::penetration`), not the paper's SDF/mesh metric.")
    w("- **Tiny training set.** The model was trained on a few dozen CMU and AIST++ takes (its "
      "model card lists them) paired with two songs (escape_from_chaosland, metal_madness); the "
      "held-out song and dancers are unseen.")
    w("- **Short segments for the long-form metrics.** A 16–20 s segment has only 3–4 window "
      "boundaries and 16–19 one-second windows; the long-form rows are the ones to read for "
      "boundary jerk and freezing.")
    w("- Boundary jerk is recomputed outside `dancegen eval` (see above): `eval --window N` "
      "covers evenly spaced window starts only; it has no option for a list of boundaries.")
    w("")
    w("## Generation time")
    w("")
    times = {}
    tpath = os.path.join(out, "times.tsv")
    if os.path.exists(tpath):
        last = {}
        for ln in open(tpath):
            p = ln.rstrip("\n").split("\t")
            if len(p) >= 5:
                last[(p[0], p[1], p[2], p[4])] = float(p[3])  # the last run of each output
        for (cfg, seed, kind, _), t in last.items():
            if cfg in done and seed in seeds:
                times.setdefault((cfg, kind), []).append(t)
    w("| configuration | one segment (s, mean) | one whole song (s, mean) |")
    w("|---|---|---|")
    for name, label, _, _ in configs:
        a = times.get((name, "seg"))
        b = times.get((name, "long"))
        w(f"| {label} | {'n/a' if not a else f'{statistics.fmean(a):.0f}'} | "
          f"{'n/a' if not b else f'{statistics.fmean(b):.0f}'} |")
    w("")
    total = sum(sum(v) for v in times.values())
    w("Process wall time of each `dancegen generate` call (model loading and music analysis "
      "included), while other jobs shared the CPU. Total generation time behind this report: "
      f"{total / 60:.0f} min (outputs of an earlier, interrupted run of the same command and "
      "model are reused, so the wall time above can be shorter).")
    w("")
    write_report(args.report, L)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("clips")
    p.add_argument("--manifest", required=True)
    p.add_argument("--features", required=True, help="(T, 35) EDGE features of the song")
    p.add_argument("--song", required=True)
    p.add_argument("--out", required=True)
    p.set_defaults(func=cmd_clips)
    p = sub.add_parser("stub")
    p.add_argument("--src", required=True)
    p.add_argument("--frames", type=int, required=True)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("-o", "--out", required=True)
    p.set_defaults(func=cmd_stub)
    p = sub.add_parser("model")
    p.add_argument("model")
    p.add_argument("--genre", default="salsa")
    p.set_defaults(func=cmd_model)
    p = sub.add_parser("contact", help="the report's contact sheet (tools/contact_sheet.sh)")
    p.add_argument("--bin", required=True, help="dancegen binary")
    p.add_argument("--png", required=True)
    p.add_argument("--info", required=True, help="JSON describing the sheet for the report")
    p.add_argument("--caption", required=True, help="what the sheet shows (model, song, clip)")
    p.add_argument("--work", required=True, help="directory for the single pictures")
    p.add_argument("rows", nargs="+", metavar="LABEL=FILE[+FILE...]")
    p.set_defaults(func=cmd_contact)
    p = sub.add_parser("report")
    p.add_argument("--out", required=True)
    p.add_argument("--seeds", required=True)
    p.add_argument("--configs", default=" ".join(c[0] for c in CONFIGS))
    p.add_argument("--window", type=int, required=True)
    p.add_argument("--long", action="store_true")
    p.add_argument("--dry-run", action="store_true")
    p.add_argument("--report", required=True)
    p.add_argument("--baseline", action="append",
                   help="an earlier run's OUT directory: its full system is compared with this "
                   "run's in a before/after table (repeatable, oldest first)")
    p.add_argument("--baseline-label", action="append",
                   help="names the --baseline of the same position")
    p.set_defaults(func=cmd_report)
    a = ap.parse_args()
    a.func(a)


if __name__ == "__main__":
    main()
