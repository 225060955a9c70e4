#!/usr/bin/env bash
# Holistic (SoulNet) evaluation on the held-out song (issue 19): generates dances with fingers and
# face for every held-out clip of the holistic data set (same cut of the held-out song) and for
# the whole song, per seed; measures the body against the real held-out motion with
# `dancegen eval` (FID_k, FID_g, Div, BAS, PFC, foot skating, freezing), the boundary jerk at the
# generator's window joins, finger / face movement against the synthetic held-out data, BAS
# against the guidance scale and against half-beat-shifted beats; runs `holistic_probe` for MMR
# retrieval / matching score and the part autoencoders' reconstruction; writes
# docs/holistic-eval.md.
#
#   bash tools/holistic_eval.sh [--dry-run]
#
# Environment (all optional):
#   SEEDS="0 1 2"          seeds of the held-out segments and of the whole-song dances
#   GUIDANCES="1 2 4 6"    --guidance values of the CFG sweep (seed 0, held-out segments; the
#                          model's default value reuses the seed-0 segments)
#   LONG=1                 also the whole song per seed (0: segments only)
#   MODEL=models/soulnet-small     MODEL_WAIT=0 (seconds to wait for the bundle to appear)
#   DATASET=target/datasets/holistic (manifest.json, motion/, holistic/, held_out/)
#   SONG=../shared/data/music/sectoid/feelings.ogg (the held-out clips' song in the manifest)
#   VQ_RUNS="target/runs/soulnet_small_vq target/runs/soulnet_small_vq_rvq
#            target/runs/soulnet_small_vq_vq"   part autoencoder runs to compare (missing: noted)
#   DANCEGEN=target/release/dancegen (must have `generate --system holistic`)
#   PROBE=target/release/examples/holistic_probe (built with `cargo build --release --locked
#          -p dancegen-train --example holistic_probe` when missing or older than its source)
#   OUT=target/holistic-eval (scratch; finished generations of the same model are reused)
#   REPORT=docs/holistic-eval.md
#   PYTHON=/usr/bin/python3 (3.11+ with numpy)
#   MMR_LOSS_MODEL=DIR     a bundle whose generator was trained with the MMR alignment loss
#                          ([model] mmr_loss_weight > 0): section 7 compares it with
#   MMR_BASE_MODEL=DIR     the same generator without the loss (default: MODEL), on the held-out
#                          segments and SEEDS (without MMR_LOSS_MODEL section 7 says so)
#   SEED_NOTE="..."        a sentence added to the report
#   FRESH=1                regenerate everything
#   CONTACT=1              draw the contact sheet (tools/contact_sheet.sh): the first seed's body
#                          and the real motion of the first held-out clip, at the same moments,
#                          to images/holistic-eval-contact.png beside the report (default: 1, 0
#                          in a dry run)
#
# Every body, generated and real, also gets the physical plausibility figures
# (`dancegen eval --metrics physical`).
#
# --dry-run: no model; each "generated" clip is the held-out real body with the synthetic
# fingers and face, shifted per seed (tests the plumbing). Writes to $OUT/dry-run/ only
# (CONTACT=1: its sheet to $OUT/dry-run/images/).
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"
# shellcheck source=tools/eval_lib.sh
source "$ROOT/tools/eval_lib.sh"
parse_eval_args "$0" "$@"

abs() { realpath -m "$1"; }
SEEDS=${SEEDS:-"0 1 2"}
GUIDANCES=${GUIDANCES:-"1 2 4 6"}
LONG=${LONG:-1}
MODEL=$(abs "${MODEL:-$ROOT/models/soulnet-small}")
MODEL_WAIT=${MODEL_WAIT:-0}
MMR_LOSS_MODEL=${MMR_LOSS_MODEL:+$(abs "$MMR_LOSS_MODEL")}
MMR_BASE_MODEL=$(abs "${MMR_BASE_MODEL:-$MODEL}")
DATASET=$(abs "${DATASET:-$ROOT/target/datasets/holistic}")
SONG=${SONG:-$ROOT/../shared/data/music/sectoid/feelings.ogg}
VQ_RUNS=${VQ_RUNS:-"target/runs/soulnet_small_vq target/runs/soulnet_small_vq_rvq target/runs/soulnet_small_vq_vq"}
PYTHON=${PYTHON:-/usr/bin/python3}
OUT=$(abs "${OUT:-$ROOT/target/holistic-eval}")
REPORT=$(abs "${REPORT:-$ROOT/docs/holistic-eval.md}")
if [ "$DRY" = 1 ]; then
    OUT=$OUT/dry-run
    REPORT=$OUT/holistic-eval.md
