#!/usr/bin/env bash
# Settles and documents the true frame rate of every take in ../shared/data: surveys each take
# as `dancegen dataset build` reads it (retargeted to SMPL 24, 30 fps, resting feet on y = 0)
# at its trusted rate, and the salsa again at its header's rate, then writes
# docs/data-rates.md (rate, where it comes from, kinematic tempo, floor) from the manifests'
# `takes`. The figures behind `dancegen_dataset::takes::HUMAN_TEMPO`.
#
#   bash tools/data_rates.sh            # uses target/release/dancegen (built if missing)
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${DANCEGEN:-${CARGO_TARGET_DIR:-target}/release/dancegen}"
[ -x "$bin" ] || cargo build --release -p dancegen-cli
data=../shared/data
song="$data/music/sectoid/metal_madness.ogg"
out=target/data-rates
rm -rf "$out"
inputs=(--motion "$data/cmu-salsa" "$data/cmu-dance/modern" "$data/cmu-dance/break"
  "$data/cmu-dance/whirl" "$data/aistpp/motions")
"$bin" dataset build "${inputs[@]}" --music "$song" --source-fps "$data/cmu-salsa=60" \
  -o "$out/true" | tee "$out.true.txt"
"$bin" dataset build --motion "$data/cmu-salsa" --music "$song" -o "$out/header" \
  2> "$out.header.log" | tee "$out.header.txt"
/usr/bin/env python3 - "$out" <<'PY'
import json, sys, statistics as st
out = sys.argv[1]
true = json.load(open(f"{out}/true/manifest.json"))["takes"]
header = json.load(open(f"{out}/header/manifest.json"))["takes"]
why = {
    "salsa": "60 (header: 120) — the capture rate (shared/data/README.md: at 120 each foot lifts 2.0-2.4 times a second, salsa at ~320 BPM)",
    "modern": "120 (header) — cgspeed conversion rate; steps and speeds of a dancer",
    "whirl": "120 (header) — cgspeed conversion rate",
    "break": "30 (header) for CMU 85 (keijiro's FBX sample rate); 60 for AIST++ (its release)",
}
rows = ["| take | genre | fps | from | s | joint speed m/s | pelvis m/s | steps/s | floor median m | float % |",
        "|---|---|---:|---|---:|---:|---:|---:|---:|---:|"]
for t in true:
    rows.append(f"| {t['name']} | {t['genre']} | {t['source_fps']:g} | {t['rate_from']} | {t['seconds']:.1f} | "
                f"{t['joint_speed']:.3f} | {t['pelvis_speed']:.3f} | {t['step_rate']:.3f} | "
                f"{t['floor_median']:.3f} | {t['float_pct']:.1f} |")
by = {}
for t in true:
    by.setdefault(t["genre"], []).append(t)
summary = ["| genre | takes | rate | joint speed m/s (min-max) | steps/s (min-max) |", "|---|---:|---|---|---|"]
for g, ts in sorted(by.items()):
    js = [t["joint_speed"] for t in ts]; sr = [t["step_rate"] for t in ts]
    summary.append(f"| {g} | {len(ts)} | {why.get(g, 'header')} | {min(js):.2f}-{max(js):.2f} | {min(sr):.2f}-{max(sr):.2f} |")
hj = [t["joint_speed"] for t in header]; hs = [t["step_rate"] for t in header]
tj = [t["joint_speed"] for t in by["salsa"]]; ts_ = [t["step_rate"] for t in by["salsa"]]
flagged = sum(1 for t in header if t.get("warning"))
text = f"""# The true frame rate of every take in `../shared/data`

Written by `bash tools/data_rates.sh` (do not edit by hand). Each take is read as
`dancegen dataset build` reads it: retargeted to SMPL 24, resampled to 30 fps, its resting feet
put on y = 0 (`dancegen_motion::repr::motion::planted_floor_height`). Figures are
`dancegen_metrics::physical`'s: mean joint speed, mean horizontal pelvis speed, foot steps of
both feet per second, the lowest foot joint's median height and the share of frames with no foot
joint within 5 cm of the floor.

## Rates by genre

{chr(10).join(summary)}

`dancegen_dataset::takes::HUMAN_TEMPO` holds these ranges (the `break` row spans CMU 85 and the
AIST++ `gBR` takes, `*` spans every take); a take more than 15 % outside its genre's range is
warned about by `dataset build` (`crates/dancegen-dataset/tests/takes.rs` recomputes them).

## The salsa at its header's 120 fps

At the header's rate the {len(header)} salsa takes move their joints at {min(hj):.2f}-{max(hj):.2f} m/s
(mean {st.mean(hj):.2f}) and step {min(hs):.2f}-{max(hs):.2f} times a second (mean {st.mean(hs):.2f}); at 60 fps,
{min(tj):.2f}-{max(tj):.2f} m/s (mean {st.mean(tj):.2f}) and {min(ts_):.2f}-{max(ts_):.2f} steps a second
(mean {st.mean(ts_):.2f}, about {st.mean(ts_)/2:.2f} per foot: salsa's six steps in eight beats at
{st.mean(ts_)*8/6*60:.0f} BPM). `dataset build` without `--source-fps` flags {flagged} of the {len(header)} takes as
too fast for salsa.

## Every take

{chr(10).join(rows)}
"""
open("docs/data-rates.md", "w").write(text)
print("wrote docs/data-rates.md")
PY
