#!/usr/bin/env bash
# Genre control of a solo model (issue 16): for every genre the model knows, dances at two cuts of
# the held-out song and several seeds, classified by `dancegen eval --metrics genre` (a
# nearest-centroid kinetic-feature classifier fit on the real, unmirrored training clips of a data
# set) and compared by FID_k with that genre's real clips.
#
#   bash tools/genre_eval.sh
#
# Environment (all optional):
#   MODEL=models/lodgepp-small   DATASET=target/datasets/solo-v3 (manifest.json + motion/)
#   GENRES="..."  (default: the model's genres)   SEEDS="0 1 2"   CUTS="20:36 80:96" (seconds)
#   SONG=../shared/data/music/sectoid/feelings.ogg   OUT=target/genre-eval
#   DANCEGEN=path/to/dancegen (default target/release/dancegen)   FLAGS="extra generate flags"
#   MIN_CLIPS=2 (genres with fewer real training clips are left out of the classifier)
# Writes $OUT/<genre>/*.npy, $OUT/<genre>.json (the eval JSON) and prints one line per genre:
#   genre  share_requested  counts  fid_k(own genre)  chance_uniform  chance_majority  loo_accuracy
#   genres left out of the classifier (fewer real clips than MIN_CLIPS, default 2: eval's
#   --genre-min-clips)
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"
BIN=${DANCEGEN:-$ROOT/target/release/dancegen}
MODEL=${MODEL:-$ROOT/models/lodgepp-small}
DATASET=${DATASET:-$ROOT/target/datasets/solo-v3}
SONG=${SONG:-$ROOT/../shared/data/music/sectoid/feelings.ogg}
SEEDS=${SEEDS:-"0 1 2"}
CUTS=${CUTS:-"20:36 80:96"}
OUT=${OUT:-$ROOT/target/genre-eval}
PYTHON=${PYTHON:-python3}
[ -x "$BIN" ] || { echo "$BIN: no dancegen binary (build with cargo build --release)" >&2; exit 1; }
[ -f "$MODEL/model.toml" ] || { echo "$MODEL/model.toml missing" >&2; exit 1; }
[ -f "$DATASET/manifest.json" ] || { echo "$DATASET/manifest.json missing: build the data set" >&2; exit 1; }
if [ -z "${GENRES:-}" ]; then
    GENRES=$($PYTHON - "$MODEL/model.toml" <<'EOF'
import sys, tomllib
print(" ".join(tomllib.load(open(sys.argv[1], "rb"))["genres"]))
EOF
)
fi

# The real reference: the data set's training clips without their mirror images and extra song
# pairings (one clip per take), as world joints.
mkdir -p "$OUT/real"
$PYTHON - "$DATASET/manifest.json" <<'EOF' > "$OUT/real.txt"
import json, sys
m = json.load(open(sys.argv[1]))
for c in m["clips"]:
    if c["motion"].startswith("held_out/") or c["name"].endswith("_mirror") or "__" in c["name"]:
        continue
    print(c["name"], c["motion"])
EOF
while read -r name motion; do
    [ -f "$OUT/real/$name.npy" ] || "$BIN" -q convert "$DATASET/$motion" -o "$OUT/real/$name.npy"
done < "$OUT/real.txt"

for g in $GENRES; do
    mkdir -p "$OUT/$g"
    for seed in $SEEDS; do
        for cut in $CUTS; do
            s=${cut%%:*} e=${cut##*:}
            out=$OUT/$g/seed${seed}_${s}_${e}.npy
            # shellcheck disable=SC2086
            [ -f "$out" ] || "$BIN" -q generate "$SONG" --model "$MODEL" --genre "$g" --seed "$seed" \
                --start "$s" --end "$e" ${FLAGS:-} -o "$out"
        done
    done
    # A genre with too few real clips to be classified is reported, not checked.
    if ! "$BIN" -q eval --pred "$OUT/$g" --gt "$OUT/real" --gt-genres "$DATASET/manifest.json" \
        --want-genre "$g" --genre-min-clips "${MIN_CLIPS:-2}" --protocol finedance-lodge --fps 30 \
        --metrics genre --json "$OUT/$g.json" >/dev/null 2>"$OUT/$g.err"; then
        if grep -q -- "--genre-min-clips" "$OUT/$g.err"; then
            printf '%s\tnot checked: %s\n' "$g" "$(grep -o -- "has [0-9]* real --gt clip.*" "$OUT/$g.err" | head -1)"
            continue
        fi
        cat "$OUT/$g.err" >&2
        exit 1
    fi
    $PYTHON - "$OUT/$g.json" "$g" <<'EOF'
import json, sys
r = json.load(open(sys.argv[1]))["genre"]
g = sys.argv[2]
fid = (r.get("fid_k") or {}).get(g)
fid = "n/a" if fid is None else f"{fid:.1f}"
counts = ",".join(f"{k}:{v}" for k, v in sorted(r["counts"].items()))
excl = ",".join(f"{k}:{v}" for k, v in sorted((r.get("excluded") or {}).items())) or "none"
print(f"{g}\tshare {r['share_requested']:.2f} ({counts})\tfid_k({g}) {fid}\t"
      f"chance {r['chance_uniform']:.2f}/{r['chance_majority']:.2f}\tloo {r['loo_accuracy_real']:.2f}\t"
      f"left out (too few real clips) {excl}")
EOF
done
