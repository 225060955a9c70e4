#!/usr/bin/env bash
# ReactDance duet generation speed: the latent BLC sampler (LDCFG, the model's DDIM steps, 2000 frames)
# plus the HFSQ decoder on burn-flex vs the same architecture and step count in PyTorch CPU
# (interleaved in one run), then `dancegen generate SONG --leader LEADER` end to end for a
# 2000-frame (66.7 s) leader against the 2 s budget.
#   bash bench/duet.sh [ROUNDS] [CASE]     (default 3 rounds, all cases; CASE filters by name)
# Environment:
#   DANCEGEN_TORCH_VENV   torch venv (default bench/.venv-torch, created from PyPI if missing)
#   DANCEGEN_BENCH_REPS   timed runs per round and case (default 3)
#   DUET_E2E_REPS         `dancegen generate --leader` runs (default 3)
#   DUET_SKIP_E2E=1       sampler comparison only
#   DUET_SKIP_DENOISER=1  end-to-end only
#   DUET_MODEL            duet model directory (default models/reactdance-small)
#   DUET_SONG             song (default ../shared/data/music/sectoid/escape_from_chaosland.ogg)
#   DUET_RESULTS          file for the JSON lines (default a temporary file)
# The end-to-end part needs the duet model (and the bundled solo model models/lodgepp-small,
# which makes the leader); it is skipped with a message when either is missing. Ratio = PyTorch
# time / burn time (> 1 = Rust faster).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
# shellcheck source=bench/lib.sh
source "$here/lib.sh"
root="$(cd "$here/.." && pwd)"
rounds="${1:-3}"
case="${2:-}"
venv="${DANCEGEN_TORCH_VENV:-$here/.venv-torch}"
threads=$(nproc)
song="${DUET_SONG:-$(cd "$root/.." && pwd)/shared/data/music/sectoid/escape_from_chaosland.ogg}"
model="${DUET_MODEL:-$root/models/reactdance-small}"
solo_model="$root/models/lodgepp-small"
exe="$root/target/release/dancegen"
frames=2000
py=$(torch_python "$venv")
out="${DUET_RESULTS:-$(mktemp)}"
: > "$out"
echo "results: $out" >&2
echo "load before: $(uptime)" >&2

if [ "${DUET_SKIP_DENOISER:-0}" != 1 ]; then
  bin=$(bench_binary dancegen-reactdance blc_sampling "$py")
  interleaved_rounds "$rounds" "$threads" "$bin" "$py" "$here/duet_denoiser.py" "$case" "$out"
fi

if [ "${DUET_SKIP_E2E:-0}" != 1 ] && [[ "e2e_${frames}f_duet" == *"$case"* ]]; then
  if [ ! -f "$model/model.toml" ]; then
    echo "no duet model at $model: end-to-end case skipped" >&2
  elif [ ! -f "$solo_model/model.toml" ]; then
    echo "no solo model at $solo_model (it makes the leader): end-to-end case skipped" >&2
  else
    if [ ! -x "$exe" ]; then
      cargo build -q --release --bin dancegen --manifest-path "$root/Cargo.toml"
    fi
    tmp=$(mktemp -d)
    trap 'rm -rf "$tmp"' EXIT
    # The leader: a 2000-frame solo dance to the first 66.67 s of the song (the solo model; not
    # timed). `generate` gives round(end · 30) frames (librosa framing: 1 + floor(samples / hop)
    # feature rows, a dance of (rows − 1) / 30 s at most); the count is checked through
    # `dancegen convert` and --end corrected if it is off.
    end=66.67
    n=0
    for attempt in 1 2 3; do
      "$exe" generate "$song" --end "$end" -o "$tmp/leader.npz" --seed 0 -q
      "$exe" convert "$tmp/leader.npz" -o "$tmp/leader_joints.npy" -q
      n=$("$py" -c 'import sys, numpy; print(numpy.load(sys.argv[1], mmap_mode="r").shape[0])' \
        "$tmp/leader_joints.npy")
      echo "leader: --end $end gives $n frames" >&2
      [ "$n" = "$frames" ] && break
      end=$("$py" -c 'import sys; print(round(float(sys.argv[1]) + (int(sys.argv[2]) - int(sys.argv[3])) / 30, 4))' \
        "$end" "$frames" "$n")
    done
    if [ "$n" != "$frames" ]; then
      echo "could not make a $frames-frame leader (last: $n frames)" >&2
      exit 1
    fi
    RAYON_NUM_THREADS=$threads "$py" - "$exe" "$tmp" "$song" "$model" "${DUET_E2E_REPS:-3}" \
      "$frames" >> "$out" <<'PY'
import json, re, statistics, subprocess, sys, time
exe, tmp, song, model, reps, frames = sys.argv[1:7]
reps = int(reps)
wall, gen, sampling, decoding, line = [], [], [], [], ""
num = lambda pat: (lambda m: float(m.group(1)) if m else float("nan"))(re.search(pat, line))
for _ in range(reps):
    t = time.perf_counter()
    p = subprocess.run([exe, "generate", song, "--leader", f"{tmp}/leader.npz", "--model", model,
                        "-o", f"{tmp}/out.npy", "--seed", "0"], capture_output=True, text=True)
    wall.append(time.perf_counter() - t)
    if p.returncode != 0:
        sys.exit(f"dancegen generate --leader failed:\n{p.stderr}")
    line = p.stdout.splitlines()[0]
    gen.append(num(r"generated in ([0-9.]+) s"))
    sampling.append(num(r"sampling ([0-9.]+) s"))
    decoding.append(num(r"decoding ([0-9.]+) s"))
ms = lambda v: round(statistics.median(v) * 1e3, 1)
print(json.dumps({"impl": "dancegen-e2e", "case": f"e2e_{frames}f_duet", "median_ms": ms(wall),
                  "min_ms": round(min(wall) * 1e3, 1), "generate_ms": ms(gen),
                  "sampling_ms": ms(sampling), "decoding_ms": ms(decoding), "reps": reps,
                  "summary": line}), flush=True)
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
if den:
    steps = sorted({r.get("steps") for r in rows if r["impl"] != "dancegen-e2e"})
    print(f"{f'sampler ({steps[0]} steps) + HFSQ decoder':<34}{'pytorch ms':>12}{'burn ms':>12}"
          f"{'pytorch/burn':>14}  per round (pytorch / burn)")
    for c in den:
        pr, br = runs(c, "pytorch"), runs(c, "burn-flex")
        p, b = med(pr), med(br)
        ratio = f"{p / b:.2f}x" if pr and br else "(Rust only)"
        per = ", ".join(f"{x:.0f} / {y:.0f}" for x, y in zip(pr, br)) if pr else \
            ", ".join(f"{y:.0f}" for y in br)
        print(f"{c:<34}{p:>12.0f}{b:>12.0f}{ratio:>14}  {per}")
e2e = [r for r in rows if r["impl"] == "dancegen-e2e"]
if e2e:
    print(f"\n{'dancegen generate --leader':<34}{'wall s':>10}{'generate s':>12}{'sampling s':>12}"
          f"{'decoding s':>12}  vs 2 s")
    for r in e2e:
        s = r["median_ms"] / 1e3
        target = f"met ({2.0 / s:.2f}x under)" if s <= 2.0 else f"missed ({s / 2.0:.2f}x over)"
        print(f"{r['case']:<34}{s:>10.2f}{r['generate_ms'] / 1e3:>12.2f}"
              f"{r['sampling_ms'] / 1e3:>12.2f}{r['decoding_ms'] / 1e3:>12.2f}  {target}")
        print(f"  {r['summary']}")
PY
