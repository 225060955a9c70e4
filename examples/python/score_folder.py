#!/usr/bin/env python3
"""Score a folder of generated dances as a paper's results table does.

    python examples/python/score_folder.py GENERATED/ REAL/ --protocol aistpp-bailando \
        --fps 60 --beats BEATS.npy

GENERATED/ and REAL/ hold motion files (`.npy` joints (T, 24, 3), `.pkl`, `.npz`, `.bvh`: any
motion `dancegen convert` reads). The table has the columns of Bailando's and EDGE's tables
(FID_k, FID_g lower is better; Div_k, Div_g nearer the real dances' is better; BAS higher is
better; PFC lower is better) with a row for the real dances, followed by the physical figures
every dancegen report carries (feet on the floor, jerk, foot sliding, joint speed, step rate).
`--json FILE` also writes every value, per clip too.
"""

import argparse
import json
import sys

import dancegen

COLUMNS = [("FID_k", "fid_k"), ("FID_g", "fid_g"), ("Div_k", "div_k"), ("Div_g", "div_g"),
           ("BAS", "bas"), ("PFC", "pfc")]
PHYSICAL = [("float (%)", "float"), ("foot slide (m/s)", "foot_slide"), ("jerk (m/s³)", "jerk"),
            ("joint speed (m/s)", "joint_speed"), ("step rate (/s)", "step_rate")]


def cell(value):
    return "-" if value is None else f"{value:.4f}"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("generated")
    ap.add_argument("real")
    ap.add_argument("--protocol", default="aistpp-bailando",
                    help="aistpp-bailando, finedance-lodge, edge-5s or none")
    ap.add_argument("--fps", type=float, help="frame rate of .npy clips (they store none)")
    ap.add_argument("--beats", help="music beat frames (.npy); or --music")
    ap.add_argument("--music", help="the song, whose beats are found")
    ap.add_argument("--bas-variant", default="bailando")
    ap.add_argument("--json", help="write the whole report here")
    args = ap.parse_args(argv)

    common = dict(protocol=args.protocol, fps=args.fps)
    music = dict(beats=args.beats, music=args.music, bas_variant=args.bas_variant)
    wanted = ["fid_k", "fid_g", "div_k", "div_g", "pfc", "physical"]
    if args.beats or args.music:
        wanted.append("bas")
    ours = dancegen.evaluate(args.generated, args.real, metrics=wanted, **music, **common)
    # The real dances' own row: their diversity (`*_gt`), BAS, PFC and physical figures.
    real = dancegen.evaluate(args.real, metrics=[m for m in wanted if not m.startswith("fid")],
                             **music, **common)
    real_row = {"div_k": ours.get("div_k_gt"), "div_g": ours.get("div_g_gt"),
                "bas": real.get("bas"), "pfc": real.get("pfc")}

    print(f"protocol {ours['protocol']}: {len(ours['per_clip'])} generated dances")
    print(f"{'':<14}" + "".join(f"{name:>10}" for name, _ in COLUMNS))
    print(f"{'Ground truth':<14}" + "".join(f"{cell(real_row.get(k)):>10}" for _, k in COLUMNS))
    print(f"{'Generated':<14}" + "".join(f"{cell(ours.get(k)):>10}" for _, k in COLUMNS))
    print()
    print(f"{'':<14}" + "".join(f"{name:>19}" for name, _ in PHYSICAL))
    for label, report in (("Ground truth", real), ("Generated", ours)):
        print(f"{label:<14}" + "".join(f"{cell(report.get(k)):>19}" for _, k in PHYSICAL))
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"generated": ours, "real": real}, f, indent=1)
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except dancegen.DancegenError as e:
        sys.exit(f"score_folder.py: {e}")
