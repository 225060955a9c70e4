#!/usr/bin/env bash
# Duet (ReactDance, reactive dance) evaluation on the held-out couples: for every held-out clip of
# the duet data set, generates a follower for the real leader (and the clip's song cut) with the
# full system and its ablations, runs `dancegen eval` with the duet metrics, and writes
# docs/duet-eval.md.
#
#   bash tools/duet_eval.sh [--dry-run]
#
# Environment (all optional):
#   SEEDS="0 1 2"        seeds per configuration
#   CONFIGS="full no_foot_lock no_separation no_beat_align single_cfg autoregressive m64 no_pm"
#       full            MODEL, default sampling (BLC + layer-wise guidance) and couple separation
#       no_foot_lock    MODEL, --no-foot-lock (the follower's root glides as generated)
#       no_separation   MODEL, --no-separation (the follower where the model put it)
#       no_beat_align   MODEL, --no-beat-align (the follower's timing as generated)
#       single_cfg      MODEL, --guidance 2.0 (one scale s = 1 for every level, no LDCFG)
#       autoregressive  MODEL, --sampler autoregressive (w/o BLC)
#       m64             MODEL_M64 (trained with sliding-window stride 64 instead of 4)
#       no_pm           MODEL_NO_PM (autoencoder trained without progressive masking)
#     a configuration whose model directory does not exist is skipped (noted in the report)
#   MODEL=models/reactdance-small
#   MODEL_M64=target/models/reactdance-small-m64   MODEL_NO_PM=target/models/reactdance-small-no-pm
#       (bundled from the runs of configs/ablations/reactdance_*.toml with `dancegen bundle`)
#   STEPS=N              denoising steps for every configuration (default: each model's own)
#   DATASET=target/datasets/duet (built by `dancegen dataset build --pairing duet`)
#   DANCEGEN=path/to/dancegen (default: target/release/dancegen; snapshotted into $OUT/bin)
#   OUT=target/duet-eval (scratch: joints, generated followers, eval JSON; finished generations
#                         are reused)
#   REPORT=docs/duet-eval.md
#   PYTHON=python3 (3.11+, standard library only)
#   SEED_NOTE="..." a sentence added to the report (e.g. why fewer seeds were used)
#   BASELINE=target/duet-eval-old  an earlier run's OUT (another model, same clips and seeds):
#                        its full system is added as a "before" row; BASELINE_LABEL names it
#   FRESH=1              regenerate everything (otherwise outputs of the same model files and
#                        flags are reused)
#   CONTACT=1            draw the contact sheet (tools/contact_sheet.sh): the first seed's full
#                        system and the real couple of the first held-out clip, at the same
#                        moments, to images/duet-eval-contact.png beside the report (default: 1,
#                        0 in a dry run)
#
# Every follower, generated and real, also gets the physical plausibility figures
# (`dancegen eval --metrics physical`).
#
# --dry-run: no model; each "generated" follower is the real held-out follower moved by a few cm
# per seed (tests the plumbing end to end). Writes to $OUT/dry-run/ and never to docs/
# (CONTACT=1: its sheet to $OUT/dry-run/images/).
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"
# shellcheck source=tools/eval_lib.sh
source "$ROOT/tools/eval_lib.sh"
parse_eval_args "$0" "$@"

ALL_CONFIGS="full no_foot_lock no_separation no_beat_align single_cfg autoregressive m64 no_pm"
SEEDS=${SEEDS:-"0 1 2"}
CONFIGS=${CONFIGS:-$ALL_CONFIGS}
MODEL=${MODEL:-$ROOT/models/reactdance-small}
MODEL_M64=${MODEL_M64:-$ROOT/target/models/reactdance-small-m64}
MODEL_NO_PM=${MODEL_NO_PM:-$ROOT/target/models/reactdance-small-no-pm}
STEPS=${STEPS:-}
DATASET=${DATASET:-$ROOT/target/datasets/duet}
PYTHON=${PYTHON:-python3}
OUT=${OUT:-$ROOT/target/duet-eval}
REPORT=${REPORT:-$ROOT/docs/duet-eval.md}
if [ "$DRY" = 1 ]; then
    OUT=$OUT/dry-run
    REPORT=$OUT/duet-eval.md
