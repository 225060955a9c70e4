"""PyTorch side of `bash bench/nn.sh`: the EDGE-sized denoiser of
`crates/dancegen-nn/benches/denoiser.rs`, same shapes and cases, same timing (warm-up, then
`--reps` runs, median and min). Layers come from the parity reference
(`tools/parity/blocks.py::FilmDecoderLayer`, EDGE's FiLM decoder layer with rotary).
"""

import argparse
import json
import os
import sys
import time

import torch
import torch.nn as nn

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools", "parity"))
from blocks import FilmDecoderLayer  # noqa: E402

FRAMES, D_MOTION, D = 150, 151, 512


class Denoiser(nn.Module):
    def __init__(self):
        super().__init__()
        self.input = nn.Linear(D_MOTION, D)
        self.layers = nn.ModuleList(FilmDecoderLayer(D, 8, 1024, D) for _ in range(8))
        self.output = nn.Linear(D, D_MOTION)

    def forward(self, x, memory, cond):
        h = self.input(x)
        for l in self.layers:
            h = l(h, memory, cond, 0, None)
        return self.output(h)


def timed(name, reps, f):
    f()
    ms = []
    for _ in range(reps):
        t = time.perf_counter()
        f()
        ms.append((time.perf_counter() - t) * 1e3)
    ms.sort()
    print(json.dumps({"impl": "pytorch", "case": name, "median_ms": round(ms[len(ms) // 2], 2),
                      "min_ms": round(ms[0], 2), "reps": reps}), flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("only", nargs="?", default="")
    a = ap.parse_args()
    torch.manual_seed(0)
    inputs = lambda b: (torch.randn(b, FRAMES, D_MOTION), torch.randn(b, FRAMES, D),
                        torch.randn(b, D))
    model = Denoiser().eval()
    for b in (1, 8):
        case = f"forward_b{b}"
        if a.only in case:
            x, m, c = inputs(b)
            with torch.no_grad():
                timed(case, a.reps, lambda: model(x, m, c))
    for b in (1, 8):
        case = f"train_step_b{b}"
        if a.only not in case:
            continue
        net = Denoiser().train()
        opt = torch.optim.AdamW(net.parameters(), lr=1e-4)
        x, m, c = inputs(b)
        target = torch.randn(b, FRAMES, D_MOTION)

        def step():
            opt.zero_grad(set_to_none=True)
            loss = ((net(x, m, c) - target) ** 2).mean()
            loss.backward()
            opt.step()

        timed(case, a.reps, step)


if __name__ == "__main__":
    main()
