# Shared by the evaluation scripts (sourced after `set -euo pipefail`): option parsing, the CPU
# load note and the binary snapshot, so every report states its run the same way.

# Sets DRY=1 for --dry-run; --help prints the calling script's header comment ($1 = the script).
parse_eval_args() {
    local script=$1
    shift
    DRY=0
    for a in "$@"; do
        case $a in
            --dry-run) DRY=1 ;;
            -h|--help) awk 'NR > 1 && !/^#/ {exit} NR > 1 {sub(/^# ?/, ""); print}' "$script"; exit 0 ;;
            *) echo "unknown argument $a (see --help)" >&2; exit 2 ;;
        esac
    done
}

# Other CPU users now (reports print it: timings depend on them). Counts training processes
# whatever the binary is called (a copy such as /tmp/dancegen-train too).
load_note() {
    echo "$(pgrep -c -f 'dancegen[^ ]* train ' || true) \`dancegen train\` processes running at the start, load average $(cut -d' ' -f1-3 /proc/loadavg)"
}

# Hard-links (or copies) binary $1 to $2/bin/dancegen, so a rebuild during the run cannot swap it
# midway; sets BIN.
snapshot_binary() {
    mkdir -p "$2/bin"
    BIN=$2/bin/dancegen
    ln -f "$1" "$BIN" 2>/dev/null || cp -f "$1" "$BIN"
}

# The real motion as joints, with "$BIN" (snapshot_binary): each held-out clip of $1/clips.txt
# (its 5th column is the clip's .npz) into $1/gt/, each training clip of $2/motion/*.npz into
# $1/gt_train/, and both into $1/gt_all/ (hard links).
convert_real_clips() {
    local out=$1 dataset=$2 stem npz
    mkdir -p "$out/gt" "$out/gt_train" "$out/gt_all"
    while read -r stem _ _ _ npz _; do
        "$BIN" -q convert "$npz" -o "$out/gt/$stem.npy"
        ln -f "$out/gt/$stem.npy" "$out/gt_all/$stem.npy"
    done < "$out/clips.txt"
    for npz in "$dataset"/motion/*.npz; do
        stem=$(basename "$npz" .npz)
        "$BIN" -q convert "$npz" -o "$out/gt_train/$stem.npy"
        ln -f "$out/gt_train/$stem.npy" "$out/gt_all/$stem.npy"
    done
}

# The contact sheet of one generated clip beside the real held-out clip it stands for
# ($OUT/gt/STEM.npy), drawn by tools/solo_eval.py's `contact` (tools/contact_sheet.sh) into
# $CONTACT_PNG with its description in $OUT/contact.json. Uses BIN, PYTHON, ROOT, OUT, SONG,
# DRY and the caller's log(). Arguments: the generated .npy, its row label, what it is (the
# caption's start), STEM, and the clip's start and end in the song (s). Without the generated
# file, or when drawing fails, there is no $OUT/contact.json and the report shows no sheet.
contact_sheet_clip() {
    local gen=$1 label=$2 what=$3 stem=$4 start=$5 end=$6 span caption
    rm -f "$OUT/contact.json"
    if [ ! -f "$gen" ]; then
        log "no contact sheet: $gen was not generated"
        return 0
    fi
    span=$(awk -v a="$start" -v b="$end" 'BEGIN{printf "%.1f–%.1f s", a, b}')
    caption=$what
    [ "$DRY" = 1 ] && caption="DRY RUN: the shifted real motion standing in for generated motion"
    caption="$caption and the real held-out clip \`$stem\`, on $(basename "$SONG") $span"
    $PYTHON "$ROOT/tools/solo_eval.py" contact --bin "$BIN" --png "$CONTACT_PNG" \
        --info "$OUT/contact.json" --work "$OUT/contact" --caption "$caption" \
        "$label=$gen" "real $stem=$OUT/gt/$stem.npy" \
        || log "contact sheet failed; the report has none"
}
