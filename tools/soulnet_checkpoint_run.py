#!/usr/bin/env python3
# Makes a "finished run" directory from a soulnet_magm checkpoint (its raw weights, not the EMA),
# so `dancegen bundle --holistic-generator` can assemble a model from it: the comparison of the
# generator with and without the MMR loss at equal steps (docs/holistic-eval.md section 7).
#
#     python3 tools/soulnet_checkpoint_run.py RUN STEP OUT_RUN_DIR
#
# e.g. RUN = target/runs/soulnet_small_generator, STEP = 1000. Needs Python 3.11 (tomllib).
import sys, os, shutil, tomllib
run, step, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
cfg = tomllib.load(open(os.path.join(run, "config.toml"), "rb"))
m = cfg["model"]
vq = tomllib.load(open(os.path.join(m["vq"], "model.toml"), "rb"))["config"]
mmr = tomllib.load(open(os.path.join(m["mmr"], "model.toml"), "rb"))["config"]
def val(v):
    if isinstance(v, bool): return "true" if v else "false"
    if isinstance(v, str): return '"%s"' % v
    if isinstance(v, list): return "[" + ", ".join(val(x) for x in v) + "]"
    return repr(v)
def table(name, d):
    return "[%s]\n" % name + "".join("%s = %s\n" % (k, val(v)) for k, v in d.items() if not isinstance(v, dict)) + "\n"
os.makedirs(out, exist_ok=True)
top = {k: v for k, v in m.items() if k not in ("kind", "generator")}
text = 'ema = false\nfps = 30.0\nkind = "soulnet_magm"\nrepresentation = "holistic"\nsteps = %d\nwindow = 128\n\n' % step
text += table("config", top) + table("config.generator", m["generator"]) + table("config.vq_table", vq) + table("config.mmr_table", mmr)
open(os.path.join(out, "model.toml"), "w").write(text)
shutil.copy(os.path.join(run, "checkpoints", "step_%d" % step, "model.safetensors"), os.path.join(out, "model.safetensors"))
shutil.copy(os.path.join(run, "normalizer.json"), os.path.join(out, "normalizer.json"))
shutil.copy(os.path.join(run, "config.toml"), os.path.join(out, "config.toml"))
print(out)
