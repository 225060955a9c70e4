#!/usr/bin/env bash
# dancegen-nn (burn-flex) vs PyTorch CPU on the same denoiser shapes, interleaved in one run.
#   bash bench/nn.sh [ROUNDS] [CASE]      (default 3 rounds, all cases)
# Builds `crates/dancegen-nn/benches/denoiser.rs` in the bench profile, installs torch (CPU
# wheels from PyPI, ~3 GB with its CUDA dependencies) into bench/.venv-torch if missing, then
# alternates burn / PyTorch per round and prints the median over rounds of each side's median,
# and the speed ratio PyTorch time / burn time (1.0 = parity, higher = burn faster).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/.." && pwd)"
rounds="${1:-3}"
case="${2:-}"
venv="${DANCEGEN_TORCH_VENV:-$here/.venv-torch}"
if [ ! -x "$venv/bin/python" ] || ! "$venv/bin/python" -c "import torch" 2>/dev/null; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install -q torch numpy safetensors
fi
cargo bench -q -p dancegen-nn --bench denoiser --manifest-path "$root/Cargo.toml" --no-run
bin=$(cargo bench -p dancegen-nn --bench denoiser --manifest-path "$root/Cargo.toml" --no-run \
  --message-format=json 2>/dev/null | "$venv/bin/python" -c '
import json, sys
for line in sys.stdin:
    m = json.loads(line)
    if m.get("reason") == "compiler-artifact" and m["target"]["name"] == "denoiser" and m.get("executable"):
        print(m["executable"])')
out=$(mktemp)
threads=$(nproc)
for r in $(seq "$rounds"); do
  echo "round $r/$rounds" >&2
  RAYON_NUM_THREADS=$threads "$bin" $case >> "$out"
  OMP_NUM_THREADS=$threads "$venv/bin/python" "$here/nn_denoiser.py" $case >> "$out"
done
"$venv/bin/python" - "$out" <<'PY'
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.startswith("{")]
cases = sorted({r["case"] for r in rows})
print(f"{'case':<16}{'pytorch ms':>12}{'burn ms':>12}{'speed vs pytorch':>18}")
for c in cases:
    med = lambda impl: statistics.median([r["median_ms"] for r in rows if r["case"] == c and r["impl"] == impl] or [float("nan")])
    p, b = med("pytorch"), med("burn-flex")
    print(f"{c:<16}{p:>12.1f}{b:>12.1f}{p / b:>17.2f}x")
PY
