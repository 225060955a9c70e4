#!/usr/bin/env bash
# SoulNet holistic generation speed (issue 19): 60 s (1800 frames) of holistic dance through
# `dancegen_soulnet::pipeline::generate` (per window: MMR music encoder, masked transformer with
# the model's decoding steps and classifier-free guidance, residual transformer; then the conv
# decoder over the whole song) on burn-flex vs the same networks, windows and steps in PyTorch CPU
# (interleaved in one run), then `dancegen -q generate SONG --system holistic --end 60` end to
# end against the issue's 5 s target.
#   bash bench/holistic.sh [ROUNDS] [CASE]     (default 3 rounds, all cases; CASE filters by name)
# Environment:
#   DANCEGEN_TORCH_VENV     torch venv (default bench/.venv-torch, created from PyPI if missing)
#   DANCEGEN_BENCH_REPS     timed runs per round and case (default 3)
#   HOLISTIC_E2E_REPS       `dancegen generate --system holistic` runs (default 3)
#   HOLISTIC_SKIP_E2E=1     sampler comparison only
#   HOLISTIC_SKIP_SAMPLER=1 end-to-end only
#   HOLISTIC_MODEL          holistic model directory (default models/soulnet-small); both sampler
#                           sides take their sizes and sampling settings from its model.toml, or
#                           from configs/soulnet_small_*.toml when it has none
#   HOLISTIC_SONG           song (default ../shared/data/music/sectoid/escape_from_chaosland.ogg)
#   HOLISTIC_RESULTS        file for the JSON lines (default a temporary file)
# The sampler comparison runs on random weights (no model needed). The end-to-end part needs the
# model and target/release/dancegen; it is skipped with a message when either is missing. Ratio =
# PyTorch time / burn time (> 1 = Rust faster). The script fails when the two sides did not run
# the same number of windows and forwards.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
# shellcheck source=bench/lib.sh
source "$here/lib.sh"
root="$(cd "$here/.." && pwd)"
rounds="${1:-3}"
case="${2:-}"
venv="${DANCEGEN_TORCH_VENV:-$here/.venv-torch}"
threads=$(nproc)
song="${HOLISTIC_SONG:-$(cd "$root/.." && pwd)/shared/data/music/sectoid/escape_from_chaosland.ogg}"
model="${HOLISTIC_MODEL:-$root/models/soulnet-small}"
export HOLISTIC_MODEL="$model"
exe="$root/target/release/dancegen"
py=$(torch_python "$venv")
out="${HOLISTIC_RESULTS:-$(mktemp)}"
: > "$out"
echo "results: $out" >&2
echo "load before: $(uptime)" >&2

if [ "${HOLISTIC_SKIP_SAMPLER:-0}" != 1 ]; then
  bin=$(bench_binary dancegen-soulnet holistic_sampling "$py")
  interleaved_rounds "$rounds" "$threads" "$bin" "$py" "$here/holistic_sampler.py" "$case" "$out"
fi

if [ "${HOLISTIC_SKIP_E2E:-0}" != 1 ] && [[ "e2e_60s_holistic" == *"$case"* ]]; then
  if [ ! -f "$model/model.toml" ]; then
    echo "no holistic model at $model: end-to-end case skipped" >&2
  elif [ ! -x "$exe" ]; then
    echo "no $exe (cargo build --release --bin dancegen): end-to-end case skipped" >&2
  else
    # Through cargo (a no-op when up to date), so a stale binary is never timed.
    cargo build -q --release --bin dancegen --manifest-path "$root/Cargo.toml"
    tmp=$(mktemp -d)
    trap 'rm -rf "$tmp"' EXIT
    # Wall clock of the whole command: process start, loading the model, analysing the song,
    # the token windows, decoding, post-processing, writing the .npy ((T, 52, 3) SMPL-H joints;
    # its frame count is read back).
    RAYON_NUM_THREADS=$threads "$py" - "$exe" "$tmp" "$song" "$model" "${HOLISTIC_E2E_REPS:-3}" \
      >> "$out" <<'PY'
