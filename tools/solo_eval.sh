#!/usr/bin/env bash
# Solo (Lodge++) evaluation on the held-out song: generates dances with the full system and its
# ablations for every held-out real clip of the solo data set (same cut of the held-out song) and
# for the whole song, runs `dancegen eval`, and writes docs/solo-eval.md.
#
#   bash tools/solo_eval.sh [--dry-run]
#
# Environment (all optional):
#   SEEDS="0 1 2"        seeds per configuration
#   CONFIGS="full no_global no_foot_refine no_pen_guidance no_foot_lock no_beat_align edge"
#   LONG=1               also the whole song per configuration and seed (0: segments only)
#   MODEL=models/lodgepp-small   GENRE=salsa
#   DATASET=target/datasets/solo-v3 (built by `dancegen dataset build`, manifest.json + held_out/;
#                        the command is at the top of configs/lodgepp_small_pddm.toml)
#   SONG=../shared/data/music/sectoid/feelings.ogg (the held-out song of the manifest)
#   DANCEGEN=path/to/dancegen (default: target/release/dancegen if it has `generate`, else the
#            test-profile build target/debug/dancegen, built if needed)
#   OUT=target/solo-eval (scratch: generated motion, eval JSON; finished generations are reused)
#   REPORT=docs/solo-eval.md
#   PYTHON=python3 (3.11+, standard library only)
#   SEED_NOTE="..." a sentence added to the report (e.g. why fewer seeds were used)
#   BASELINE=DIR         an earlier run's OUT (e.g. of the previously shipped model): the report adds
#                        a before/after table of the two full systems; BASELINE_LABEL names it;
#                        BASELINE2 / BASELINE2_LABEL add a second, later one
#   FRESH=1              regenerate everything (otherwise outputs of the same model are reused)
#   CONTACT=1            draw the contact sheet (tools/contact_sheet.sh): the first seed's full
#                        system and the real motion of the first held-out clip, at the same
#                        moments, to images/solo-eval-contact.png beside the report (default: 1,
#                        0 in a dry run)
#   CONTACT_CLIP=60_13_scaled  the held-out clip of the contact sheet (default: the first of the
#                        genre GENRE, so the generated and the real dancer dance the same genre)
#
# Every motion also gets the physical plausibility figures (`dancegen eval --metrics physical`).
#
# --dry-run: no model; each "generated" clip is the held-out real motion, shifted per seed (tests
# the plumbing). Writes to $OUT/dry-run/ and never to docs/ (CONTACT=1: its sheet to
# $OUT/dry-run/images/).
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"
# shellcheck source=tools/eval_lib.sh
source "$ROOT/tools/eval_lib.sh"
parse_eval_args "$0" "$@"

SEEDS=${SEEDS:-"0 1 2"}
CONFIGS=${CONFIGS:-"full no_global no_foot_refine no_pen_guidance no_foot_lock no_beat_align edge"}
LONG=${LONG:-1}
MODEL=${MODEL:-$ROOT/models/lodgepp-small}
GENRE=${GENRE:-salsa}
DATASET=${DATASET:-$ROOT/target/datasets/solo-v3}
SONG=${SONG:-$ROOT/../shared/data/music/sectoid/feelings.ogg}
PYTHON=${PYTHON:-python3}
OUT=${OUT:-$ROOT/target/solo-eval}
REPORT=${REPORT:-$ROOT/docs/solo-eval.md}
if [ "$DRY" = 1 ]; then
    OUT=$OUT/dry-run
    REPORT=$OUT/solo-eval.md
fi
CONTACT=${CONTACT:-$((1 - DRY))}
CONTACT_PNG=$(dirname "$REPORT")/images/solo-eval-contact.png
HELP="$PYTHON $ROOT/tools/solo_eval.py"
T0=$(date +%s)
LOAD_NOTE=$(load_note)
log() { echo "[solo-eval $(date -u +%H:%M:%S)] $*" >&2; }

# ---- the binary: snapshot it (hard link) so a rebuild during the run cannot swap it midway
has_generate() { [ -x "$1" ] && "$1" generate --help >/dev/null 2>&1; }
if [ -n "${DANCEGEN:-}" ]; then
    SRC_BIN=$DANCEGEN
elif has_generate "$ROOT/target/release/dancegen"; then
    SRC_BIN=$ROOT/target/release/dancegen
else
    if ! cargo build --profile test -p dancegen-cli --locked -q; then
        log "cargo build failed; using the existing target/debug/dancegen"
    fi
    SRC_BIN=$ROOT/target/debug/dancegen