fi
CONTACT=${CONTACT:-$((1 - DRY))}
CONTACT_PNG=$(dirname "$REPORT")/images/holistic-eval-contact.png
HELP="$PYTHON $ROOT/tools/holistic_eval.py"
SOLO_HELP="$PYTHON $ROOT/tools/solo_eval.py"
T0=$(date +%s)
LOAD_NOTE=$(load_note)
log() { echo "[holistic-eval $(date -u +%H:%M:%S)] $*" >&2; }
"$PYTHON" -c 'import numpy, tomllib' 2>/dev/null \
    || { echo "$PYTHON: needs Python 3.11+ with numpy (PYTHON=/usr/bin/python3)" >&2; exit 1; }

# ---- the binaries: snapshots (hard links), so a rebuild during the run cannot swap them
SRC_BIN=${DANCEGEN:-$ROOT/target/release/dancegen}
[ -x "$SRC_BIN" ] && "$SRC_BIN" generate --help 2>/dev/null | grep -q holistic \
    || { echo "$SRC_BIN: no 'generate --system holistic' (build target/release/dancegen)" >&2; exit 1; }
snapshot_binary "$SRC_BIN" "$OUT"
log "binary: $SRC_BIN"
PROBE_SRC=${PROBE:-$ROOT/target/release/examples/holistic_probe}
PROBE_RS=$ROOT/crates/dancegen-train/examples/holistic_probe.rs
build_probe() {
    log "building holistic_probe ($1)"
    cargo build --release --locked -q -p dancegen-train --example holistic_probe \
        || log "cargo build of holistic_probe failed; using what is there"
}
snapshot_probe() {
    PROBE_BIN=""
    if [ -x "$PROBE_SRC" ]; then
        PROBE_BIN=$OUT/bin/holistic_probe
        ln -f "$PROBE_SRC" "$PROBE_BIN" 2>/dev/null || cp -f "$PROBE_SRC" "$PROBE_BIN"
    fi
}
# The built example is used as it is; it is (re)built when missing, or when it fails and is
# older than its source (see probe() below).
[ -z "${PROBE:-}" ] && [ ! -x "$PROBE_SRC" ] && build_probe "missing"
snapshot_probe
PROBE_REBUILT=0

[ -f "$DATASET/manifest.json" ] || { echo "$DATASET/manifest.json missing: build the holistic data set first" >&2; exit 1; }
[ -f "$SONG" ] || { echo "$SONG missing" >&2; exit 1; }
SONG=$(realpath "$SONG")
model_ready() { # [dir]
    local f
    for f in model.toml vq.safetensors mmr.safetensors generator.safetensors normalizer.json; do
        [ -f "${1:-$MODEL}/$f" ] || return 1
    done
}
fingerprint() { # model dir: its weights, configs and normaliser (not MODEL_CARD.md)
    (cd "$1" && find . -type f \( -name '*.safetensors' -o -name '*.toml' -o -name '*.json' \) \
        -printf '%p %s %T@\n' | sort | sha256sum | cut -c1-16)
}
if [ "$DRY" = 0 ]; then
    waited=0
    until model_ready; do
        if [ "$waited" -ge "$MODEL_WAIT" ]; then
            echo "$MODEL: no complete SoulNet bundle (model.toml, *.safetensors, normalizer.json)" >&2
            exit 1
        fi
        log "waiting for $MODEL ($waited of $MODEL_WAIT s)"
        sleep 30
        waited=$((waited + 30))
    done
    [ "$waited" -gt 0 ] && sleep 10   # let the bundle writer finish its last file
    read -r MODEL_NAME _ _ _ DEFAULT_G _ < <($HELP model "$MODEL")
else
    MODEL_NAME="(dry run: no model)" DEFAULT_G=4
fi

