#!/usr/bin/env bash
# Music features: dancegen vs librosa 0.11 on the same 60 s file, in the same run.
#   bash bench/music_features.sh [AUDIO] [--fps 30|60]
# Installs librosa 0.11.0 + soundfile into bench/.venv from PyPI if missing, builds the release
# binary, then runs bench/music_features.py (see its docstring for what is timed).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/.." && pwd)"
shared="$root/../shared"
audio="${1:-$shared/fixtures/music/clips/bench_60s.ogg}"
shift || true
venv="$here/.venv"
if [ ! -x "$venv/bin/python" ] || ! "$venv/bin/python" -c "import librosa, soundfile" 2>/dev/null; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install -q "librosa==0.11.0" soundfile threadpoolctl
fi
cargo build --release -q -p dancegen-cli --manifest-path "$root/Cargo.toml"
target="${CARGO_TARGET_DIR:-$root/target}"
long="$shared/data/music/sectoid/escape_from_chaosland.ogg"
exec "$venv/bin/python" "$here/music_features.py" --binary "$target/release/dancegen" \
  --audio "$audio" --long-audio "$long" "$@"
