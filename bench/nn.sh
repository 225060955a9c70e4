#!/usr/bin/env bash
# dancegen-nn (burn-flex) vs PyTorch CPU on the same denoiser shapes, interleaved in one run.
#   bash bench/nn.sh [ROUNDS] [CASE]      (default 3 rounds, all cases)
# Builds `crates/dancegen-nn/benches/denoiser.rs` in the bench profile, installs torch (CPU
# wheels from PyPI, ~3 GB with its CUDA dependencies) into bench/.venv-torch if missing, then
# alternates burn / PyTorch per round and prints the median over rounds of each side's median,
# and the speed ratio PyTorch time / burn time (1.0 = parity, higher = burn faster).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
# shellcheck source=bench/lib.sh
source "$here/lib.sh"
root="$(cd "$here/.." && pwd)"
rounds="${1:-3}"
case="${2:-}"
venv="${DANCEGEN_TORCH_VENV:-$here/.venv-torch}"
py=$(torch_python "$venv" safetensors)
bin=$(bench_binary dancegen-nn denoiser "$py")
out=$(mktemp)
threads=$(nproc)
interleaved_rounds "$rounds" "$threads" "$bin" "$py" "$here/nn_denoiser.py" "$case" "$out"
"$py" - "$out" <<'PY'
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.startswith("{")]
cases = sorted({r["case"] for r in rows})
print(f"{'case':<16}{'pytorch ms':>12}{'burn ms':>12}{'speed vs pytorch':>18}")
for c in cases:
    med = lambda impl: statistics.median([r["median_ms"] for r in rows if r["case"] == c and r["impl"] == impl] or [float("nan")])
    p, b = med("pytorch"), med("burn-flex")
    print(f"{c:<16}{p:>12.1f}{b:>12.1f}{p / b:>17.2f}x")
PY
