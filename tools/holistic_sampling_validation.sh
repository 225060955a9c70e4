#!/usr/bin/env bash
# Sampling-setting validation of a holistic (SoulNet) model on the TRAINING songs (issue 41):
# settings such as the token temperature or the guidance are chosen here, never on the held-out
# song (feelings.ogg), which tools/holistic_eval.sh then measures once.
#
#   MODEL=models/soulnet-small SAMPLING="temperature=0.7" bash tools/holistic_sampling_validation.sh
#
# Dances: every STRIDE-th training clip of the holistic data set's manifest (held-out clips
# excluded), generated on the clip's own song cut (`source_song`, from `song_start_s`, at most
# SECONDS long), seeds SEEDS. Prints FID_k and Div_k against the real training bodies (FineDance
# / Lodge protocol, as tools/holistic_eval.sh), the mean BAS (Bailando variant, each dance against
# its cut's beats) and the physical figures of `dancegen eval --metrics physical`, for the model
# and for the real training clips.
#
# Environment:
#   MODEL (required)           a holistic model directory
#   SAMPLING="k=v k=v"         [sampling] values to override (a patched copy of model.toml is
#                              written under OUT; the weights are linked, not copied)
#   DATASET=target/datasets/holistic   REFERENCE=<dir of the real training bodies, (T, 24, 3)
#                              .npy, as tools/holistic_eval.sh writes to $OUT/gt_train>
#   OUT=target/holistic-validation/<model name><SAMPLING>   STRIDE=3   CUT_SECONDS=20   SEEDS="0 1"
#   DANCEGEN=target/release/dancegen   PYTHON=/usr/bin/python3 (3.11+ with numpy)
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"
: "${MODEL:?set MODEL to a holistic model directory}"
: "${REFERENCE:?set REFERENCE to the real training bodies (tools/holistic_eval.sh writes OUT/gt_train)}"
BIN=${DANCEGEN:-$ROOT/target/release/dancegen}
DATASET=${DATASET:-$ROOT/target/datasets/holistic}
PYTHON=${PYTHON:-/usr/bin/python3}
SAMPLING=${SAMPLING:-}
TAG=$(printf '%s' "$SAMPLING" | tr ' =' '_-')
OUT=${OUT:-$ROOT/target/holistic-validation/$(basename "$MODEL")${TAG:+_$TAG}}
STRIDE=${STRIDE:-3}
SECONDS_MAX=${CUT_SECONDS:-20}
SEEDS=${SEEDS:-"0 1"}
[ -x "$BIN" ] || { echo "$BIN: no dancegen binary" >&2; exit 1; }
[ -f "$MODEL/model.toml" ] || { echo "$MODEL: no model.toml" >&2; exit 1; }
[ -f "$DATASET/manifest.json" ] || { echo "$DATASET: no manifest.json" >&2; exit 1; }
[ -d "$REFERENCE" ] || { echo "$REFERENCE: no real training bodies" >&2; exit 1; }
"$PYTHON" -c 'import numpy, tomllib' 2>/dev/null \
    || { echo "$PYTHON: needs Python 3.11+ with numpy" >&2; exit 1; }
mkdir -p "$OUT/dances" "$OUT/body" "$OUT/beats" "$OUT/features" "$OUT/eval"

