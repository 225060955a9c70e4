#!/usr/bin/env bash
# Byte-for-byte comparison of what two `dancegen` binaries write, for a refactor that must not
# change behaviour (issue 42): every system on the demo song, in every output format, plus a
# character retarget, the holistic face as Live Link CSV, a rendered frame, BVH and AIST++
# conversions, and a pseudo-paired and a duet training set.
#
#   bash tools/compare_outputs.sh BEFORE_BIN AFTER_BIN [WORK_DIR]
#
# KEEP_BEFORE=1 keeps the before side of an earlier run in WORK_DIR (the old binary need not
# be rebuilt). Both binaries use the checkout's models (DANCEGEN_MODEL_DIR=models unless set). Prints one
# line per output ("same" or "DIFFERENT") and exits 1 if any output differs or is missing.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BEFORE=${1:?usage: compare_outputs.sh BEFORE_BIN AFTER_BIN [WORK_DIR]}
AFTER=${2:?usage: compare_outputs.sh BEFORE_BIN AFTER_BIN [WORK_DIR]}
WORK=${3:-$(mktemp -d)}
export DANCEGEN_MODEL_DIR=${DANCEGEN_MODEL_DIR:-$ROOT/models}
SONG=$ROOT/assets/demo_metal_madness_45s.ogg
SALSA=$ROOT/../shared/data/cmu-salsa
AISTPP=$ROOT/../shared/data/aistpp/motions
for bin in "$BEFORE" "$AFTER"; do
    [ -x "$bin" ] || { echo "$bin: not an executable" >&2; exit 2; }
done

# run NAME ARGS...: runs both binaries with ARGS, where @OUT@ stands for the output file NAME
# in each side's folder. A group written as .bvh or .npz is one file per dancer (NAME_0.bvh,
# ...), so the folders are compared file by file at the end, not by NAME.
fail=0
run() {
    local name=$1
    shift
    local side bin
    for side in before after; do
        bin=$BEFORE
        [ "$side" = after ] && bin=$AFTER
        # KEEP_BEFORE=1 reuses the before side of an earlier run in the same WORK_DIR.
        [ "$side" = before ] && [ -n "${KEEP_BEFORE:-}" ] && continue
        mkdir -p "$WORK/$side"
        "$bin" -q "${@//@OUT@/$WORK/$side/$name}" || { echo "$name: $side failed" >&2; fail=1; }
    done
}

for ext in npy bvh glb fbx npz; do
    run "solo.$ext" generate "$SONG" --seed 0 -o @OUT@
    run "holistic.$ext" generate "$SONG" --system holistic --seed 0 -o @OUT@
    run "duet.$ext" generate "$SONG" --leader "$SALSA/60_13_scaled.bvh" --leader-fps 60 --seed 0 -o @OUT@
    run "group.$ext" generate "$SONG" --system group --dancers 3 --seed 0 -o @OUT@
done
run "holistic_face.csv" generate "$SONG" --system holistic --seed 0 -o @OUT@
run "solo_frame.png" render "$SALSA/61_14_scaled.bvh" --source-fps 60 --frame 100 -o @OUT@
run "solo_mixamo.fbx" generate "$SONG" --seed 0 --rig mixamo -o @OUT@
# A character: the solo's own rigged .glb, given back as the character to dance.
run "solo_on_character.glb" generate "$SONG" --seed 1 --character "$WORK/before/solo.glb" -o @OUT@
run "salsa.npy" convert "$SALSA/61_14_scaled.bvh" --source-fps 60 --fps 30 -o @OUT@
run "salsa.glb" convert "$SALSA/61_14_scaled.bvh" --source-fps 60 --fps 30 -o @OUT@
# Training sets: a pseudo-paired and a duet data set from two salsa partners (folders).
run "dataset_pseudo" dataset build --motion "$SALSA/60_01_scaled.bvh" "$SALSA/61_01_scaled.bvh" \
    --source-fps "$SALSA=60" --music "$ROOT/../shared/data/music/sectoid/metal_madness.ogg" -o @OUT@
run "dataset_duet" dataset build --pairing duet --motion "$SALSA/60_01_scaled.bvh" \
    "$SALSA/61_01_scaled.bvh" --source-fps "$SALSA=60" \
    --music "$ROOT/../shared/data/music/sectoid/metal_madness.ogg" -o @OUT@
first_pkl=$(find "$AISTPP" -name '*.pkl' | sort | head -n 1)
if [ -n "$first_pkl" ]; then
    run "aistpp.bvh" convert "$first_pkl" -o @OUT@
    run "aistpp.fbx" convert "$first_pkl" -o @OUT@
fi
if [ "$(cd "$WORK/before" && ls)" != "$(cd "$WORK/after" && ls)" ]; then
    echo "the two sides wrote different sets of files" >&2
    diff <(cd "$WORK/before" && ls) <(cd "$WORK/after" && ls) >&2 || true
    fail=1
fi
for f in "$WORK"/before/*; do
    name=$(basename "$f")
    if [ -d "$f" ]; then
        if diff -rq "$f" "$WORK/after/$name" >/dev/null; then
            echo "same       $name/ ($(find "$f" -type f | wc -l) files)"
        else
            echo "DIFFERENT  $name/"
            diff -rq "$f" "$WORK/after/$name" | head -n 5
            fail=1
        fi
    elif cmp -s "$f" "$WORK/after/$name"; then
        echo "same       $name"
    else
        echo "DIFFERENT  $name"
        fail=1
    fi
done
echo "outputs in $WORK"
exit $fail