fi
mkdir -p "$OUT"
OUT=$(realpath "$OUT")
CONTACT=${CONTACT:-$((1 - DRY))}
CONTACT_PNG=$(dirname "$REPORT")/images/duet-eval-contact.png
HELP="$PYTHON $ROOT/tools/duet_eval.py"
T0=$(date +%s)
LOAD_NOTE=$(load_note)
log() { echo "[duet-eval $(date -u +%H:%M:%S)] $*" >&2; }
for c in $CONFIGS; do
    case " $ALL_CONFIGS " in *" $c "*) ;; *) echo "unknown configuration $c (known: $ALL_CONFIGS)" >&2; exit 2 ;; esac
done

# ---- the binary: snapshot it (hard link) so a rebuild during the run cannot swap it midway
SRC_BIN=${DANCEGEN:-$ROOT/target/release/dancegen}
if ! { [ -x "$SRC_BIN" ] && "$SRC_BIN" generate --help 2>/dev/null | grep -q -- '--leader'; }; then
    echo "$SRC_BIN: missing or without duet generation (\`generate --leader\`): build it with" \
        "\`cargo build --release -p dancegen-cli\` or set DANCEGEN" >&2
    exit 1
fi
snapshot_binary "$SRC_BIN" "$OUT"
log "binary: $SRC_BIN"