# ---- song features / beats, held-out clips, their beats (and half-beat-shifted), real joints
mkdir -p "$OUT/song" "$OUT/beats" "$OUT/gt" "$OUT/gt_train" "$OUT/gt_all" "$OUT/eval/real"
[ -f "$OUT/song/features.npy" ] || "$BIN" -q features "$SONG" --fps 30 -o "$OUT/song/features.npy"
$SOLO_HELP clips --manifest "$DATASET/manifest.json" --features "$OUT/song/features.npy" \
    --song "$SONG" --out "$OUT/beats" > "$OUT/clips.txt"
$HELP halfbeats --clips "$OUT/clips.txt" --beats "$OUT/beats" --out "$OUT/beats_half"
SONG_FRAMES=$(cat "$OUT/beats/song_frames.txt")
NCLIPS=$(wc -l < "$OUT/clips.txt")
convert_real_clips "$OUT" "$DATASET"
log "$NCLIPS held-out clips; song $SONG_FRAMES frames; model $MODEL_NAME (default guidance $DEFAULT_G)"

# ---- generation (reused for the same model files unless FRESH=1)
if [ "$DRY" = 1 ]; then FP="dry-run"; else FP=$(fingerprint "$MODEL"); fi
if [ "${FRESH:-0}" = 1 ] || [ "$(cat "$OUT/gen/fingerprint" 2>/dev/null)" != "$FP" ]; then
    [ -d "$OUT/gen" ] && log "new model or FRESH=1: discarding earlier generations"
    rm -rf "$OUT/gen" "$OUT/body" "$OUT/times.tsv"
    mkdir -p "$OUT/gen"
    echo "$FP" > "$OUT/gen/fingerprint"
fi
TIMES=$OUT/times.tsv   # kind, seed or guidance, seconds, file, frames (appended across runs)
FAILED=$OUT/failed.txt
: > "$FAILED"
gen() { # kind key seed out.npy frames [start end [guidance]]
    local kind=$1 key=$2 seed=$3 out=$4 frames=$5 start=${6:-} end=${7:-} g=${8:-}
    local js=${out%.npy}.json
    [ -f "$out" ] && [ -f "$js" ] && return 0
    mkdir -p "$(dirname "$out")"
    local t
    t=$(date +%s.%N)
    if [ "$DRY" = 1 ]; then
        local stem
        stem=$(basename "$out" .npy)
        [ "$kind" = long ] && stem=$(head -1 "$OUT/clips.txt" | cut -d' ' -f1)
        $HELP stub --gt24 "$OUT/gt/$stem.npy" --holistic "$DATASET/held_out/holistic/$stem.npz" \
            --motion "$DATASET/held_out/motion/$stem.npz" --frames "$frames" \
            --seed "$(( seed + $(printf '%s' "$g" | cksum | cut -c1-4) ))" -o "${out%.npy}.part.npy" --json "${js%.json}.part.json"
    else
        local extra=()
        [ -n "$start" ] && extra+=(--start "$start" --end "$end")
        [ -n "$g" ] && extra+=(--guidance "$g")
        if ! "$BIN" -q generate "$SONG" --system holistic --model "${GEN_MODEL:-$MODEL}" --seed "$seed" \
            "${extra[@]}" -o "${out%.npy}.part.npy" -o "${js%.json}.part.json" 2> "$out.err"; then
            log "FAILED: $kind $key $(basename "$out"): $(tail -3 "$out.err" | tr '\n' ' ')"
            echo "$kind $key $(basename "$out"): $(tail -3 "$out.err" | tr '\n' ' ')" >> "$FAILED"
            rm -f "${out%.npy}.part.npy" "${js%.json}.part.json"
            return 0
        fi
        rm -f "$out.err"
    fi
    mv "${js%.json}.part.json" "$js"
    mv "${out%.npy}.part.npy" "$out"
    local secs
    secs=$(awk -v a="$t" -v b="$(date +%s.%N)" 'BEGIN{printf "%.2f", b-a}')
    printf '%s\t%s\t%s\t%s\t%s\n' "$kind" "$key" "$secs" "$(basename "$out")" "$frames" >> "$TIMES"
    log "  $kind $key $(basename "$out"): $secs s"
}

# Seed by seed (segments, then the whole song), so an interrupted run leaves complete seeds.
for seed in $SEEDS; do
    while read -r stem start end frames _; do
        gen seg "$seed" "$seed" "$OUT/gen/seed$seed/$stem.npy" "$frames" "$start" "$end"
    done < "$OUT/clips.txt"
    log "generated segments: seed $seed"
    if [ "$LONG" = 1 ]; then
        gen long "$seed" "$seed" "$OUT/gen/seed$seed/long/song.npy" "$SONG_FRAMES"
        log "generated the whole song: seed $seed"
    fi