import json, statistics, subprocess, sys, time
import numpy
exe, tmp, song, model, reps = sys.argv[1:6]
reps = int(reps)
cmd = [exe, "-q", "generate", song, "--system", "holistic", "--end", "60", "--model", model,
       "-o", f"{tmp}/x.npy", "--seed", "0"]
wall = []
for _ in range(reps):
    t = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True)
    wall.append(time.perf_counter() - t)
    if p.returncode != 0:
        sys.exit(f"dancegen generate --system holistic failed:\n{p.stderr}")
shape = numpy.load(f"{tmp}/x.npy", mmap_mode="r").shape
print(json.dumps({"impl": "dancegen-e2e", "case": "e2e_60s_holistic",
                  "median_ms": round(statistics.median(wall) * 1e3, 1),
                  "min_ms": round(min(wall) * 1e3, 1), "reps": reps, "shape": list(shape),
                  "command": f"dancegen -q generate SONG --system holistic --end 60 "
                             f"--model {model} -o x.npy --seed 0"}), flush=True)
PY
  fi
fi

echo "load after: $(uptime)" >&2
"$py" - "$out" <<'PY'
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.startswith("{")]
runs = lambda c, impl: [r["median_ms"] for r in rows if r["case"] == c and r["impl"] == impl]
med = lambda v: statistics.median(v) if v else float("nan")
den = sorted({r["case"] for r in rows if r["impl"] != "dancegen-e2e"})
work_keys = ("steps", "windows", "masked_forwards", "masked_batch", "residual_forwards",
             "residual_batch", "mmr_forwards")
mismatch = False
if den:
    print(f"{'holistic generation (random weights)':<38}{'pytorch ms':>12}{'burn ms':>12}"
          f"{'pytorch/burn':>14}  per round (pytorch / burn)")
for c in den:
    pr, br = runs(c, "pytorch"), runs(c, "burn-flex")
    p, b = med(pr), med(br)
    ratio = f"{p / b:.2f}x" if pr and br else "(one side only)"
    per = ", ".join(f"{x:.0f} / {y:.0f}" for x, y in zip(pr, br)) if pr and br else \
        ", ".join(f"{y:.0f}" for y in (br or pr))
    print(f"{c:<38}{p:>12.0f}{b:>12.0f}{ratio:>14}  {per}")
    work = {r["impl"]: tuple(r.get(k) for k in work_keys) for r in rows
            if r["case"] == c and r["impl"] != "dancegen-e2e"}
    w = next(iter(work.values()))
    print("  work per run: " + ", ".join(f"{k} {v}" for k, v in zip(work_keys, w)))
    if len(set(work.values())) > 1:
        mismatch = True
        print(f"  WORK DIFFERS between the sides: {work}")
    elif len(work) == 2:
        print("  both sides ran the same windows and forwards")
e2e = [r for r in rows if r["impl"] == "dancegen-e2e"]
if e2e:
    print(f"\n{'dancegen generate --system holistic':<38}{'wall s':>10}{'min s':>10}  frames  vs 5 s")
    for r in e2e:
        s = r["median_ms"] / 1e3
        target = f"met ({5.0 / s:.2f}x under)" if s <= 5.0 else f"missed ({s / 5.0:.2f}x over)"
        print(f"{r['case']:<38}{s:>10.2f}{r['min_ms'] / 1e3:>10.2f}  {r['shape'][0]:>6}  {target}")
        print(f"  {r['command']} (median of {r['reps']})")
        pl = runs("holistic_1800f", "pytorch")
        if pl:
            print(f"  PyTorch sampler alone (random weights) / this whole command: "
                  f"{med(pl) / r['median_ms']:.2f}x")
sys.exit(1 if mismatch else 0)
PY