[ -f "$DATASET/manifest.json" ] || { echo "$DATASET/manifest.json missing: build the duet data set first" >&2; exit 1; }
rel() { # relative to the repository root if inside it, else absolute
    local p
    p=$(realpath -m "$1")
    case $p in "$ROOT"/*) echo "${p#"$ROOT"/}" ;; *) echo "$p" ;; esac
}

# ---- configurations: model directory and flags; skipped when the model does not exist
model_of() {
    case $1 in
        full|no_foot_lock|no_separation|no_beat_align|single_cfg|autoregressive) echo "$MODEL" ;;
        m64) echo "$MODEL_M64" ;;
        no_pm) echo "$MODEL_NO_PM" ;;
    esac
}
flags_of() {
    case $1 in
        full|m64|no_pm) echo "" ;;
        no_foot_lock) echo "--no-foot-lock" ;;
        no_separation) echo "--no-separation" ;;
        no_beat_align) echo "--no-beat-align" ;;
        single_cfg) echo "--guidance 2.0" ;;
        autoregressive) echo "--sampler autoregressive" ;;
    esac
}
: > "$OUT/configs.tsv"
RUN=""
REAL_WINDOW=""
for cfg in $CONFIGS; do
    dir=$(model_of "$cfg")
    if [ "$DRY" = 1 ]; then
        # No model is read: every configuration runs (the block is the default 60 tokens × 4).
        note="dry run"
        [ -f "$dir/model.toml" ] || note="dry run; model directory missing"
        printf '%s\tok\t%s\t240\t4\t60\t-\t-\t(%s)\n' "$cfg" "$(rel "$dir")" "$note" >> "$OUT/configs.tsv"
    elif [ -f "$dir/model.toml" ]; then
        info=$($HELP model "$dir")
        printf '%s\tok\t%s\t%s\n' "$cfg" "$(rel "$dir")" "$info" >> "$OUT/configs.tsv"
    else
        why="model directory $(rel "$dir") does not exist"
        [ -d "$dir" ] && why="$(rel "$dir") has no model.toml"
        printf '%s\t%s\t%s\t0\t0\t0\t-\t-\t-\n' "$cfg" "$why" "$(rel "$dir")" >> "$OUT/configs.tsv"
        log "skipping $cfg: $why"
        continue
    fi
    RUN="$RUN $cfg"
done
RUN=${RUN# }
window_of() { awk -F'\t' -v c="$1" '$1 == c {print $4}' "$OUT/configs.tsv"; }
# The real followers' boundary jerk is measured at the full model's block grid (240 if absent).
REAL_WINDOW=$(window_of full)
[ -n "$REAL_WINDOW" ] && [ "$REAL_WINDOW" != 0 ] || REAL_WINDOW=240

# ---- clips: held-out (generation + eval) and all real clips (FID reference), as joints
mkdir -p "$OUT/gt" "$OUT/leader" "$OUT/gt_all" "$OUT/gt_leader_all" "$OUT/gt_train" "$OUT/eval/real"
$HELP clips --manifest "$DATASET/manifest.json" --root "$ROOT" \
    --heldout "$OUT/clips.txt" --all "$OUT/all.txt"
while read -r stem mot lead; do
    "$BIN" -q convert "$mot" -o "$OUT/gt_all/$stem.npy"
    "$BIN" -q convert "$lead" -o "$OUT/gt_leader_all/$stem.npy"
done < "$OUT/all.txt"
rm -f "$OUT"/gt/*.npy "$OUT"/leader/*.npy "$OUT"/gt_train/*.npy
while read -r stem _; do
    ln -f "$OUT/gt_all/$stem.npy" "$OUT/gt/$stem.npy"
    ln -f "$OUT/gt_leader_all/$stem.npy" "$OUT/leader/$stem.npy"
done < "$OUT/clips.txt"
# The training followers (every real clip but the held-out ones), for the physical figures.
while read -r stem _; do
    awk -v s="$stem" '$1 == s {f = 1} END {exit !f}' "$OUT/clips.txt" \
        || ln -f "$OUT/gt_all/$stem.npy" "$OUT/gt_train/$stem.npy"
done < "$OUT/all.txt"
NCLIPS=$(wc -l < "$OUT/clips.txt")
log "$NCLIPS held-out clips, $(wc -l < "$OUT/all.txt") real clips in the FID reference; configurations: ${RUN:-none}"

# ---- generation (existing outputs are reused: the script can be re-run after an interruption)
# ... but only for the same model files, flags and steps (FRESH=1 regenerates everything).
fingerprint() { # cfg
    if [ "$DRY" = 1 ]; then echo "dry-run"; return; fi
    local dir
    dir=$(model_of "$1")
    # Weights, configs, normalisers (not MODEL_CARD.md and other notes).
    echo "flags=$(flags_of "$1") steps=$STEPS $(cd "$dir" && find . -type f \( -name '*.safetensors' \
        -o -name '*.toml' -o -name '*.json' -o -name '*.npz' \) -printf '%p %s %T@\n' | sort \
        | sha256sum | cut -c1-16)"
}
for cfg in $RUN; do
    fp=$(fingerprint "$cfg")
    g=$OUT/gen/$cfg
    if [ "${FRESH:-0}" = 1 ] || [ "$(cat "$g/fingerprint" 2>/dev/null)" != "$fp" ]; then
        [ -d "$g" ] && log "$cfg: new model or flags, or FRESH=1: discarding earlier generations"
        rm -rf "$g"
        mkdir -p "$g"
        echo "$fp" > "$g/fingerprint"
    fi
done
FAILED=$OUT/failed.txt
: > "$FAILED"
gen() { # cfg seed stem start song leader out
    local cfg=$1 seed=$2 stem=$3 start=$4 song=$5 leader=$6 out=$7
    [ -f "$out" ] && return 0
    mkdir -p "$(dirname "$out")"
    local t gsec="-" tsec="-"
    t=$(date +%s.%N)
    if [ "$DRY" = 1 ]; then
        $HELP stub --src "$OUT/gt/$stem.npy" --seed "$seed" -o "$out"
    else
        local extra=()
        [ -n "$STEPS" ] && extra=(--steps "$STEPS")
        # shellcheck disable=SC2046
        if ! "$BIN" generate "$song" --start "$start" --leader "$leader" \
            --model "$(model_of "$cfg")" --seed "$seed" $(flags_of "$cfg") "${extra[@]}" \
            -o "$out" > "$out.log" 2> "$out.err"; then
            log "FAILED: $cfg seed $seed $stem: $(tail -3 "$out.err" | tr '\n' ' ')"
            echo "$cfg seed $seed $stem: $(tail -3 "$out.err" | tr '\n' ' ')" >> "$FAILED"
            rm -f "$out"
            return 0
        fi
        gsec=$(grep -o 'generated in [0-9.]* s' "$out.log" | awk '{print $3}' | tail -1)
        tsec=$(grep -o '[0-9.]* s in total' "$out.log" | awk '{print $1}' | tail -1)
        rm -f "$out.err"
    fi
    local secs
    secs=$(awk -v a="$t" -v b="$(date +%s.%N)" 'BEGIN{printf "%.2f", b-a}')
    # seed stem generation_s total_s(as printed) wall_s
    printf '%s\t%s\t%s\t%s\t%s\n' "$seed" "$stem" "${gsec:--}" "${tsec:--}" "$secs" \
        >> "$OUT/gen/$cfg/times.tsv"
    log "  $cfg seed $seed $stem: ${gsec:--} s generation, $secs s wall"
}

# Seed by seed, so that an interrupted run leaves complete seeds behind: re-run with fewer SEEDS
# to report what is there.
for seed in $SEEDS; do
    for cfg in $RUN; do
        while read -r stem start song _frames _mot lead; do
            gen "$cfg" "$seed" "$stem" "$start" "$song" "$lead" "$OUT/gen/$cfg/seed$seed/$stem.npy"
        done < "$OUT/clips.txt"
        log "generated: $cfg seed $seed"
    done
done

# ---- evaluation (always redone: cheap)
METRICS=fid_k,fid_g,div_k,div_g,pfc,mpjpe,freeze,boundary_jerk,fid_cd,div_cd,bed,ipr,contact_range
eval_set() { # pred_dir window out.json
    "$BIN" -q eval --pred "$1" --leader "$OUT/leader" --gt "$OUT/gt_all" \
        --gt-leader "$OUT/gt_leader_all" --fps 30 --window "$2" --metrics "$METRICS" \
        --json "$3" > /dev/null
}
eval_physical() { # pred_dir out.json: the physical plausibility figures of the followers alone
    "$BIN" -q eval --pred "$1" --fps 30 --metrics physical --json "$2" > /dev/null
}
eval_set "$OUT/gt" "$REAL_WINDOW" "$OUT/eval/real/eval.json"
eval_physical "$OUT/gt" "$OUT/eval/real/physical.json"
eval_physical "$OUT/gt_train" "$OUT/eval/real/physical_train.json"
# Every real couple's BED, for the report's sense of scale.
"$BIN" -q eval --pred "$OUT/gt_all" --leader "$OUT/gt_leader_all" --fps 30 --metrics bed \
    --json "$OUT/eval/real_all_bed.json" > /dev/null
for cfg in $RUN; do
    for seed in $SEEDS; do
        d=$OUT/gen/$cfg/seed$seed
        e=$OUT/eval/$cfg/seed$seed
        rm -rf "$e"
        n=$(find "$d" -maxdepth 1 -name '*.npy' 2>/dev/null | wc -l)
        if [ "$n" != "$NCLIPS" ]; then
            log "skipping the evaluation of $cfg seed $seed: $n of $NCLIPS followers generated"
            continue
        fi
        mkdir -p "$e"
        eval_set "$d" "$(window_of "$cfg")" "$e/eval.json"
        eval_physical "$d" "$e/physical.json"
    done
    log "evaluated $cfg"
done

# ---- contact sheet: the first seed's full system and the real couple of the first held-out
# clip, at the same moments (not in a dry run unless CONTACT=1: there "generated" is real)
rm -f "$OUT/contact.json"
if [ "$CONTACT" = 1 ]; then
    read -r stem start song _ < "$OUT/clips.txt"
    read -r seed _ <<< "$SEEDS"
    g=$OUT/gen/full/seed$seed/$stem.npy
    if [ -f "$g" ]; then
        name=$(awk -F'\t' '$1 == "full" {print $9}' "$OUT/configs.tsv")
        caption="ReactDance \`$name\` (full system, seed $seed): the follower it made"
        [ "$DRY" = 1 ] && caption="DRY RUN: the shifted real follower standing in for a generated one"
        caption="$caption for the real leader of the held-out clip \`$stem\`, and the real couple"
        caption="$caption ($(basename "$song") from $(awk -v a="$start" 'BEGIN{printf "%.1f", a}') s;"
        caption="$caption leader blue, follower orange)"
        $PYTHON "$ROOT/tools/solo_eval.py" contact --bin "$BIN" --png "$CONTACT_PNG" \
            --info "$OUT/contact.json" --work "$OUT/contact" --caption "$caption" \
            "generated follower (full, seed $seed)=$OUT/leader/$stem.npy+$g" \
            "real couple $stem=$OUT/leader/$stem.npy+$OUT/gt/$stem.npy" \
            || log "contact sheet failed; the report has none"
    else
        log "no contact sheet: $g was not generated"
    fi
fi

# ---- report
WALL=$(( $(date +%s) - T0 ))
CMD="bash tools/duet_eval.sh"
[ "$DRY" = 1 ] && CMD="$CMD --dry-run"
for v in STEPS CONFIGS SEEDS MODEL_NO_PM MODEL_M64 MODEL; do
    case $v in
        SEEDS) default="0 1 2" ;;
        CONFIGS) default=$ALL_CONFIGS ;;
        STEPS) default="" ;;
        MODEL) default=$ROOT/models/reactdance-small ;;
        MODEL_M64) default=$ROOT/target/models/reactdance-small-m64 ;;
        MODEL_NO_PM) default=$ROOT/target/models/reactdance-small-no-pm ;;
    esac
    val=${!v}
    case $v in MODEL*) [ "$(realpath -m "$val")" = "$(realpath -m "$default")" ] && val=$default; val_show=$(rel "$val") ;; *) val_show=$val ;; esac
    [ "$val" != "$default" ] && CMD="$v=\"$val_show\" $CMD"
done
if [ -n "${BASELINE:-}" ]; then
    CMD="BASELINE=\"$(rel "$BASELINE")\" BASELINE_LABEL=\"${BASELINE_LABEL:-the earlier model}\" $CMD"
fi
DIRTY=false
[ -n "$(git status --porcelain --untracked-files=no 2>/dev/null)" ] && DIRTY=true
$HELP meta --out "$OUT/meta.json" \
    "command=$CMD" \
    "date=$(date -u '+%Y-%m-%d %H:%M UTC')" \
    "commit=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)" \
    "dirty=$DIRTY" \
    "binary=$(rel "$SRC_BIN")" \
    "nproc=$(nproc)" \
    "load=$LOAD_NOTE; load average $(cut -d' ' -f1-3 /proc/loadavg) at the end" \
    "out=$(rel "$OUT")" \
    "wall=$((WALL / 60)) min $((WALL % 60)) s" \
    "steps=$STEPS" \
    "real_window=$REAL_WINDOW" \
    "manifest=$(realpath "$DATASET/manifest.json")" \
    "seed_note=${SEED_NOTE:-}"
RFLAGS=()
[ "$DRY" = 1 ] && RFLAGS+=(--dry-run)
if [ -n "${BASELINE:-}" ]; then
    RFLAGS+=(--baseline "$(rel "$BASELINE")" --baseline-label "${BASELINE_LABEL:-the earlier model}")
fi
$HELP report --out "$OUT" --seeds "$SEEDS" --configs "$CONFIGS" "${RFLAGS[@]}" --report "$REPORT"
log "done in $((WALL / 60)) min $((WALL % 60)) s"
