"""Parity fixtures (and a timing peer) for the selective state-space layer of `dancegen-nn`
(`crates/dancegen-nn/src/ssm.rs`): Mamba v1 (Gu & Dao 2023) with the sizes TCDiff++ uses
(`mamba_addon/modules/mamba_simple.py`: d_state 16, d_conv 4, expand 2, dt_rank ceil(d/16),
dt in [0.001, 0.1], S4D-real A). The reference below is written from the paper's recurrence and
the reference scan's formulas (`selective_scan_ref`): pure PyTorch, one step per frame.

    python tools/parity/ssm.py            # writes the fixtures
    python tools/parity/ssm.py --bench    # times forward and forward+backward on the bench shapes
"""

import argparse
import json
import math
import time

import torch
import torch.nn as nn
import torch.nn.functional as F

from common import randn, seeded, write


class Mamba(nn.Module):
    def __init__(self, d_model, d_state=16, d_conv=4, expand=2, dt_min=0.001, dt_max=0.1,
                 dt_init_floor=1e-4):
        super().__init__()
        self.d_inner = expand * d_model
        self.d_state = d_state
        self.dt_rank = math.ceil(d_model / 16)
        di, n, r = self.d_inner, d_state, self.dt_rank
        self.in_proj = nn.Linear(d_model, 2 * di, bias=False)
        self.conv1d = nn.Conv1d(di, di, d_conv, groups=di, padding=d_conv - 1, bias=True)
        self.x_proj = nn.Linear(di, r + 2 * n, bias=False)
        self.dt_proj = nn.Linear(r, di, bias=True)
        std = r ** -0.5
        nn.init.uniform_(self.dt_proj.weight, -std, std)
        dt = torch.exp(torch.rand(di) * (math.log(dt_max) - math.log(dt_min)) + math.log(dt_min))
        dt = dt.clamp(min=dt_init_floor)
        with torch.no_grad():
            self.dt_proj.bias.copy_(dt + torch.log(-torch.expm1(-dt)))
        a = torch.arange(1, n + 1, dtype=torch.float32).repeat(di, 1)
        self.A_log = nn.Parameter(torch.log(a))
        self.D = nn.Parameter(torch.ones(di))
        self.out_proj = nn.Linear(di, d_model, bias=False)

    def forward(self, x, scan="sequential", chunk=None):
        B, T, _ = x.shape
        di, n, r = self.d_inner, self.d_state, self.dt_rank
        x, z = self.in_proj(x).chunk(2, dim=-1)
        u = F.silu(self.conv1d(x.transpose(1, 2))[..., :T].transpose(1, 2))
        dt, b, c = self.x_proj(u).split([r, n, n], dim=-1)
        delta = F.softplus(self.dt_proj(dt))
        a = -torch.exp(self.A_log)
        y = (sequential_scan if scan == "sequential" else
             lambda *args: chunked_scan(*args, chunk=chunk))(u, delta, a, b, c, self.D)
        return self.out_proj(y * F.silu(z))


def sequential_scan(u, delta, a, b, c, d):
    """h_t = exp(delta_t A) h_{t-1} + delta_t B_t u_t, y_t = C_t . h_t + D u_t (batch-first)."""
    B, T, di = u.shape
    decay = torch.exp(delta[..., None] * a)               # [B, T, D, N]
    dbu = (delta * u)[..., None] * b[:, :, None, :]       # [B, T, D, N]
    h = u.new_zeros(B, di, a.shape[1])
    ys = []
    for t in range(T):
        h = decay[:, t] * h + dbu[:, t]
        ys.append((h * c[:, t, None, :]).sum(-1))
    return torch.stack(ys, dim=1) + u * d


CHUNK_LOG_RANGE, MAX_CHUNK = 60.0, 64  # as `ssm.rs`


