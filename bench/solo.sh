#!/usr/bin/env bash
# Lodge++ solo generation speed: the PDDM sampler on burn-flex vs the same denoiser architecture
# and step count in PyTorch CPU (interleaved in one run), then `dancegen generate` end to end from
# the audio file (1024 frames and 5 minutes) against Lodge++'s reported 6.2 s GPU time.
#   bash bench/solo.sh [ROUNDS] [CASE]     (default 3 rounds, all cases; CASE filters by name)
# Environment:
#   DANCEGEN_TORCH_VENV        torch venv (default bench/.venv-torch, created from PyPI if missing)
#   DANCEGEN_BENCH_REPS        timed runs per round of the 1024-frame cases (default 3)
#   DANCEGEN_BENCH_REPS_LONG   timed runs per round of the 5-minute case (default 1)
#   SOLO_E2E_REPS              `dancegen generate` runs per end-to-end case (default 3; 5 min: 1)
#   SOLO_SKIP_E2E=1            denoiser comparison only
#   SOLO_SKIP_DENOISER=1       end-to-end only
# The end-to-end part needs the bundled model (models/lodgepp-small); it is skipped with a
# message when the model is missing. Ratio = PyTorch time / burn time (> 1 = Rust faster).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
# shellcheck source=bench/lib.sh
source "$here/lib.sh"
root="$(cd "$here/.." && pwd)"
rounds="${1:-3}"
case="${2:-}"
venv="${DANCEGEN_TORCH_VENV:-$here/.venv-torch}"
threads=$(nproc)
songs="${SOLO_SONGS:-$root/../shared/data/music/sectoid}"
model="$root/models/lodgepp-small"
py=$(torch_python "$venv")
out="${SOLO_RESULTS:-$(mktemp)}"
: > "$out"
echo "results: $out" >&2
echo "load before: $(uptime)" >&2

if [ "${SOLO_SKIP_DENOISER:-0}" != 1 ]; then
  bin=$(bench_binary dancegen-lodgepp pddm_sampling "$py")
  interleaved_rounds "$rounds" "$threads" "$bin" "$py" "$here/solo_pddm.py" "$case" "$out"
fi

if [ "${SOLO_SKIP_E2E:-0}" != 1 ]; then
  if [ ! -f "$model/model.toml" ]; then
    echo "no bundled model at $model: end-to-end cases skipped" >&2
  else
    cargo build -q --release -p dancegen-cli --manifest-path "$root/Cargo.toml"
    tmp=$(mktemp -d)
    trap 'rm -rf "$tmp"' EXIT
    # A 34.12 s song and a 299.99 s song from the sectoid songs: librosa framing (centred,
    # 1 + floor(samples / hop)) gives exactly 1024 frames (8 windows) and 9000 frames (71
    # windows) at 30 fps; 34.133 s would give 1025 frames and a 9th window. Licence of the songs:
    # shared/data/music/sectoid/COPYRIGHT.txt (MIT-style).
    ffmpeg -v error -y -i "$songs/escape_from_chaosland.ogg" -t 34.12 -c:a pcm_s16le "$tmp/song_1024f.wav"
    ffmpeg -v error -y -i "$songs/escape_from_chaosland.ogg" -i "$songs/metal_madness.ogg" \
      -filter_complex '[0:a][1:a]concat=n=2:v=0:a=1[a]' -map '[a]' -t 299.99 -c:a pcm_s16le "$tmp/song_5min.wav"
    RAYON_NUM_THREADS=$threads "$py" - "$root/target/release/dancegen" "$tmp" "$songs" \
      "${SOLO_E2E_REPS:-3}" "$case" >> "$out" <<'PY'
import json, re, statistics, subprocess, sys, time
exe, tmp, songs, reps, only = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]), sys.argv[5]
cases = [
    # (name, generate arguments, runs)
    ("e2e_1024f_34s_song", [f"{tmp}/song_1024f.wav"], reps),
    ("e2e_1024f_end34.13", [f"{songs}/escape_from_chaosland.ogg", "--end", "34.13"], reps),
    ("e2e_5min_song", [f"{tmp}/song_5min.wav"], 1),
]
for name, args, n in cases:
    if only not in name:
        continue
    wall, gen, line = [], [], ""
    for _ in range(n):
        t = time.perf_counter()
        p = subprocess.run([exe, "generate", *args, "-o", f"{tmp}/out.npy", "--seed", "0"],
                           capture_output=True, text=True)
        wall.append(time.perf_counter() - t)
        if p.returncode != 0:
            sys.exit(f"{name}: dancegen generate failed:\n{p.stderr}")
        line = p.stdout.splitlines()[0]
        m = re.search(r"generated in ([0-9.]+) s", line)
        gen.append(float(m.group(1)) if m else float("nan"))
    print(json.dumps({"impl": "dancegen-e2e", "case": name, "median_ms": round(statistics.median(wall) * 1e3, 1),
                      "min_ms": round(min(wall) * 1e3, 1),
                      "generate_ms": round(statistics.median(gen) * 1e3, 1), "reps": n,
                      "summary": line}), flush=True)
PY
  fi
fi

echo "load after: $(uptime)" >&2
"$py" - "$out" <<'PY'
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.startswith("{")]
med = lambda c, impl, k="median_ms": statistics.median(
    [r[k] for r in rows if r["case"] == c and r["impl"] == impl] or [float("nan")])
den = sorted({r["case"] for r in rows if r["impl"] != "dancegen-e2e"})
if den:
    print(f"{'PDDM sampler (50 steps, CFG)':<30}{'pytorch ms':>12}{'burn ms':>12}{'pytorch/burn':>14}")
    for c in den:
        p, b = med(c, "pytorch"), med(c, "burn-flex")
        ratio = f"{p / b:.2f}x" if p == p else "(Rust only)"
        print(f"{c:<30}{p:>12.0f}{b:>12.0f}{ratio:>14}")
e2e = [r for r in rows if r["impl"] == "dancegen-e2e"]
if e2e:
    print(f"\n{'dancegen generate (wall)':<30}{'wall s':>10}{'generate s':>12}  target")
    for r in e2e:
        s = r["median_ms"] / 1e3
        target = ("under 6.2 s" if s < 6.2 else "over 6.2 s") if "1024f" in r["case"] else "-"
        print(f"{r['case']:<30}{s:>10.2f}{r['generate_ms'] / 1e3:>12.2f}  {target}")
        print(f"  {r['summary']}")
PY
