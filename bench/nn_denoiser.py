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

import math

import torch
import torch.nn as nn
import torch.nn.functional as F

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools", "parity"))
from blocks import FilmDecoderLayer  # noqa: E402

FRAMES, D_MOTION, D = 150, 151, 512


def timestep_embedding(t, d):
    half = d // 2
    f = torch.exp(torch.arange(half, dtype=torch.float32) * -(math.log(10000) / (half - 1)))
    e = t[:, None] * f[None]
    return torch.cat([e.sin(), e.cos()], -1)


class Denoiser(nn.Module):
    def __init__(self):
        super().__init__()
        self.time = nn.Linear(D, 4 * D)
        self.time_cond = nn.Linear(4 * D, D)
        self.input = nn.Linear(D_MOTION, D)
        self.layers = nn.ModuleList(FilmDecoderLayer(D, 8, 1024, D) for _ in range(8))
        self.output = nn.Linear(D, D_MOTION)

    def forward(self, x, t, memory, cond):
        cond = cond + self.time_cond(F.mish(self.time(timestep_embedding(t, D))))
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


def ddim(model, memory, cond, steps=50, eta=1.0, w=2.0):
    """EDGE's sampler: cosine schedule (T 1000), DDIM on int(linspace(-1, 999, 51)) pairs,
    x0 clamped to [-1, 1], guidance `unc + w (cond - unc)` (two forwards per step)."""
    T, s = 1000, 0.008
    x = torch.linspace(0, T, T + 1, dtype=torch.float64)
    ac = torch.cos(((x / T) + s) / (1 + s) * math.pi * 0.5) ** 2
    ac = ac / ac[0]
    betas = torch.clip(1 - ac[1:] / ac[:-1], 0, 0.999)
    acp = torch.cumprod(1 - betas, 0)
    times = list(reversed(torch.linspace(-1, T - 1, steps + 1).int().tolist()))
    xt = torch.randn(1, FRAMES, D_MOTION)
    null_m, null_c = torch.zeros_like(memory), torch.zeros_like(cond)
    for t, tn in zip(times[:-1], times[1:]):
        tt = torch.full((1,), float(t))
        pc = model(xt, tt, memory, cond)
        pu = model(xt, tt, null_m, null_c)
        x0 = (pu + w * (pc - pu)).clamp(-1, 1)
        a = acp[t].item()
        eps = (xt / math.sqrt(a) - x0) / math.sqrt(1 / a - 1)
        if tn < 0:
            xt = x0
            continue
        an = acp[tn].item()
        sigma = eta * math.sqrt((1 - a / an) * (1 - an) / (1 - a))
        c = math.sqrt(1 - an - sigma ** 2)
        xt = x0 * math.sqrt(an) + c * eps + sigma * torch.randn_like(xt)
    return xt


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
                timed(case, a.reps, lambda: model(x, torch.full((b,), 500.0), m, c))
    if a.only in "ddim50_b1":
        _, m, c = inputs(1)
        with torch.no_grad():
            timed("ddim50_b1", min(a.reps, 3), lambda: ddim(model, m, c))
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
            loss = ((net(x, torch.full((b,), 500.0), m, c) - target) ** 2).mean()
            loss.backward()
            opt.step()

        timed(case, a.reps, step)


if __name__ == "__main__":
    main()