done
# Guidance sweep: seed 0, the held-out segments; the default guidance reuses seed 0's segments.
for g in $GUIDANCES; do
    d=$OUT/gen/cfg$g
    if awk -v a="$g" -v b="$DEFAULT_G" 'BEGIN{exit !(a + 0 == b + 0)}' \
        && [ "$(find "$OUT/gen/seed0" -maxdepth 1 -name '*.json' 2>/dev/null | wc -l)" = "$NCLIPS" ]; then
        mkdir -p "$d"
        while read -r stem _; do
            for ext in npy json; do ln -f "$OUT/gen/seed0/$stem.$ext" "$d/$stem.$ext"; done
        done < "$OUT/clips.txt"
        touch "$d/REUSED"
        continue
    fi
    while read -r stem start end frames _; do
        gen cfg "$g" 0 "$d/$stem.npy" "$frames" "$start" "$end" "$g"
    done < "$OUT/clips.txt"
    log "generated guidance $g"
done

# ---- with and without the MMR loss (section 7): held-out segments, SEEDS, per model
MMR_SETS=()
if [ -n "$MMR_LOSS_MODEL" ]; then
    if [ "$DRY" = 1 ] || { model_ready "$MMR_LOSS_MODEL" && model_ready "$MMR_BASE_MODEL"; }; then
        MMR_SETS=("without=$MMR_BASE_MODEL" "with=$MMR_LOSS_MODEL")
    else
        log "MMR_LOSS_MODEL / MMR_BASE_MODEL: not complete bundles; section 7 has no comparison"
    fi
