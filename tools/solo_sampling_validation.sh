#!/usr/bin/env bash
# Sampling-setting validation of a solo model on the TRAINING songs (issue 16): settings such
# as GPT top-k or the guidance weight are chosen here, never on the held-out song
# (feelings.ogg), which tools/solo_eval.sh then measures once.
#
#   MODEL=target/models/lodgepp-v6 bash tools/solo_sampling_validation.sh
#
# 12 dances: escape_from_chaosland.ogg and metal_madness.ogg, cuts 20-36 s and 60-76 s (CUTS),
# seeds 0-2, --genre salsa. Prints FID_k against the real training clips of REFERENCE, Div_k, the
# share upside down, the mean BAS (Bailando variant, each clip against its cut's beats) and the
# mean joint speeds (m/s) of pelvis, knee, ankle, elbow and wrist, and the physical figures of
# `dancegen eval --metrics physical` (joint speed, steps, jerk, largest frame step, foot sliding,
# crossed shins, floating), for the model and the reference.
#
# Environment: MODEL (required), DANCEGEN (default target/release/dancegen),
#   REFERENCE=target/solo-eval/gt_train (real training clips as (T, 24, 3) .npy, written by
#   tools/solo_eval.sh), OUT=target/solo-validation/<model name>, GENRE=salsa,
#   PYTHON=python3 with numpy, FLAGS="extra generate flags" (e.g. --no-foot-refine; give each
#   flag set its own OUT), CUTS="20:36 60:76" (start:end seconds of each song; both songs are
#   longer than 140 s, so CUTS="20:36 60:76 100:116 120:136" doubles the set).
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"
: "${MODEL:?set MODEL to a solo model directory}"
BIN=${DANCEGEN:-$ROOT/target/release/dancegen}
REFERENCE=${REFERENCE:-$ROOT/target/solo-eval/gt_train}
OUT=${OUT:-$ROOT/target/solo-validation/$(basename "$MODEL")}
GENRE=${GENRE:-salsa}
PYTHON=${PYTHON:-python3}
SONGS=$ROOT/../shared/data/music/sectoid
[ -x "$BIN" ] || { echo "$BIN: no dancegen binary" >&2; exit 1; }
[ -d "$REFERENCE" ] || { echo "$REFERENCE: no real clips (run tools/solo_eval.sh first)" >&2; exit 1; }
$PYTHON -c "import numpy" 2>/dev/null || { echo "$PYTHON has no numpy (apt-get install python3-numpy)" >&2; exit 1; }
mkdir -p "$OUT/dances" "$OUT/beats" "$OUT/eval"
for song in escape_from_chaosland metal_madness; do
    [ -f "$OUT/features_$song.npy" ] || "$BIN" -q features "$SONGS/$song.ogg" -o "$OUT/features_$song.npy"
    for cut in ${CUTS:-20:36 60:76}; do
        s=${cut%:*}
        e=${cut#*:}
        # The cut's beats as generate sees them: beat frames in [30 s, 30 e), shifted to 0.
        $PYTHON - "$OUT/features_$song.npy" "$s" "$e" "$OUT/beats/${song}_$s.npy" <<'PY'
import sys
import numpy as np
f = np.load(sys.argv[1]); s, e = int(sys.argv[2]) * 30, int(sys.argv[3]) * 30
np.save(sys.argv[4], np.array([t - s for t in range(len(f)) if f[t, -1] > 0 and s <= t < e], dtype=np.int64))
PY
        for seed in 0 1 2; do
            out=$OUT/dances/${song}_${s}_$seed.npy
            # shellcheck disable=SC2086
            [ -f "$out" ] || "$BIN" -q generate "$SONGS/$song.ogg" --model "$MODEL" --start "$s" \
                --end "$e" --seed "$seed" --genre "$GENRE" ${FLAGS:-} -o "$out"
            "$BIN" -q eval --pred "$out" --protocol none --fps 30 --metrics bas \
                --bas-variant bailando --beats "$OUT/beats/${song}_$s.npy" \
                --json "$OUT/eval/bas_${song}_${s}_$seed.json" >/dev/null
        done
    done
done
"$BIN" -q eval --pred "$OUT/dances" --gt "$REFERENCE" --protocol none --fps 30 \
    --metrics fid_k,div_k,inverted,freeze --json "$OUT/eval/set.json" >/dev/null
"$BIN" -q eval --pred "$OUT/dances" --protocol none --fps 30 --metrics physical \
    --json "$OUT/eval/physical.json" >/dev/null
[ -f "$OUT/eval/physical_real.json" ] || "$BIN" -q eval --pred "$REFERENCE" --protocol none \
    --fps 30 --metrics physical --json "$OUT/eval/physical_real.json" >/dev/null
$PYTHON - "$OUT" "$REFERENCE" <<'PY'
import glob, json, os, sys
import numpy as np
out, ref = sys.argv[1], sys.argv[2]
s = json.load(open(os.path.join(out, "eval/set.json")))
bas = [json.load(open(f))["bas"] for f in glob.glob(os.path.join(out, "eval/bas_*.json"))]
def speeds(files):
    v = [np.linalg.norm(np.diff(np.load(f), axis=0), axis=-1).mean(0) * 30 for f in files]
    m = np.mean(v, axis=0)
    return " / ".join(f"{m[j]:.2f}" for j in (0, 4, 7, 18, 20))
print(f"fid_k {s['fid_k']:.1f}  div_k {s['div_k']:.2f}  inverted {s['inverted']:.3f}  "
      f"bas {np.mean(bas):.3f} ({len(bas)} dances)")
def physical(name):
    p = json.load(open(os.path.join(out, "eval", name)))
    return "  ".join(f"{k} {p[k]:.3g}" for k in ("joint_speed", "step_rate", "jerk", "max_step",
                                                  "foot_slide", "leg_cross", "float"))
print(f"physical: model {physical('physical.json')}")
print(f"physical: real  {physical('physical_real.json')}")
print(f"speed m/s pelvis/knee/ankle/elbow/wrist: model {speeds(glob.glob(os.path.join(out, 'dances/*.npy')))}, "
      f"real {speeds(glob.glob(os.path.join(ref, '*.npy')))}")
PY