# The model, with SAMPLING written over its [sampling] table.
GEN_MODEL=$MODEL
if [ -n "$SAMPLING" ]; then
    GEN_MODEL=$OUT/model
    mkdir -p "$GEN_MODEL"
    for f in "$MODEL"/*; do
        [ "$(basename "$f")" = model.toml ] || ln -sfn "$(realpath "$f")" "$GEN_MODEL/$(basename "$f")"
    done
    "$PYTHON" - "$MODEL/model.toml" "$GEN_MODEL/model.toml" $SAMPLING <<'PY'
import re, sys, tomllib
src, dst, pairs = sys.argv[1], sys.argv[2], sys.argv[3:]
text = open(src).read()
sampling = tomllib.loads(text).get("sampling")
if sampling is None:
    sys.exit(f"{src}: no [sampling] table")
head, sep, tail = text.partition("[sampling]")
for p in pairs:
    k, _, v = p.partition("=")
    if k not in sampling:
        sys.exit(f"SAMPLING: {k} is not a [sampling] key of {src} ({', '.join(sampling)})")
    tail, n = re.subn(rf"(?m)^{re.escape(k)}\s*=.*$", f"{k} = {v}", tail, count=1)
    assert n == 1, k
tomllib.loads(head + sep + tail)
open(dst, "w").write(head + sep + tail)
PY
fi

# The cuts: "stem song start end" per chosen training clip.
"$PYTHON" - "$DATASET/manifest.json" "$STRIDE" "$SECONDS_MAX" > "$OUT/cuts.txt" <<'PY'
import json, os, sys
path, stride, most = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
m = json.load(open(path))
held = set(m.get("held_out") or [])
clips = [c for c in m["clips"] if c["name"] not in held and c.get("source_song")]
for c in clips[::stride]:
    s = c["song_start_s"]
    e = min(c["song_end_s"], s + most)
    song = os.path.normpath(os.path.join(os.path.dirname(path), "..", "..", c["source_song"]))
    if not os.path.exists(song):
        song = os.path.normpath(c["source_song"])
    print(c["name"], song, f"{s:.3f}", f"{e:.3f}")
PY
[ -s "$OUT/cuts.txt" ] || { echo "$DATASET: no training clip with a song" >&2; exit 1; }

while read -r stem song s e; do
    feats=$OUT/features/$(basename "$song" .ogg).npy
    [ -f "$feats" ] || "$BIN" -q features "$song" --fps 30 -o "$feats"
    # The cut's beats as generate sees them: beat frames in [30 s, 30 e), shifted to 0.
    "$PYTHON" - "$feats" "$s" "$e" "$OUT/beats/$stem.npy" <<'PY'
import sys
import numpy as np
f = np.load(sys.argv[1]); s, e = round(float(sys.argv[2]) * 30), round(float(sys.argv[3]) * 30)
np.save(sys.argv[4], np.array([t - s for t in range(len(f)) if f[t, -1] > 0 and s <= t < e], dtype=np.int64))
PY
    for seed in $SEEDS; do
        out=$OUT/dances/${stem}_$seed.npy
        [ -f "$out" ] || "$BIN" -q generate "$song" --system holistic --model "$GEN_MODEL" \
            --start "$s" --end "$e" --seed "$seed" -o "$out"
    done
done < "$OUT/cuts.txt"
"$PYTHON" "$ROOT/tools/holistic_eval.py" body24 "$OUT/dances" "$OUT/body" >/dev/null
while read -r stem _; do
    for seed in $SEEDS; do
        "$BIN" -q eval --pred "$OUT/body/${stem}_$seed.npy" --protocol none --fps 30 --metrics bas \
            --bas-variant bailando --beats "$OUT/beats/$stem.npy" \
            --json "$OUT/eval/bas_${stem}_$seed.json" >/dev/null
    done
done < "$OUT/cuts.txt"
"$BIN" -q eval --pred "$OUT/body" --gt "$REFERENCE" --protocol finedance-lodge \
    --metrics fid_k,div_k --json "$OUT/eval/set.json" >/dev/null
"$BIN" -q eval --pred "$OUT/body" --protocol none --fps 30 --metrics physical \
    --json "$OUT/eval/physical.json" >/dev/null
"$BIN" -q eval --pred "$REFERENCE" --protocol none --fps 30 --metrics physical \
    --json "$OUT/eval/physical_real.json" >/dev/null
"$PYTHON" - "$OUT" "${SAMPLING:-model defaults}" <<'PY'
import glob, json, os, sys
import numpy as np
out, label = sys.argv[1], sys.argv[2]
s = json.load(open(os.path.join(out, "eval/set.json")))
bas = [json.load(open(f))["bas"] for f in glob.glob(os.path.join(out, "eval/bas_*.json"))]
def physical(name):
    p = json.load(open(os.path.join(out, "eval", name)))
    return "  ".join(f"{k} {p[k]:.3g}" for k in ("joint_speed", "step_rate", "jerk", "max_step",
                                                  "foot_slide", "leg_cross", "float"))
print(f"[{label}] fid_k {s['fid_k']:.1f}  div_k {s['div_k']:.2f}  bas {np.mean(bas):.3f} ({len(bas)} dances)")
print(f"physical: model {physical('physical.json')}")
print(f"physical: real  {physical('physical_real.json')}")
PY