fi
for entry in "${MMR_SETS[@]}"; do
    name=${entry%%=*}
    GEN_MODEL=${entry#*=}
    d=$OUT/mmr/gen/$name
    if [ "$DRY" = 1 ]; then fp="dry-run $name"; else fp=$(fingerprint "$GEN_MODEL"); fi
    if [ "${FRESH:-0}" = 1 ] || [ "$(cat "$d/fingerprint" 2>/dev/null)" != "$fp" ]; then
        rm -rf "$d" "$OUT/mmr/body/$name"
        mkdir -p "$d"
        echo "$fp" > "$d/fingerprint"
    fi
    for seed in $SEEDS; do
        while read -r stem start end frames _; do
            o=$d/seed$seed/$stem
            if [ "$DRY" = 0 ] && [ "$GEN_MODEL" = "$MODEL" ] && [ -f "$OUT/gen/seed$seed/$stem.json" ] \
                && [ -f "$OUT/gen/seed$seed/$stem.npy" ]; then
                mkdir -p "$d/seed$seed"
                ln -f "$OUT/gen/seed$seed/$stem.npy" "$o.npy"
                ln -f "$OUT/gen/seed$seed/$stem.json" "$o.json"
                continue
            fi
            # dry run: a different stub per model
            gen "mmr_$name" "$seed" "$seed" "$o.npy" "$frames" "$start" "$end" \
                "$( [ "$DRY" = 1 ] && [ "$name" = with ] && echo 9 || true)"
        done < "$OUT/clips.txt"
    done
    log "generated segments of the MMR comparison: $name ($GEN_MODEL)"
done
GEN_MODEL=""

# ---- SMPL-24-shaped bodies of the generated joints
mkdir -p "$OUT/body"
n=$($HELP body24 "$OUT/gen" "$OUT/body")
[ -d "$OUT/mmr/gen" ] && n=$((n + $($HELP body24 "$OUT/mmr/gen" "$OUT/mmr/body")))
log "body joints: $n files converted"

# ---- evaluation
EV=("$BIN" -q eval)
CLIP_METRICS=pfc,fsr,freeze,inverted,boundary_jerk
eval_clips() { # dir out.json
    "${EV[@]}" --pred "$1" --protocol none --fps 30 --metrics "$CLIP_METRICS" --json "$2" >/dev/null
}
eval_bas() { # outdir pred_dir beats_dir prefix
    local stem
    while read -r stem _; do
        "${EV[@]}" --pred "$2/$stem.npy" --protocol none --fps 30 --metrics bas \
            --bas-variant bailando --beats "$3/$stem.npy" --json "$1/${4}_$stem.json" >/dev/null
    done < "$OUT/clips.txt"
}
eval_set() { # pred gt out.json
    "${EV[@]}" --pred "$1" --gt "$2" --protocol finedance-lodge \
        --metrics fid_k,fid_g,div_k,div_g --json "$3" >/dev/null
}
eval_physical() { # pred (a file or directory) out.json: the physical plausibility figures
    "${EV[@]}" --pred "$1" --protocol none --fps 30 --metrics physical --json "$2" >/dev/null
}
full_set() { # dir: every held-out clip there
    [ "$(find "$1" -maxdepth 1 -name '*.npy' 2>/dev/null | wc -l)" = "$NCLIPS" ]
}
eval_clips "$OUT/gt" "$OUT/eval/real/clip.json"
eval_physical "$OUT/gt" "$OUT/eval/real/physical.json"
eval_physical "$OUT/gt_train" "$OUT/eval/real/physical_train.json"
eval_bas "$OUT/eval/real" "$OUT/gt" "$OUT/beats" bas
eval_bas "$OUT/eval/real" "$OUT/gt" "$OUT/beats_half" bas_half
eval_set "$OUT/gt_train" "$OUT/gt" "$OUT/eval/real/fid_train.json"
eval_set "$OUT/gt_train" "$OUT/gt_all" "$OUT/eval/real/fid_train_all.json"
eval_set "$OUT/gt" "$OUT/gt_all" "$OUT/eval/real/fid_heldout_all.json"
for seed in $SEEDS; do
    b=$OUT/body/seed$seed
    e=$OUT/eval/seed$seed
    rm -rf "$e"
    mkdir -p "$e"
    if full_set "$b"; then
        eval_set "$b" "$OUT/gt" "$e/fid.json"
        eval_set "$b" "$OUT/gt_all" "$e/fid_all.json"
        eval_clips "$b" "$e/clip.json"
        eval_physical "$b" "$e/physical.json"
        eval_bas "$e" "$b" "$OUT/beats" bas
        eval_bas "$e" "$b" "$OUT/beats_half" bas_half
    else
        log "skipping the segments of seed $seed: not all $NCLIPS generated"
    fi
    if [ "$LONG" = 1 ] && [ -f "$b/long/song.npy" ]; then
        "${EV[@]}" --pred "$b/long/song.npy" --protocol none --fps 30 \
            --metrics "bas,$CLIP_METRICS" --bas-variant bailando \
            --beats "$OUT/beats/song.npy" --json "$e/long.json" >/dev/null
        "${EV[@]}" --pred "$b/long/song.npy" --protocol none --fps 30 --metrics bas \
            --bas-variant bailando --beats "$OUT/beats_half/song.npy" --json "$e/long_half.json" >/dev/null
        eval_physical "$b/long/song.npy" "$e/physical_long.json"
    fi
    log "evaluated seed $seed"
done
for g in $GUIDANCES; do
    b=$OUT/body/cfg$g
    e=$OUT/eval/cfg$g
    rm -rf "$e"
    full_set "$b" || { log "skipping guidance $g: not all $NCLIPS generated"; continue; }
    mkdir -p "$e"
    eval_clips "$b" "$e/clip.json"
    eval_physical "$b" "$e/physical.json"
    eval_set "$b" "$OUT/gt_all" "$e/fid_all.json"
    eval_bas "$e" "$b" "$OUT/beats" bas
    eval_bas "$e" "$b" "$OUT/beats_half" bas_half
done
log "evaluated the guidance sweep"
rm -rf "$OUT/eval/mmr"
for entry in "${MMR_SETS[@]}"; do
    name=${entry%%=*}
    for seed in $SEEDS; do
        b=$OUT/mmr/body/$name/seed$seed
        e=$OUT/eval/mmr/$name/seed$seed
        full_set "$b" || { log "skipping MMR $name seed $seed: not all $NCLIPS generated"; continue; }
        mkdir -p "$e"
        eval_set "$b" "$OUT/gt" "$e/fid.json"
        eval_set "$b" "$OUT/gt_all" "$e/fid_all.json"
        eval_clips "$b" "$e/clip.json"
        eval_physical "$b" "$e/physical.json"
        eval_bas "$e" "$b" "$OUT/beats" bas
        eval_bas "$e" "$b" "$OUT/beats_half" bas_half
    done
done
[ "${#MMR_SETS[@]}" -gt 0 ] && log "evaluated the MMR comparison"

# ---- MMR retrieval / matching score and part reconstruction (holistic_probe)
mkdir -p "$OUT/probe"
rm -f "$OUT/probe/"*.json "$OUT/probe/"*.err
RUNS=() MISSING=()
for r in $VQ_RUNS; do
    ra=$(abs "$r")
    if [ -f "$ra/model.toml" ] && [ -f "$ra/model.safetensors" ]; then RUNS+=("$ra"); else
        MISSING+=("$(realpath --relative-to="$ROOT" "$ra" 2>/dev/null || echo "$r")")
        log "VQ run $r: not a finished run, skipped"
    fi
done
probe() { # name args...
    local name=$1
    shift
    if [ -z "$PROBE_BIN" ]; then echo "no holistic_probe binary" > "$OUT/probe/$name.err"; return 0; fi
    if "$PROBE_BIN" "$@" > "$OUT/probe/$name.json.tmp" 2> "$OUT/probe/$name.err"; then
        mv "$OUT/probe/$name.json.tmp" "$OUT/probe/$name.json"
        [ -s "$OUT/probe/$name.err" ] || rm -f "$OUT/probe/$name.err"
    else
        rm -f "$OUT/probe/$name.json.tmp"
        log "holistic_probe $name failed: $(grep . "$OUT/probe/$name.err" | tail -1)"
        if [ -z "${PROBE:-}" ] && [ "$PROBE_REBUILT" = 0 ] && [ "$PROBE_RS" -nt "$PROBE_SRC" ]; then
            PROBE_REBUILT=1
            build_probe "it failed and is older than its source"
            snapshot_probe
            probe "$name" "$@"
        fi
    fi
}
if [ "$DRY" = 0 ]; then
    probe mmr mmr "$MODEL" "$DATASET"
    # The matching score of generated dances, judged by the shipped model's MMR (both MMR-loss
    # generators share it): the shipped model's segments and each comparison set, per seed.
    for seed in $SEEDS; do
        probe "mmr_gen_seed$seed" mmr-gen "$MODEL" "$DATASET" "$OUT/gen/seed$seed"
        for entry in "${MMR_SETS[@]}"; do
            name=${entry%%=*}
            probe "mmr_gen_${name}_seed$seed" mmr-gen "$MODEL" "$DATASET" "$OUT/mmr/gen/$name/seed$seed"
        done
    done
else
    echo "dry run: no model" > "$OUT/probe/mmr.err"
fi
if [ "${#RUNS[@]}" -gt 0 ]; then
    probe recon recon "$DATASET" "${RUNS[@]}"
else
    echo "no finished VQ run among: $VQ_RUNS" > "$OUT/probe/recon.err"
fi
log "probes done"

# ---- contact sheet: the first seed's body and the real motion of the first held-out clip, at
# the same moments (not in a dry run unless CONTACT=1: there "generated" is real)
rm -f "$OUT/contact.json"
if [ "$CONTACT" = 1 ]; then
    read -r stem start end _ < "$OUT/clips.txt"
    read -r seed _ <<< "$SEEDS"
    contact_sheet_clip "$OUT/body/seed$seed/$stem.npy" "generated (seed $seed)" \
        "SoulNet \`$MODEL_NAME\` (\`$(basename "$MODEL")\`, seed $seed, its body as evaluated)" \
        "$stem" "$start" "$end"
fi

# ---- report
WALL=$(( $(date +%s) - T0 ))
CMD="bash tools/holistic_eval.sh"
[ "$DRY" = 1 ] && CMD="$CMD --dry-run"
for v in SEEDS GUIDANCES LONG; do
    default=$(case $v in SEEDS) echo "0 1 2";; GUIDANCES) echo "1 2 4 6";; LONG) echo 1;; esac)
    [ "${!v}" != "$default" ] && CMD="$v=\"${!v}\" $CMD"
