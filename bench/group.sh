#!/usr/bin/env bash
# TCDiff++ group generation speed: the long group sampler (5 dancers, 1800 frames = 60 s, the
# model's DDIM steps and guidance from its model.toml, LGDS and the parallel sampler) on burn-flex vs the same
# network, samplers and step count in PyTorch CPU (interleaved in one run), then `dancegen
# generate SONG --system group --dancers 5 --end 60` end to end against the issue's 20 s target.
#   bash bench/group.sh [ROUNDS] [CASE]     (default 3 rounds, all cases; CASE filters by name)
# Environment:
#   DANCEGEN_TORCH_VENV   torch venv (default bench/.venv-torch, created from PyPI if missing)
#   DANCEGEN_BENCH_REPS   timed runs per round and case (default 3)
#   GROUP_E2E_REPS        `dancegen generate --system group` runs (default 3)
#   GROUP_SKIP_E2E=1      sampler comparison only
#   GROUP_SKIP_DENOISER=1 end-to-end only
#   GROUP_MODEL           group model directory (default models/tcdiffpp-small)
#   GROUP_SONG            song (default ../shared/data/music/sectoid/escape_from_chaosland.ogg)
#   GROUP_RESULTS         file for the JSON lines (default a temporary file)
# The sampler comparison runs on random weights (no model needed). The end-to-end part needs the
# group model; it is skipped with a message when it is missing. Ratio = PyTorch time / burn time
# (> 1 = Rust faster).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
# shellcheck source=bench/lib.sh
source "$here/lib.sh"
root="$(cd "$here/.." && pwd)"
rounds="${1:-3}"
case="${2:-}"
venv="${DANCEGEN_TORCH_VENV:-$here/.venv-torch}"
threads=$(nproc)
song="${GROUP_SONG:-$(cd "$root/.." && pwd)/shared/data/music/sectoid/escape_from_chaosland.ogg}"
model="${GROUP_MODEL:-$root/models/tcdiffpp-small}"
exe="$root/target/release/dancegen"
py=$(torch_python "$venv")
out="${GROUP_RESULTS:-$(mktemp)}"
: > "$out"
echo "results: $out" >&2
echo "load before: $(uptime)" >&2
# Both sides sample with the shipped model's steps and guidance (its [model.sampling]), the
# same the end-to-end command uses.
if [ -f "$model/model.toml" ]; then
  read -r GROUP_BENCH_STEPS GROUP_BENCH_GUIDANCE < <("$py" -c '
import sys, tomllib
s = tomllib.load(open(sys.argv[1], "rb")).get("model", {}).get("sampling", {})
print(s.get("steps", 6), s.get("guidance", 2.0))' "$model/model.toml")
  export GROUP_BENCH_STEPS GROUP_BENCH_GUIDANCE
  echo "sampling: $GROUP_BENCH_STEPS steps, guidance $GROUP_BENCH_GUIDANCE ($model/model.toml)" >&2
fi

if [ "${GROUP_SKIP_DENOISER:-0}" != 1 ]; then
  bin=$(bench_binary dancegen-tcdiffpp group_sampling "$py")
  interleaved_rounds "$rounds" "$threads" "$bin" "$py" "$here/group_denoiser.py" "$case" "$out"
fi

if [ "${GROUP_SKIP_E2E:-0}" != 1 ] && [[ "e2e_5x60s_group" == *"$case"* ]]; then
  if [ ! -f "$model/model.toml" ]; then
    echo "no group model at $model: end-to-end case skipped" >&2
  else
    # Always through cargo (a no-op when up to date), so a stale binary is never timed.
    cargo build -q --release --bin dancegen --manifest-path "$root/Cargo.toml"
    tmp=$(mktemp -d)
    trap 'rm -rf "$tmp"' EXIT
    # Wall clock of the whole command: process start, loading the model, analysing the song,
    # sampling 5 dancers x 60 s, post-processing, writing the .npy. The frame count of the
    # result is read back to check that --end 60 gave 1800 frames.
    RAYON_NUM_THREADS=$threads "$py" - "$exe" "$tmp" "$song" "$model" "${GROUP_E2E_REPS:-3}" \
      >> "$out" <<'PY'
import json, statistics, subprocess, sys, time
import numpy
exe, tmp, song, model, reps = sys.argv[1:6]
reps = int(reps)
cmd = [exe, "generate", song, "--system", "group", "--dancers", "5", "--end", "60",
       "--model", model, "-o", f"{tmp}/x.npy", "--progress", "none", "-q"]
wall = []
for _ in range(reps):
    t = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True)
    wall.append(time.perf_counter() - t)
    if p.returncode != 0:
        sys.exit(f"dancegen generate --system group failed:\n{p.stderr}")
shape = numpy.load(f"{tmp}/x.npy", mmap_mode="r").shape
print(json.dumps({"impl": "dancegen-e2e", "case": "e2e_5x60s_group",
                  "median_ms": round(statistics.median(wall) * 1e3, 1),
                  "min_ms": round(min(wall) * 1e3, 1), "reps": reps, "shape": list(shape),
                  "command": f"dancegen generate SONG --system group --dancers 5 --end 60 "
                             f"--model {model} -o x.npy --progress none -q"}), flush=True)
PY
  fi
fi

echo "load after: $(uptime)" >&2
"$py" - "$out" <<'PY'
import json, os, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.startswith("{")]
runs = lambda c, impl: [r["median_ms"] for r in rows if r["case"] == c and r["impl"] == impl]
med = lambda v: statistics.median(v) if v else float("nan")
den = sorted({r["case"] for r in rows if r["impl"] != "dancegen-e2e"})
if den:
    steps = sorted({r.get("steps") for r in rows if r["impl"] != "dancegen-e2e"})
    w = os.environ.get("GROUP_BENCH_GUIDANCE", "2")
    print(f"{f'group sampler ({steps[0]} steps, w = {w})':<34}{'pytorch ms':>12}{'burn ms':>12}"
          f"{'pytorch/burn':>14}  per round (pytorch / burn)")
    for c in den:
        pr, br = runs(c, "pytorch"), runs(c, "burn-flex")
        p, b = med(pr), med(br)
        ratio = f"{p / b:.2f}x" if pr and br else "(one side only)"
        per = ", ".join(f"{x:.0f} / {y:.0f}" for x, y in zip(pr, br)) if pr and br else \
            ", ".join(f"{y:.0f}" for y in (br or pr))
        print(f"{c:<34}{p:>12.0f}{b:>12.0f}{ratio:>14}  {per}")
e2e = [r for r in rows if r["impl"] == "dancegen-e2e"]
if e2e:
    print(f"\n{'dancegen generate --system group':<34}{'wall s':>10}{'min s':>10}  frames  vs 20 s")
    for r in e2e:
        s = r["median_ms"] / 1e3
        target = f"met ({20.0 / s:.2f}x under)" if s <= 20.0 else f"missed ({s / 20.0:.2f}x over)"
        print(f"{r['case']:<34}{s:>10.2f}{r['min_ms'] / 1e3:>10.2f}  {r['shape'][-3]:>6}  {target}")
        print(f"  {r['command']} (median of {r['reps']})")
        pl = runs("lgds_5x1800f", "pytorch")
        if pl:
            print(f"  PyTorch LGDS sampler alone (random weights) / this whole command: "
                  f"{med(pl) / r['median_ms']:.2f}x")
PY