fi
has_generate "$SRC_BIN" || { echo "$SRC_BIN: no 'generate' subcommand" >&2; exit 1; }
snapshot_binary "$SRC_BIN" "$OUT"
log "binary: $SRC_BIN"

[ -f "$DATASET/manifest.json" ] || { echo "$DATASET/manifest.json missing: build the solo data set first" >&2; exit 1; }
[ -f "$SONG" ] || { echo "$SONG missing" >&2; exit 1; }
SONG=$(realpath "$SONG")
if [ "$DRY" = 0 ]; then
    [ -f "$MODEL/model.toml" ] || { echo "$MODEL/model.toml missing (no trained model yet?)" >&2; exit 1; }
    read -r WINDOW MODEL_NAME GENRE < <($HELP model "$MODEL" --genre "$GENRE")
else
    WINDOW=128 MODEL_NAME="(dry run: no model)"
fi

# ---- song features / beats, held-out clips, their beats and real joints
mkdir -p "$OUT/song" "$OUT/beats" "$OUT/gt" "$OUT/gt_train" "$OUT/gt_all" "$OUT/eval/real"
[ -f "$OUT/song/features.npy" ] || "$BIN" -q features "$SONG" --fps 30 -o "$OUT/song/features.npy"
$HELP clips --manifest "$DATASET/manifest.json" --features "$OUT/song/features.npy" \
    --song "$SONG" --out "$OUT/beats" > "$OUT/clips.txt"
SONG_FRAMES=$(cat "$OUT/beats/song_frames.txt")
# The held-out clips, and the training clips: a second, larger FID reference (all real salsa)
# and a calibration row.
convert_real_clips "$OUT" "$DATASET"
log "$(wc -l < "$OUT/clips.txt") held-out clips; song $SONG_FRAMES frames; window $WINDOW"

flags_of() {
    case $1 in
        full) echo "" ;;
        no_global) echo "--sampler autoregressive" ;;
        no_foot_refine) echo "--no-foot-refine" ;;
        no_pen_guidance) echo "--no-penetration-guidance" ;;
        no_foot_lock) echo "--no-foot-lock" ;;
        no_beat_align) echo "--no-beat-align" ;;
        edge) echo "--sampler edge" ;;
        *) echo "unknown configuration $1" >&2; exit 2 ;;
    esac
}

# ---- generation (existing outputs are reused: the script can be re-run after an interruption)
# ... but only for the same model files and genre (FRESH=1 regenerates everything).
if [ "$DRY" = 1 ]; then FP="dry-run"; else
    # Weights, configs, normalisers, library (not MODEL_CARD.md and other notes).
    FP="genre=$GENRE $(cd "$MODEL" && find . -type f \( -name '*.safetensors' -o -name '*.toml' \
        -o -name '*.json' -o -name '*.npz' \) -printf '%p %s %T@\n' | sort | sha256sum | cut -c1-16)"
fi
if [ "${FRESH:-0}" = 1 ] || [ "$(cat "$OUT/gen/fingerprint" 2>/dev/null)" != "$FP" ]; then
    [ -d "$OUT/gen" ] && log "new model or FRESH=1: discarding earlier generations"
    rm -rf "$OUT/gen" "$OUT/times.tsv"
    mkdir -p "$OUT/gen"
    echo "$FP" > "$OUT/gen/fingerprint"
fi
TIMES=$OUT/times.tsv   # appended across runs; the report keeps the last entry per output
FAILED=$OUT/failed.txt
: > "$FAILED"
gen() { # config seed kind out [start end]
    local cfg=$1 seed=$2 kind=$3 out=$4 start=${5:-} end=${6:-}
    [ -f "$out" ] && return 0
    mkdir -p "$(dirname "$out")"
    local t=$(date +%s.%N)
    if [ "$DRY" = 1 ]; then
        local stem src frames
        stem=$(basename "$out" .npy)
        if [ "$kind" = long ]; then
            src=$OUT/gt/$(head -1 "$OUT/clips.txt" | cut -d' ' -f1).npy; frames=$SONG_FRAMES
        else
            src=$OUT/gt/$stem.npy; frames=$(awk -v s="$stem" '$1==s{print $4}' "$OUT/clips.txt")
        fi
        $HELP stub --src "$src" --frames "$frames" --seed "$seed" -o "$out"
    else
        local range=()
        [ -n "$start" ] && range=(--start "$start" --end "$end")
        # shellcheck disable=SC2046
        if ! "$BIN" -q generate "$SONG" --model "$MODEL" --genre "$GENRE" --seed "$seed" \
            "${range[@]}" $(flags_of "$cfg") -o "$out" 2> "$out.err"; then
            log "FAILED: $cfg seed $seed $kind $(basename "$out"): $(tail -3 "$out.err" | tr '\n' ' ')"
            echo "$cfg seed $seed $kind $(basename "$out"): $(tail -3 "$out.err" | tr '\n' ' ')" >> "$FAILED"
            rm -f "$out"
            return 0
        fi
        rm -f "$out.err"
    fi
    local secs
    secs=$(awk -v a="$t" -v b="$(date +%s.%N)" 'BEGIN{printf "%.2f", b-a}')
    printf '%s\t%s\t%s\t%s\t%s\n' "$cfg" "$seed" "$kind" "$secs" "$(basename "$out")" >> "$TIMES"
    log "  $cfg seed $seed $kind $(basename "$out"): $secs s"
}