done
if [ -n "$MMR_LOSS_MODEL" ]; then
    CMD="MMR_LOSS_MODEL=$(realpath --relative-to="$ROOT" "$MMR_LOSS_MODEL") MMR_BASE_MODEL=$(realpath --relative-to="$ROOT" "$MMR_BASE_MODEL") $CMD"
fi
rel() { # relative to the repository, unless that climbs more than one level
    local r
    r=$(realpath --relative-to="$ROOT" "$1" 2>/dev/null) || { echo "$1"; return; }
    case $r in ../../*) realpath -m "$1" ;; *) echo "$r" ;; esac
}
DIRTY=0
[ -n "$(git status --porcelain --untracked-files=no 2>/dev/null)" ] && DIRTY=1
M_COMMAND=$CMD M_DATE=$(date -u '+%Y-%m-%d %H:%M UTC') \
M_COMMIT=$(git rev-parse --short HEAD 2>/dev/null || echo unknown) M_DIRTY=$DIRTY \
M_MODEL_DIR=$(rel "$MODEL") M_MODEL_ABS=$MODEL M_BINARY=$(rel "$SRC_BIN") \
M_PROBE=$( [ -n "$PROBE_BIN" ] && rel "$PROBE_SRC" || echo "none") M_NPROC=$(nproc) \
M_LOAD="$LOAD_NOTE; load average $(cut -d' ' -f1-3 /proc/loadavg) at the end" \
M_OUT=$(rel "$OUT") M_WALL="$((WALL / 60)) min $((WALL % 60)) s" M_SONG=$(rel "$SONG") \
M_SONG_SECONDS=$(awk -v f="$SONG_FRAMES" 'BEGIN{printf "%.1f", f/30}') \
M_DATASET=$(rel "$DATASET") M_DATASET_ABS=$DATASET M_ROOT=$ROOT M_SEED_NOTE=${SEED_NOTE:-} \
M_PROBE_MMR="holistic_probe mmr $(rel "$MODEL") $(rel "$DATASET")" \
M_PROBE_RECON="holistic_probe recon $(rel "$DATASET")$(for r in "${RUNS[@]}"; do printf ' %s' "$(rel "$r")"; done)" \
M_VQ_MISSING="${MISSING[*]:-}" \
M_MMR_SETS="$(for e in "${MMR_SETS[@]}"; do printf '%s=%s\n' "${e%%=*}" "$(rel "${e#*=}")"; done)" \
M_MMR_REQUESTED=$( [ -n "$MMR_LOSS_MODEL" ] && rel "$MMR_LOSS_MODEL" || true) \
M_MMR_IMPL=$(grep -q mmr_loss_weight "$ROOT/crates/dancegen-train/src/tasks/soulnet.rs" 2>/dev/null && echo 1 || echo 0) \
$PYTHON - "$OUT/meta.json" <<'EOF'
import json, os, sys
e = os.environ
json.dump({
    "command": e["M_COMMAND"], "date": e["M_DATE"], "commit": e["M_COMMIT"],
    "dirty": e["M_DIRTY"] == "1", "model_dir": e["M_MODEL_DIR"], "model_abs": e["M_MODEL_ABS"],
    "binary": e["M_BINARY"], "probe": e["M_PROBE"], "nproc": e["M_NPROC"], "load": e["M_LOAD"],
    "out": e["M_OUT"], "wall": e["M_WALL"], "song": e["M_SONG"],
    "song_seconds": e["M_SONG_SECONDS"], "dataset": e["M_DATASET"],
    "dataset_abs": e["M_DATASET_ABS"], "root": e["M_ROOT"], "seed_note": e["M_SEED_NOTE"],
    "probe_cmd_mmr": e["M_PROBE_MMR"], "probe_cmd_recon": e["M_PROBE_RECON"],
    "vq_missing": e["M_VQ_MISSING"].split(),
    "mmr_sets": [ln.split("=", 1) for ln in e["M_MMR_SETS"].splitlines() if ln],
    "mmr_requested": e["M_MMR_REQUESTED"], "mmr_loss_implemented": e["M_MMR_IMPL"] == "1",
}, open(sys.argv[1], "w"), indent=1)
EOF
RFLAGS=()
[ "$DRY" = 1 ] && RFLAGS+=(--dry-run)
$HELP report --out "$OUT" --seeds "$SEEDS" --guidances "$GUIDANCES" "${RFLAGS[@]}" --report "$REPORT"
log "done in $((WALL / 60)) min $((WALL % 60)) s"
