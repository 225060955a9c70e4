#!/usr/bin/env python3
"""The Python package (`import dancegen`) against the Python tools researchers use today, in
the same process and the same run: `dancegen.features` against librosa 0.11's EDGE/Lodge
pipeline (bench/music_features.py), and `dancegen.evaluate` against the Python/numpy port of
the reference metric code (bench/metrics_reference.py) on the metrics test set.

    python_package.py --audio CLIP --set bench/.metrics-set [--reps 5] [--json OUT]

Run through bench/python_package.sh, which builds the release wheel, installs it with librosa,
scipy and dtaidistance into bench/.venv, and builds the test set. Every side is timed in this
process with time.perf_counter (median of --reps after a warm-up call; the reference metric port
runs once per protocol, as bench/metrics.sh times it, because it takes minutes):
  - features: the same 16-bit WAV (the clip decoded once at its native rate) into librosa with
    one BLAS thread and with the default threads, and into dancegen.features (both cores);
  - evaluate: the reference port's whole solo suite (FID/Div on kinetic and geometric features,
    BAS, PFC, FSR, MPJPE, freeze, boundary jerk), with the clips already loaded, against
    dancegen.evaluate on the same arrays (in memory, `(name, array)` as the package takes them)
    and on the folders (reading the .npy files included). The values are cross-checked.
numpy/BLAS threads are pinned to 2 by the .sh (the machine has 2 cores).
"""
import argparse
import json
import os
import statistics
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import dancegen  # noqa: E402
import metrics_reference as ref  # noqa: E402
from music_features import librosa_extract  # noqa: E402

SOLO_METRICS = "fid_k,div_k,fid_g,div_g,bas,pfc,fsr,mpjpe,freeze,boundary_jerk"


def median_time(fn, reps):
    fn()  # warm-up: numba JIT, FFT plans, page cache
    times = []
    for _ in range(reps):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times), times


def bench_features(audio, reps):
    import librosa
    import soundfile as sf
    from threadpoolctl import threadpool_limits

    with tempfile.TemporaryDirectory() as tmp:
        y, sr = librosa.load(audio, sr=None, mono=True)
        wav = os.path.join(tmp, "clip.wav")
        sf.write(wav, y, sr, subtype="PCM_16")
        with threadpool_limits(limits=1):
            lib1, _ = median_time(lambda: librosa_extract(wav, 30), reps)
        libd, _ = median_time(lambda: librosa_extract(wav, 30), reps)
        ours, _ = median_time(lambda: dancegen.features(wav), reps)
        a, b = dancegen.features(wav), librosa_extract(wav, 30)
        return {
            "audio": audio,
            "seconds_of_audio": len(y) / sr,
            "librosa_1_thread_s": lib1,
            "librosa_default_threads_s": libd,
            "dancegen_features_s": ours,
            "ratio_vs_librosa_1_thread": lib1 / ours,
            "ratio_vs_librosa_default_threads": libd / ours,
            "identical_beats": bool(np.array_equal(a[:, 34], b[:, 34])),
            "mfcc_max_abs_diff": float(np.abs(a[:, 1:21] - b[:, 1:21]).max()),
        }


def bench_evaluate(set_dir, protocol, reps):
    pred = ref.load_dir(f"{set_dir}/solo/pred")
    gt = ref.load_dir(f"{set_dir}/solo/gt")
    beats = np.load(f"{set_dir}/beats.npy").astype(np.int64)
    groups = ref.solo_groups(pred, gt, beats, protocol, ref.FPS)
    t = time.perf_counter()
    values = {}
    for fn in groups.values():
        values.update(fn()[0])
    reference_s = time.perf_counter() - t

    kw = dict(protocol=protocol, fps=ref.FPS, beats=beats.tolist(), metrics=SOLO_METRICS)
    pred_arrays = [(n, a) for n, a in pred]
    gt_arrays = [(n, a) for n, a in gt]
    in_memory = lambda: dancegen.evaluate(dict(pred_arrays), dict(gt_arrays), **kw)  # noqa: E731
    from_files = lambda: dancegen.evaluate(f"{set_dir}/solo/pred", f"{set_dir}/solo/gt", **kw)  # noqa: E731
    arrays_s, _ = median_time(in_memory, reps)
    files_s, _ = median_time(from_files, reps)
    ours = in_memory()
    worst = {k: ref.rel_diff(v, ours.get(k)) for k, v in values.items() if k in ours}
    return {
        "protocol": protocol,
        "clips": [len(pred), len(gt)],
        "reference_port_s": reference_s,
        "dancegen_evaluate_arrays_s": arrays_s,
        "dancegen_evaluate_files_s": files_s,
        "ratio_arrays": reference_s / arrays_s,
        "ratio_files": reference_s / files_s,
        "worst_rel_diff": worst,
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--audio", required=True)
    ap.add_argument("--set", required=True)
    ap.add_argument("--protocols", default="none,finedance-lodge")
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--json")
    args = ap.parse_args()

    out = {"numpy": np.__version__, "threads": os.environ.get("OPENBLAS_NUM_THREADS")}
    f = bench_features(args.audio, args.reps)
    out["features"] = f
    print(f"features of {f['audio']} ({f['seconds_of_audio']:.1f} s), median of {args.reps}:")
    print(f"  librosa 1 thread       {f['librosa_1_thread_s'] * 1e3:8.0f} ms")
    print(f"  librosa default        {f['librosa_default_threads_s'] * 1e3:8.0f} ms")
    print(f"  dancegen.features      {f['dancegen_features_s'] * 1e3:8.0f} ms   "
          f"{f['ratio_vs_librosa_1_thread']:.1f}x / {f['ratio_vs_librosa_default_threads']:.1f}x "
          f"faster; identical beats {f['identical_beats']}, "
          f"MFCC max |diff| {f['mfcc_max_abs_diff']:.1e}")
    out["evaluate"] = []
    for protocol in args.protocols.split(","):
        e = bench_evaluate(args.set, protocol, args.reps)
        out["evaluate"].append(e)
        worst = max((w for w in e["worst_rel_diff"].values() if w is not None), default=0.0)
        print(f"evaluate, protocol {protocol}, {e['clips'][0]} + {e['clips'][1]} clips "
              f"({SOLO_METRICS}):")
        print(f"  reference port         {e['reference_port_s'] * 1e3:8.0f} ms")
        print(f"  dancegen.evaluate      {e['dancegen_evaluate_arrays_s'] * 1e3:8.1f} ms   "
              f"{e['ratio_arrays']:.0f}x faster (arrays in memory)")
        print(f"  dancegen.evaluate      {e['dancegen_evaluate_files_s'] * 1e3:8.1f} ms   "
              f"{e['ratio_files']:.0f}x faster (folders, reading included)")
        print(f"  worst relative difference of a value: {worst:.1e}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(out, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