# Seed by seed (segments, then the whole song), so that an interrupted run leaves complete
# seeds behind: re-run with fewer SEEDS to report what is there.
for seed in $SEEDS; do
    for cfg in $CONFIGS; do
        while read -r stem start end frames npz; do
            gen "$cfg" "$seed" seg "$OUT/gen/$cfg/seed$seed/seg/$stem.npy" "$start" "$end"
        done < "$OUT/clips.txt"
        log "generated segments: $cfg seed $seed"
    done
    if [ "$LONG" = 1 ]; then
        for cfg in $CONFIGS; do
            gen "$cfg" "$seed" long "$OUT/gen/$cfg/seed$seed/long/song.npy"
            log "generated long form: $cfg seed $seed"
        done
    fi
done

# ---- evaluation
EV=("$BIN" -q eval)
CLIP_METRICS=pfc,fsr,penetration,freeze,inverted,boundary_jerk
eval_clips() { # dir out.json
    "${EV[@]}" --pred "$1" --protocol none --fps 30 --metrics "$CLIP_METRICS" --json "$2" >/dev/null
}
eval_bas() { # outdir pred_dir
    local stem
    while read -r stem _; do
        "${EV[@]}" --pred "$2/$stem.npy" --protocol none --fps 30 --metrics bas \
            --bas-variant bailando --beats "$OUT/beats/$stem.npy" --json "$1/bas_$stem.json" >/dev/null
    done < "$OUT/clips.txt"
}
eval_set() { # pred gt out.json
    "${EV[@]}" --pred "$1" --gt "$2" --protocol finedance-lodge \
        --metrics fid_k,fid_g,div_k,div_g --json "$3" >/dev/null
}
eval_physical() { # pred (a file or directory) out.json: the physical plausibility figures
    "${EV[@]}" --pred "$1" --protocol none --fps 30 --metrics physical --json "$2" >/dev/null
}
eval_clips "$OUT/gt" "$OUT/eval/real/clip.json"
eval_physical "$OUT/gt" "$OUT/eval/real/physical.json"
eval_physical "$OUT/gt_train" "$OUT/eval/real/physical_train.json"
eval_bas "$OUT/eval/real" "$OUT/gt"
eval_set "$OUT/gt_train" "$OUT/gt" "$OUT/eval/real/fid_train.json"
eval_set "$OUT/gt_train" "$OUT/gt_all" "$OUT/eval/real/fid_train_all.json"
eval_set "$OUT/gt" "$OUT/gt_all" "$OUT/eval/real/fid_heldout_all.json"
NCLIPS=$(wc -l < "$OUT/clips.txt")
for cfg in $CONFIGS; do
    for seed in $SEEDS; do
        d=$OUT/gen/$cfg/seed$seed
        e=$OUT/eval/$cfg/seed$seed
        rm -rf "$e"
        n=$(find "$d/seg" -name '*.npy' 2>/dev/null | wc -l)
        if [ "$n" != "$NCLIPS" ]; then
            log "skipping $cfg seed $seed: $n of $NCLIPS segments generated"
            continue
        fi
        mkdir -p "$e"
        eval_set "$d/seg" "$OUT/gt" "$e/fid.json"
        eval_set "$d/seg" "$OUT/gt_all" "$e/fid_all.json"
        eval_clips "$d/seg" "$e/clip.json"
        eval_physical "$d/seg" "$e/physical.json"
        eval_bas "$e" "$d/seg"
        if [ "$LONG" = 1 ] && [ -f "$d/long/song.npy" ]; then
            "${EV[@]}" --pred "$d/long/song.npy" --protocol none --fps 30 \
                --metrics "bas,$CLIP_METRICS" --bas-variant bailando \
                --beats "$OUT/beats/song.npy" --json "$e/long.json" >/dev/null
            eval_physical "$d/long/song.npy" "$e/physical_long.json"
        fi
    done
    log "evaluated $cfg"
