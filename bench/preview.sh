#!/usr/bin/env bash
# Preview renderer benchmark: today's dancegen-render against a baseline revision, side by side.
#
#   bash bench/preview.sh [ROUNDS]          # default 3 rounds
#   PREVIEW_BASE_REV=<rev> bash bench/preview.sh
#
# Both renderers run crates/dancegen-render/examples/preview_bench.rs (the current copy, put
# into a git worktree of the baseline revision) on the same motion: CMU salsa takes 60_01..03
# (BVH, 120 fps) retargeted to SMPL 24 at 30 fps and cut to the README command's 45 s, written as
# the 640x480 30 fps MP4 with the demo song and the 640x480 15 fps GIF. Rounds alternate
# baseline / current. Prints min and median frames/s per renderer and output, the ratio
# current / baseline of the medians, and fails unless the rendered RGB frames hash alike and
# the GIFs are byte-identical. The MP4s' encoder settings and pixel conversion differ (x264
# preset and CRF: see X264_PRESET in crates/dancegen-render/src/write.rs; RGB to YUV 4:2:0 by
# ffmpeg before, by crates/dancegen-render/src/yuv.rs since), so their video is compared with
# the rendered frames themselves: one extra, untimed run of the current program saves the raw
# RGB frames (PREVIEW_BENCH_RAW_FRAMES), both MP4s are decoded back to RGB, and PSNR and SSIM
# against the saved frames are printed; the script fails if the current MP4 is worse on either.
#
# Environment: PREVIEW_BASE_REV (default 437cb7c), PREVIEW_DATA (default
# <repo>/../shared/data), PREVIEW_AUDIO (default assets/demo_metal_madness_45s.ogg),
# PREVIEW_CACHE (default $HOME/.cache; build directories and the worktree go there).
set -euo pipefail

ROUNDS="${1:-3}"
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
BASE_REV="${PREVIEW_BASE_REV:-437cb7c}"
DATA="${PREVIEW_DATA:-$ROOT/../shared/data}"
AUDIO="${PREVIEW_AUDIO:-$ROOT/assets/demo_metal_madness_45s.ogg}"
CACHE="${PREVIEW_CACHE:-$HOME/.cache}"
CUR_TARGET="$CACHE/dancegen-render-target"
BASE_TARGET="$CACHE/dancegen-preview-baseline-target"
WORKTREE="$BASE_TARGET/worktree"
OUT="$(mktemp -d "${TMPDIR:-/tmp}/preview-bench.XXXXXX")"
MOTIONS=("$DATA/cmu-salsa/60_01_scaled.bvh" "$DATA/cmu-salsa/60_02_scaled.bvh" "$DATA/cmu-salsa/60_03_scaled.bvh")

die() { echo "preview.sh: $*" >&2; exit 1; }
for f in "${MOTIONS[@]}" "$AUDIO"; do [[ -f "$f" ]] || die "missing $f"; done
command -v ffmpeg >/dev/null || die "ffmpeg is needed"

base_commit="$(git -C "$ROOT" rev-parse --verify "$BASE_REV^{commit}")" || die "no revision $BASE_REV"
cur_commit="$(git -C "$ROOT" rev-parse --short HEAD)"
mkdir -p "$BASE_TARGET"
if [[ -d "$WORKTREE" ]]; then
  git -C "$WORKTREE" checkout -q --detach "$base_commit"
else
  git -C "$ROOT" worktree add -q --detach "$WORKTREE" "$base_commit"
fi
mkdir -p "$WORKTREE/crates/dancegen-render/examples"
cp "$ROOT/crates/dancegen-render/examples/preview_bench.rs" "$WORKTREE/crates/dancegen-render/examples/"

echo "== building baseline $(git -C "$ROOT" rev-parse --short "$base_commit") and current $cur_commit (release, one build at a time)"
(cd "$WORKTREE" && CARGO_TARGET_DIR="$BASE_TARGET" cargo build -q --release -p dancegen-render --example preview_bench)
(cd "$ROOT" && CARGO_TARGET_DIR="$CUR_TARGET" cargo build -q --release -p dancegen-render --example preview_bench)
BIN_base="$BASE_TARGET/release/examples/preview_bench"
BIN_cur="$CUR_TARGET/release/examples/preview_bench"