def chunk_len(max_abs_da, frames, max_chunk=MAX_CHUNK):
    """`ssm.rs` `chunk_len`: the longest chunk whose |sum delta A| stays within the range."""
    limit = max(1, min(max_chunk, int(CHUNK_LOG_RANGE // max_abs_da))) if max_abs_da > 0 \
        else max_chunk
    chunks = -(-frames // limit)
    return -(-frames // chunks)


def chunked_scan(u, delta, a, b, c, d, chunk=None):
    """The Rust chunked formulation (log-space cumulative sums within chunks), for timing;
    `chunk` as `selective_scan_chunked`'s maximum."""
    B, T, di = u.shape
    n = a.shape[1]
    max_abs_da = (delta.detach().amax((0, 1)) * a.detach().abs().amax(1)).max().item()
    chunk = chunk_len(max_abs_da, T, chunk or MAX_CHUNK)
    nc = -(-T // chunk)
    tp = nc * chunk
    da = F.pad(delta[..., None] * a, (0, 0, 0, 0, 0, tp - T)).reshape(B, nc, chunk, di, n)
    dbu = F.pad((delta * u)[..., None] * b[:, :, None, :], (0, 0, 0, 0, 0, tp - T))
    dbu = dbu.reshape(B, nc, chunk, di, n)
    cum = da.cumsum(2)
    mid = cum[:, :, -1:].detach() * 0.5
    grow = torch.exp(cum - mid)
    local = grow * (grow.reciprocal() * dbu).cumsum(2)
    decay = torch.exp(cum)
    h0 = u.new_zeros(B, di, n)
    starts = []
    for i in range(nc):
        starts.append(h0)
        h0 = decay[:, i, -1] * h0 + local[:, i, -1]
    h = local + decay * torch.stack(starts, 1)[:, :, None]
    cp = F.pad(c, (0, 0, 0, tp - T)).reshape(B, nc, chunk, 1, n)
    y = (h * cp).sum(-1).reshape(B, tp, di)[:, :T]
    return y + u * d


def perturb(m, g, scale=0.1):
    """Moves A_log and D off their structured init so every entry's gradient is distinct."""
    with torch.no_grad():
        m.A_log.add_(randn(g, *m.A_log.shape, scale=scale))
        m.D.add_(randn(g, *m.D.shape, scale=scale))


def mamba_fixture():
    g = seeded(11)
    B, T, d = 2, 13, 8
    m = Mamba(d)
    perturb(m, g)
    x = randn(g, B, T, d).requires_grad_(True)
    probe = randn(g, B, T, d)
    y = m(x)
    gx, ga, gw = torch.autograd.grad((y * probe).sum(), [x, m.A_log, m.dt_proj.weight])
    write("mamba", m.state_dict(),
          {"in.x": x, "in.probe": probe, "out.y": y, "grad.x": gx, "grad.A_log": ga,
           "grad.dt_proj.weight": gw},
          {"d_model": d, "d_state": m.d_state, "dt_rank": m.dt_rank})


def mamba_large_delta_fixture():
    """Large Delta (dt bias raised) so the automatic chunk length is short and the chunked scan
    runs many chunks with a carried state; T not a multiple of any chunk length used."""
    g = seeded(12)
    B, T, d = 1, 37, 8
    m = Mamba(d, d_state=4)
    perturb(m, g)
    with torch.no_grad():
        m.dt_proj.bias.add_(3.0)  # softplus(~-2 + 3) ~ 1.3: |delta A| up to ~5
    x = randn(g, B, T, d).requires_grad_(True)
    probe = randn(g, B, T, d)
    y = m(x)
    gx, ga = torch.autograd.grad((y * probe).sum(), [x, m.A_log])
    write("mamba_large_delta", m.state_dict(),
          {"in.x": x, "in.probe": probe, "out.y": y, "grad.x": gx, "grad.A_log": ga},
          {"d_model": d, "d_state": m.d_state})


class MambaBlock(nn.Module):
    """Pre-norm residual wrapper, x + mamba(norm(x))."""

    def __init__(self, d):
        super().__init__()
        self.norm = nn.LayerNorm(d)
        self.mamba = Mamba(d)

    def forward(self, x):
        return x + self.mamba(self.norm(x))


def mamba_block_fixture():
    g = seeded(13)
    B, T, d = 2, 9, 8
    blk = MambaBlock(d)
    perturb(blk.mamba, g)
    with torch.no_grad():
        blk.norm.weight.add_(randn(g, d, scale=0.1))
        blk.norm.bias.add_(randn(g, d, scale=0.1))
    x = randn(g, B, T, d).requires_grad_(True)
    probe = randn(g, B, T, d)
    y = blk(x)
    gx, gn = torch.autograd.grad((y * probe).sum(), [x, blk.norm.weight])
    write("mamba_block", blk.state_dict(),
          {"in.x": x, "in.probe": probe, "out.y": y, "grad.x": gx, "grad.norm.weight": gn},
          {"d_model": d})


def bench(rounds, forward_rounds):
    """Median ms of forward (no grad) and forward+backward of the Mamba layer, both scans.
    Shapes as `crates/dancegen-nn/benches/ssm_scan.rs`. One JSON line per measurement."""
    torch.manual_seed(0)
    for d in (64, 128):
        m = Mamba(d)
        for T in (150, 512):
            x = torch.randn(2, T, d)
            for scan in ("sequential", "chunked"):
                def fwd():
                    with torch.no_grad():
                        m(x, scan)

                def fwd_bwd():
                    xi = x.clone().requires_grad_(True)
                    m(xi, scan).square().mean().backward()

                for what, fn in (("forward", fwd), ("forward_backward", fwd_bwd)):
                    fn()
                    times = []
                    for _ in range(forward_rounds if what == "forward" else rounds):
                        t0 = time.perf_counter()
                        fn()
                        times.append((time.perf_counter() - t0) * 1e3)
                    times.sort()
                    print(json.dumps({"framework": "pytorch", "d_model": d, "frames": T,
                                      "batch": 2, "scan": scan, "what": what,
                                      "median_ms": round(times[len(times) // 2], 2),
                                      "threads": torch.get_num_threads()}), flush=True)


if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("--bench", action="store_true")
    ap.add_argument("--rounds", type=int, default=3, help="forward+backward rounds")
    ap.add_argument("--forward-rounds", type=int, default=15)
    args = ap.parse_args()
    if args.bench:
        bench(args.rounds, args.forward_rounds)
    else:
        torch.set_num_threads(1)
        mamba_fixture()
        mamba_large_delta_fixture()
        mamba_block_fixture()
        # The chunked formulation equals the reference scan (checked here too, in float64).
        g = seeded(14)
        m = Mamba(8).double()
        x = randn(g, 2, 29, 8).double()
        err = (m(x, "chunked", chunk=6) - m(x)).abs().max().item()
        assert err < 1e-12, err
