#!/usr/bin/env bash
# Evaluation metrics: `dancegen eval` vs a Python/numpy port of the reference metric code, on the
# same files, in the same run.
#   bash bench/metrics.sh [--reps N] [--protocols none,finedance-lodge] [--no-group]
# Installs numpy, scipy and dtaidistance 2.5.1 into bench/.venv from PyPI if missing, builds the
# release binary, builds the test set under bench/.metrics-set/ from ../shared/data (real data
# only; see bench/metrics_make_set.py), then runs bench/metrics_reference.py, which times each
# metric group in Python and through `dancegen eval` (median of --reps process runs), cross-checks
# the values and prints the table. numpy/BLAS are pinned to 2 threads (the machine has 2 cores).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/.." && pwd)"
shared="$root/../shared"
venv="$here/.venv"
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
fi
if ! "$venv/bin/python" -c "import numpy, scipy, dtaidistance; assert dtaidistance.__version__ == '2.5.1'" 2>/dev/null; then
  "$venv/bin/pip" install -q numpy scipy "dtaidistance==2.5.1"
fi
cargo build --release -q -p dancegen-cli --manifest-path "$root/Cargo.toml"
target="${CARGO_TARGET_DIR:-$root/target}"
bin="$target/release/dancegen"
set_dir="$here/.metrics-set"
export OMP_NUM_THREADS=2 OPENBLAS_NUM_THREADS=2 MKL_NUM_THREADS=2
"$venv/bin/python" "$here/metrics_make_set.py" --binary "$bin" --data "$shared/data" --out "$set_dir"
exec "$venv/bin/python" "$here/metrics_reference.py" --set "$set_dir" --binary "$bin" \
  --out "$set_dir/results.json" "$@"
