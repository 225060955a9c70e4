#!/usr/bin/env python3
"""Side-by-side timing: librosa 0.11 vs `dancegen features` on the same audio file.

Run through `bench/music_features.sh`, which installs librosa from PyPI into a venv if needed
and builds the release binary. Both tools compute the EDGE/Lodge 35-dim features (including
the 22050 Hz start-BPM estimate, as EDGE/Lodge do for songs without an AIST++ name) from the
same file: the clip decoded once, averaged to mono and written as 16-bit WAV at its native
rate, which is how the peer number in shared/fixtures/music/README.md §6 was taken. librosa is
timed in-process (median of N runs after a warm-up call), once with BLAS/OpenMP limited to one
thread as in that README and once with the library defaults; dancegen is timed as the wall time
of the whole CLI process (start-up + decode + features + writing the .npy) using both cores.
Prints per-run times and the ratios.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np


def librosa_extract(path, fps, start_bpm=None):
    """The reference pipeline (EDGE `baseline_features.extract`, fixtures README section 1)."""
    import librosa

    hop = 512
    sr = fps * hop
    if start_bpm is None:
        start_bpm = librosa.feature.tempo(y=librosa.load(path)[0])[0]
    y, _ = librosa.load(path, sr=sr)
    env = librosa.onset.onset_strength(y=y, sr=sr)
    mfcc = librosa.feature.mfcc(y=y, sr=sr, n_mfcc=20).T
    chroma = librosa.feature.chroma_cens(y=y, sr=sr, hop_length=hop, n_chroma=12).T
    peaks = librosa.onset.onset_detect(onset_envelope=env.flatten(), sr=sr, hop_length=hop)
    peak_1h = np.zeros_like(env, dtype=np.float32)
    peak_1h[peaks] = 1.0
    _, beats = librosa.beat.beat_track(
        onset_envelope=env, sr=sr, hop_length=hop, start_bpm=start_bpm, tightness=100
    )
    beat_1h = np.zeros_like(env, dtype=np.float32)
    beat_1h[beats] = 1.0
    return np.concatenate(
        [env[:, None], mfcc, chroma, peak_1h[:, None], beat_1h[:, None]], axis=-1
    ).astype(np.float32)


def time_librosa(path, fps, runs, threads=None):
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=threads):
        librosa_extract(path, fps)  # warm-up: numba JIT, FFT plans
        times = []
        out = None
        for _ in range(runs):
            t0 = time.perf_counter()
            out = librosa_extract(path, fps)
            times.append(time.perf_counter() - t0)
    return times, out


def time_dancegen(binary, path, fps, runs, out_npy):
    cmd = [binary, "-q", "features", path, "--fps", str(fps), "-o", out_npy]
    subprocess.run(cmd, check=True)  # warm-up: page cache
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True)
        times.append(time.perf_counter() - t0)
    return times


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--binary", required=True)
    ap.add_argument("--audio", required=True, help="input file (decoded to WAV first)")
    ap.add_argument("--long-audio", help="a song for the absolute-time check (first 180 s)")
    ap.add_argument("--fps", type=int, default=30)
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--json", help="write results here")
    args = ap.parse_args()

    import librosa
    import soundfile as sf

    results = {"librosa_version": librosa.__version__, "fps": args.fps, "runs": args.runs}
    with tempfile.TemporaryDirectory() as tmp:
        # Same input for both: the clip decoded once to 16-bit WAV at its native rate (as the
        # fixtures' timing table did), so neither side pays for a different decoder.
        y, sr = librosa.load(args.audio, sr=None, mono=True)
        wav = os.path.join(tmp, "bench.wav")
        sf.write(wav, y, sr, subtype="PCM_16")
        out_npy = os.path.join(tmp, "dg.npy")

        lt1, ref = time_librosa(wav, args.fps, args.runs, threads=1)
        ltd, _ = time_librosa(wav, args.fps, args.runs, threads=None)
        dt = time_dancegen(args.binary, wav, args.fps, args.runs, out_npy)
        ours = np.load(out_npy)
        med_1, med_dflt, med_d = (statistics.median(v) for v in (lt1, ltd, dt))
        dur = librosa.get_duration(path=wav)
        results.update(
            audio=args.audio,
            duration_s=dur,
            librosa_1thread_s=lt1,
            librosa_default_threads_s=ltd,
            dancegen_s=dt,
            ratio_vs_librosa_1thread=med_1 / med_d,
            ratio_vs_librosa_default_threads=med_dflt / med_d,
            identical_beats=bool(np.array_equal(ours[:, 34], ref[:, 34])),
            mfcc_max_abs_diff=float(np.abs(ours[:, 1:21] - ref[:, 1:21]).max()),
            chroma_max_abs_diff=float(np.abs(ours[:, 21:33] - ref[:, 21:33]).max()),
        )
        ms = lambda v: " ".join(f"{t*1e3:.0f}" for t in v)
        print(f"input: {args.audio} ({dur:.1f} s, {sr} Hz, mono 16-bit WAV), fps {args.fps}")
        print(f"librosa {librosa.__version__}, 1 BLAS thread:      {ms(lt1)} ms (median {med_1*1e3:.0f})")
        print(f"librosa {librosa.__version__}, default threads:    {ms(ltd)} ms (median {med_dflt*1e3:.0f})")
        print(f"dancegen, whole CLI process:      {ms(dt)} ms (median {med_d*1e3:.1f})")
        print(f"ratio: {med_1/med_d:.1f}x vs librosa 1 thread, {med_dflt/med_d:.1f}x vs default threads")
        print(f"identical beats: {results['identical_beats']}; MFCC max |diff| "
              f"{results['mfcc_max_abs_diff']:.1e}; chroma max |diff| {results['chroma_max_abs_diff']:.1e}")

        if args.long_audio:
            y, sr = librosa.load(args.long_audio, sr=None, mono=True, duration=180.0)
            wav2 = os.path.join(tmp, "long.wav")
            sf.write(wav2, y, sr, subtype="PCM_16")
            lt2 = time_dancegen(args.binary, wav2, args.fps, args.runs, out_npy)
            d2 = librosa.get_duration(path=wav2)
            results.update(long_audio=args.long_audio, long_duration_s=d2, long_dancegen_s=lt2)
            print(f"long input {args.long_audio} ({d2:.0f} s): dancegen "
                  + " ".join(f"{t*1e3:.0f}" for t in lt2)
                  + f" ms, median {statistics.median(lt2)*1e3:.0f} ms")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(results, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
