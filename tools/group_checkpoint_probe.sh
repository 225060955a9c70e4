#!/usr/bin/env bash
# Probes a training checkpoint of the group model the way docs/group-collapse.md does: bundles
# it, dances 5 dancers free to feelings.ogg 30-60 s with seeds 0 and 1 (quadratic DDIM
# spacing), and prints tools/group_probe.py's root steps, pose spread, closest pair and seed
# difference, then `dancegen eval --metrics physical` per dancer of seed 0.
#
#   bash tools/group_checkpoint_probe.sh RUN STEP OUT [model|ema]
#
# DANCEGEN: the CLI (default: the release build in CARGO_TARGET_DIR or target/).
set -euo pipefail
run=$1 step=$2 out=$3 weights=${4:-model}
here=$(cd "$(dirname "$0")/.." && pwd)
dg=${DANCEGEN:-${CARGO_TARGET_DIR:-$here/target}/release/dancegen}
song=${SONG:-$here/../shared/data/music/sectoid/feelings.ogg}
ckpt=$run/checkpoints/step_$step
[ -f "$ckpt/$weights.safetensors" ] || { echo "no $ckpt/$weights.safetensors" >&2; exit 1; }
rm -rf "$out" && mkdir -p "$out/run" "$out/dancers"
cp "$run/config.toml" "$run/normalizer.json" "$out/run/"
cp "$ckpt/$weights.safetensors" "$out/run/model.safetensors"
# A finished run's model.toml: the run config's [model] tables as [config] (the warm-start
# keys, which only say where training began, left out).
python3 - "$out/run/config.toml" "$out/run/model.toml" <<'PY'
import re, sys
src, dst = sys.argv[1], sys.argv[2]
out, inside = ['kind = "tcdiffpp_group"', '[config]'], False
for line in open(src).read().splitlines():
    head = re.match(r'^\[([^\]]+)\]', line)
    if head:
        name = head.group(1)
        inside = name == 'model' or name.startswith('model.')
        if inside and name != 'model':
            out.append('[config.' + name[len('model.'):] + ']')
        continue
    if inside and not re.match(r'^\s*(kind|init_from|init_fresh)\s*=', line):
        out.append(line)
open(dst, 'w').write('\n'.join(out) + '\n')
PY
"$dg" -q bundle --group "$out/run" -o "$out/model"
# Bundles get this version's sampling defaults; the probes use the quadratic spacing.
python3 - "$out/model/model.toml" <<'PY'
import re, sys
p = sys.argv[1]
s = open(p).read()
if re.search(r'^spacing\s*=', s, re.M):
    s = re.sub(r'^spacing\s*=.*$', 'spacing = "quadratic"', s, flags=re.M)
else:
    s = s.replace('[model.sampling]', '[model.sampling]\nspacing = "quadratic"', 1)
open(p, 'w').write(s)
PY
for seed in 0 1; do
  "$dg" -q generate "$song" --system group --dancers 5 --start 30 --end 60 --seed $seed \
    --model "$out/model" -o "$out/seed$seed.npy"
done
python3 "$here/tools/group_probe.py" "$out/seed0.npy" "$out/seed1.npy"
for k in 0 1 2 3 4; do
  "$dg" -q convert "$out/seed0.npy" --dancer $k -o "$out/dancers/d$k.npy"
done
"$dg" -q eval --pred "$out/dancers" --fps 30 --metrics physical
