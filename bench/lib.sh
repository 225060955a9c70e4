# Shared by the bench scripts (sourced): the PyTorch side's Python and the path of a built
# `cargo bench` binary, so every comparison sets up its peer the same way.

# Python of the torch venv $1 (created from PyPI with torch, numpy and the extra packages given
# after it when missing or without torch). Installation output goes to stderr.
torch_python() {
  local venv=$1
  shift
  if [ ! -x "$venv/bin/python" ] || ! "$venv/bin/python" -c "import torch" 2>/dev/null; then
    python3 -m venv "$venv" >&2
    "$venv/bin/pip" install -q torch numpy "$@" >&2
  fi
  echo "$venv/bin/python"
}

# Builds bench target $2 of package $1 (bench profile) and prints its executable; $3 is a Python
# that reads cargo's JSON messages.
bench_binary() {
  local package=$1 bench=$2 py=$3 manifest
  manifest="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/Cargo.toml"
  cargo bench -q -p "$package" --bench "$bench" --manifest-path "$manifest" --no-run
  cargo bench -p "$package" --bench "$bench" --manifest-path "$manifest" --no-run \
    --message-format=json 2>/dev/null | "$py" -c '
import json, sys
for line in sys.stdin:
    m = json.loads(line)
    if m.get("reason") == "compiler-artifact" and m["target"]["name"] == sys.argv[1] and m.get("executable"):
        print(m["executable"])' "$bench"
}

# Runs the burn-flex bench binary $3 and the PyTorch port $5 (run by Python $4) alternately, $1
# rounds with $2 threads each, both given the case filter $6 (may be empty), appending their
# JSON lines to $7: interleaving spreads any drift in the machine's speed over both sides.
interleaved_rounds() {
  local rounds=$1 threads=$2 bin=$3 py=$4 port=$5 case=$6 out=$7 r
  for r in $(seq "$rounds"); do
    echo "round $r/$rounds: burn-flex" >&2
    # shellcheck disable=SC2086  # an empty case filter is no argument
    RAYON_NUM_THREADS=$threads "$bin" $case >> "$out"
    echo "round $r/$rounds: pytorch" >&2
    # shellcheck disable=SC2086
    OMP_NUM_THREADS=$threads MKL_NUM_THREADS=$threads "$py" "$port" $case >> "$out"
  done
}