echo "== $ROUNDS rounds, outputs in $OUT (load average: $(cut -d' ' -f1-3 /proc/loadavg))"
for r in $(seq 1 "$ROUNDS"); do
  for who in base cur; do
    bin="BIN_$who"
    dir="$OUT/$who-$r"
    mkdir -p "$dir"
    "${!bin}" "$dir" "$AUDIO" "${MOTIONS[@]}" | tee "$dir/log" | sed "s/^/round $r $who: /"
  done
done

# "mp4: 1350 frames in 18.391 s = 73.4 frames/s (rgb fnv 6e83441f3efb6acb)"
field() { awk -v k="$2:" '$1 == k { print $'"$3"' }' "$1"; }
stats() { sort -g | awk '{ v[NR] = $1 } END { m = (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2; printf "%s %s\n", v[1], m }'; }

fail=0
echo
echo "== identity"
ref="$OUT/base-1"
for r in $(seq 1 "$ROUNDS"); do
  for who in base cur; do
    dir="$OUT/$who-$r"
    for kind in mp4 gif; do
      [[ "$(field "$dir/log" $kind 9)" == "$(field "$ref/log" $kind 9)" ]] \
        || { echo "DIFFERENT: $who round $r $kind rendered RGB frames"; fail=1; }
    done
    cmp -s "$dir/preview.gif" "$ref/preview.gif" || { echo "DIFFERENT: $who round $r GIF bytes"; fail=1; }
  done
done
echo "GIF bytes and rendered RGB frame hashes: $([[ $fail == 0 ]] && echo identical || echo NOT identical)"

echo
echo "== MP4 video against the rendered frames (one untimed run keeps them raw)"
mkdir -p "$OUT/raw"
PREVIEW_BENCH_RAW_FRAMES="$OUT/frames.rgb" "$BIN_cur" "$OUT/raw" "$AUDIO" "${MOTIONS[@]}" >/dev/null
# The decoded video is turned back into RGB (as a player shows it) and compared there.
quality() {
  ffmpeg -hide_banner -i "$1" -f rawvideo -pix_fmt rgb24 -s 640x480 -framerate 30 -i "$OUT/frames.rgb" \
    -lavfi "[0:v]format=rgb24[v];[v][1:v]$2" -f null - 2>&1 | grep -o "$3[0-9.]*" | tail -1 | cut -d: -f2
}
for who in base cur; do
  psnr="$(quality "$OUT/$who-1/preview.mp4" psnr 'average:')"
  ssim="$(quality "$OUT/$who-1/preview.mp4" ssim 'All:')"
  eval "psnr_$who=$psnr ssim_$who=$ssim"
  echo "  $who: PSNR $psnr dB, SSIM $ssim"
done
rm -f "$OUT/frames.rgb"
awk -v pb="$psnr_base" -v pc="$psnr_cur" -v sb="$ssim_base" -v sc="$ssim_cur" \
  'BEGIN { exit !(pc >= pb && sc >= sb) }' || { echo "WORSE: the current MP4 is further from the rendered frames"; fail=1; }
ls -l "$OUT/base-1/preview.mp4" "$OUT/cur-1/preview.mp4" "$OUT/base-1/preview.gif" "$OUT/cur-1/preview.gif" | awk '{ print "  " $5 " bytes " $NF }'

echo
echo "== frames/s (baseline $(git -C "$ROOT" rev-parse --short "$base_commit"), current $cur_commit, $ROUNDS rounds)"
printf "%-4s %-9s %7s %8s %s\n" out renderer min median "per round"
for kind in mp4 gif; do
  for who in base cur; do
    vals="$(for r in $(seq 1 "$ROUNDS"); do field "$OUT/$who-$r/log" $kind 8; done)"
    read -r mn md <<<"$(stats <<<"$vals")"
    printf "%-4s %-9s %7.1f %8.1f %s\n" "$kind" "$who" "$mn" "$md" "$(tr '\n' ' ' <<<"$vals")"
    eval "med_${kind}_$who=$md"
  done
  b="med_${kind}_base"; c="med_${kind}_cur"
  awk -v b="${!b}" -v c="${!c}" -v k="$kind" 'BEGIN { printf "%-4s ratio current/baseline (medians): %.2fx\n", k, c / b }'
done
[[ $fail == 0 ]] || die "outputs differ (see DIFFERENT above; files kept in $OUT)"
