#!/usr/bin/env bash
# Group (TCDiff++) evaluation on the held-out group set: for held-out samples with N = 2, 3 and
# 5 dancers and 3 seeds, dances the sample's song span with the full system (formation control
# from the sample's own trajectories), the parallel sampler, a free dance and baseline B1 (N
# solo dances placed on the formation); measures them with `dancegen eval` and
# tools/group_eval.py, and writes docs/group-eval.md.
#
#   bash tools/group_eval.sh
#
# Environment (all optional):
#   SEEDS="0 1 2"   PER_N=4 (clips per group size)   STEPS=N (default: the model's)
#   MODEL=models/tcdiffpp-small   SOLO_MODEL=models/lodgepp-small
#   DATASET=target/datasets/group (configs/tcdiffpp_small.toml says how it is built)
#   DANCEGEN=target/release/dancegen (snapshotted into $OUT/bin)
#   OUT=target/group-eval (finished generations are reused; delete it to start over)
#   REPORT=docs/group-eval.md   PYTHON=python3 (3.11+, standard library only)
#   ONLY="full lgds" (main configurations to run; default all)   GROUP_ARGS="--guidance 1"
#     (extra `dancegen generate` arguments for the group dances, named in the report)
#   ABLATIONS="full_500=DIR no_fp=DIR no_fa=DIR no_dpe=DIR no_dl=DIR": bundles of the
#     configs/ablations/tcdiffpp_*_500.toml runs (`dancegen bundle --group RUN -o DIR`), added
#     as the report's ablation rows
#   CONTACT=1   draw the contact sheet (tools/contact_sheet.sh: the first clip's full-system
#     dance, first seed, and the real couple 13 at the same moments) to
#     images/group-eval-contact.png beside the report (0: none)
#
# Every dancer, generated and real, also gets the physical plausibility figures
# (`dancegen eval --metrics physical`); the held-out real salsa is read at its true 60 fps.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"
# shellcheck source=tools/eval_lib.sh
source "$ROOT/tools/eval_lib.sh"
parse_eval_args "$0" "$@"
[ "$DRY" = 1 ] && { echo "--dry-run is not offered by the group evaluation" >&2; exit 2; }

SEEDS=${SEEDS:-"0 1 2"}
PER_N=${PER_N:-4}
MODEL=${MODEL:-$ROOT/models/tcdiffpp-small}
SOLO_MODEL=${SOLO_MODEL:-$ROOT/models/lodgepp-small}
DATASET=${DATASET:-$ROOT/target/datasets/group}
OUT=${OUT:-$ROOT/target/group-eval}
REPORT=${REPORT:-$ROOT/docs/group-eval.md}
PYTHON=${PYTHON:-python3}
CONTACT=${CONTACT:-1}
CONTACT_PNG=""
[ "$CONTACT" = 1 ] && CONTACT_PNG=$(dirname "$REPORT")/images/group-eval-contact.png
LOAD_NOTE=$(load_note)
[ -f "$DATASET/manifest.json" ] || { echo "$DATASET/manifest.json missing: build the group data set (configs/tcdiffpp_small.toml)" >&2; exit 1; }
mkdir -p "$OUT"
snapshot_binary "${DANCEGEN:-$ROOT/target/release/dancegen}" "$OUT"
# shellcheck disable=SC2086
"$PYTHON" "$ROOT/tools/group_eval.py" --bin "$BIN" --dataset "$DATASET" \
    --data "$ROOT/../shared/data" --model "$MODEL" --solo-model "$SOLO_MODEL" --out "$OUT" \
    --report "$REPORT" --seeds $SEEDS --per-n "$PER_N" ${STEPS:+--steps "$STEPS"} \
    --load-note "$LOAD_NOTE" ${ABLATIONS:+--ablation $ABLATIONS} \
    ${ONLY:+--only $ONLY} --group-args "${GROUP_ARGS:-}" --contact-png "$CONTACT_PNG"