done

# ---- contact sheet: the first seed's full system and the real motion of the first held-out
# clip, at the same moments (not in a dry run unless CONTACT=1: there "generated" is real)
if [ "$CONTACT" = 1 ]; then
    if [ -z "${CONTACT_CLIP:-}" ]; then
        CONTACT_CLIP=$($PYTHON - "$DATASET/manifest.json" "$GENRE" "$OUT/clips.txt" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))
genre = {c["name"]: c.get("genre") for c in m["clips"]}
stems = [line.split()[0] for line in open(sys.argv[3]) if line.strip()]
print(next((s for s in stems if genre.get(s) == sys.argv[2]), stems[0]))
PY
)
    fi
    read -r stem start end _ < <(awk -v c="$CONTACT_CLIP" '$1 == c' "$OUT/clips.txt")
    read -r seed _ <<< "$SEEDS"
    contact_sheet_clip "$OUT/gen/full/seed$seed/seg/$stem.npy" "generated (full, seed $seed)" \
        "$MODEL_NAME (\`$(basename "$MODEL")\`, full system, seed $seed)" "$stem" "$start" "$end"
else
    rm -f "$OUT/contact.json"
fi

# ---- report
WALL=$(( $(date +%s) - T0 ))
CMD="bash tools/solo_eval.sh"
[ "$DRY" = 1 ] && CMD="$CMD --dry-run"
for v in SEEDS CONFIGS LONG; do
    default=$(case $v in SEEDS) echo "0 1 2";; CONFIGS) echo "full no_global no_foot_refine no_pen_guidance no_foot_lock no_beat_align edge";; LONG) echo 1;; esac)
    [ "${!v}" != "$default" ] && CMD="$v=\"${!v}\" $CMD"
done
DIRTY=false
[ -n "$(git status --porcelain --untracked-files=no 2>/dev/null)" ] && DIRTY=true
rel() { realpath --relative-to="$ROOT" "$1" 2>/dev/null || echo "$1"; }
SONG_SECONDS=$(awk -v f="$SONG_FRAMES" 'BEGIN{printf "%.1f", f/30}')
$PYTHON - "$OUT/meta.json" <<EOF
import json, sys
json.dump({
    "command": '''$CMD''',
    "date": "$(date -u '+%Y-%m-%d %H:%M UTC')",
    "commit": "$(git rev-parse --short HEAD 2>/dev/null || echo unknown)",
    "dirty": $( [ "$DIRTY" = true ] && echo True || echo False ),
    "model_dir": "$(rel "$MODEL")",
    "model_name": '''$MODEL_NAME''',
    "genre": "$GENRE",
    "binary": "$(rel "$SRC_BIN")",
    "nproc": "$(nproc)",
    "load": "$LOAD_NOTE; load average $(cut -d' ' -f1-3 /proc/loadavg) at the end",
    "out": "$(rel "$OUT")",
    "wall": "$((WALL / 60)) min $((WALL % 60)) s",
    "song": "$(rel "$SONG")",
    "song_seconds": "$SONG_SECONDS",
    "manifest": "$(rel "$DATASET/manifest.json")",
    "manifest_abs": "$DATASET/manifest.json",
    "seed_note": '''${SEED_NOTE:-}''',
}, open(sys.argv[1], "w"), indent=1)
EOF
RFLAGS=()
[ "$LONG" = 1 ] && RFLAGS+=(--long)
[ "$DRY" = 1 ] && RFLAGS+=(--dry-run)
[ -n "${BASELINE:-}" ] && RFLAGS+=(--baseline "$BASELINE" --baseline-label "${BASELINE_LABEL:-the earlier model}")
[ -n "${BASELINE2:-}" ] && RFLAGS+=(--baseline "$BASELINE2" --baseline-label "${BASELINE2_LABEL:-a second earlier model}")
$HELP report --out "$OUT" --seeds "$SEEDS" --configs "$CONFIGS" --window "$WINDOW" \
    "${RFLAGS[@]}" --report "$REPORT"
log "done in $((WALL / 60)) min $((WALL % 60)) s"
