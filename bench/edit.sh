#!/usr/bin/env bash
# Editing speed (issue 44): regenerating a 10 s range of a 60 s dance against generating
# those 10 s from scratch, end to end from the audio file, interleaved in the same run, for
# each system given (default: solo; group dances with 3 dancers). The issue's bound: the edit
# takes at most the plain 10 s generation plus 1 s.
#   bash bench/edit.sh [ROUNDS] [SYSTEM...]   (default 3 rounds; solo, group, holistic)
# Environment: EDIT_SONG (default ../shared/data/music/sectoid/feelings.ogg),
#   DANCEGEN (default: the release build, built here).
# Prints one line per run and a summary: medians, their difference and whether it is within
# the bound.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/.." && pwd)"
rounds="${1:-3}"
song="${EDIT_SONG:-$root/../shared/data/music/sectoid/feelings.ogg}"
if [ -z "${DANCEGEN:-}" ]; then
  cargo build -q --release -p dancegen-cli --manifest-path "$root/Cargo.toml"
  DANCEGEN="${CARGO_TARGET_DIR:-$root/target}/release/dancegen"
fi
export DANCEGEN_MODEL_DIR="${DANCEGEN_MODEL_DIR:-$root/models}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "load before: $(uptime)" >&2
seconds() {
  local t0 t1
  t0=$(date +%s.%N)
  "$@" > /dev/null
  t1=$(date +%s.%N)
  echo "$t1 - $t0" | bc -l
}
median() { printf '%s\n' "$@" | sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
shift $(( $# > 0 ? 1 : 0 ))
systems=("$@")
[ ${#systems[@]} -gt 0 ] || systems=(solo)
for system in "${systems[@]}"; do
  flags=(--system "$system")
  case "$system" in
    solo | holistic) ;;
    group) flags+=(--dancers 3) ;;
    *) echo "bench/edit.sh: $system: give solo, group or holistic" >&2; exit 2 ;;
  esac
  "$DANCEGEN" -q generate "$song" "${flags[@]}" --start 40 --end 100 --seed 0 -o "$tmp/base.npz"
  plain=() edit=()
  for r in $(seq 1 "$rounds"); do
    p=$(seconds "$DANCEGEN" -q generate "$song" "${flags[@]}" --start 60 --end 70 --seed "$r" \
      -o "$tmp/p.npy")
    e=$(seconds "$DANCEGEN" -q generate --edit "$tmp/base.npz" --regenerate 20-30 --seed "$r" \
      -o "$tmp/e.npy")
    printf '%s round %d: generate 10 s %.2f s, edit 10 s of 60 s %.2f s\n' "$system" "$r" "$p" "$e"
    plain+=("$p") edit+=("$e")
  done
  mp=$(median "${plain[@]}") me=$(median "${edit[@]}")
  d=$(echo "$me - $mp" | bc -l)
  verdict=$(echo "$d <= 1.0" | bc -l)
  printf '%s median: generate 10 s %.2f s, edit %.2f s, difference %+.2f s (bound +1 s): %s\n' \
    "$system" "$mp" "$me" "$d" "$([ "$verdict" = 1 ] && echo within || echo OVER)"
  rm -f "$tmp"/base*.npz
done
echo "load after: $(uptime)" >&2
