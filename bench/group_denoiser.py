"""PyTorch side of `bash bench/group.sh`: the TCDiff++ group denoiser, its long samplers (LGDS
and the parallel EDGE-style one) with classifier-free guidance, the same architecture, shapes,
network evaluations and timing as `crates/dancegen-tcdiffpp/benches/group_sampling.rs` (a
warm-up run with 2 steps, then `--reps` runs, median and min, one JSON line per case).

Sizes: `configs/tcdiffpp_small.toml` [model.denoiser], read at import like the Rust bench does;
missing keys take the defaults of `crates/dancegen-tcdiffpp/src/config.rs` (d 128, 4 layers,
4 heads, FF 512, 2 music layers, cross-attention mixer, fusion hidden 2d, footwork hidden 128).
Both sides print the parameter count to stderr; they must agree. The Mamba mixer is not ported
(the shipped config uses cross-attention; this script refuses another mixer).

Architecture (written from `crates/dancegen-tcdiffpp/src/{denoiser,fusion,swap,footwork,layout,
config}.rs` and the `dancegen-nn` layers they use; random weights, identity normaliser;
parameter names follow the Rust modules). A group window is [B, T, 5 x 151], read as
frame-major tokens [B, 5 T, 151] (token k = frame k // 5, slot k % 5):
- input Linear(151 + 1 control flag -> d), plus the dancer positioning embedding (sinusoidal
  code of the token's frame + sinusoidal code of its slot out of a 5-row table), times the slot
  mask;
- Fusion Projection over each frame's 5 slots: [B, T, 5 d] -> Linear(5d, 2d) -> ReLU ->
  Linear(2d, 2d) -> ReLU -> Linear(2d, 5d), masked;
- timestep: sinusoidal(d) -> Linear(d, 4d) -> Mish, then `time_cond` Linear(4d, d);
- music (once per run and branch, `GroupDenoiser::prepare`): Linear(35 -> d) + sinusoidal PE,
  `music_layers` post-norm GELU encoder layers, `music_pool` Linear(d, d) of the mean over
  frames; the null branch uses the learned `null_music` token for every frame and for the pool;
- swap mode: one-hot 5 x 5 permutation -> Linear(25, d) -> GELU -> Linear(d, d) -> GELU, as one
  memory token in front of the music tokens (memory = 1 + T tokens) and added to the FiLM vector;
- `n_layers` norm-first FiLM decoder layers (`torch_blocks.FilmDecoderLayer`): self-attention
  over all 5 T tokens (key padding on empty slots; none with 5 dancers), cross-attention to the
  memory (keys/values projected once per run and branch, as Rust's `memory_kv`), GELU FF, FiLM
  vector = pooled music + swap + time, [B, 1, d]; tokens masked after every layer;
- output Linear(d -> 151), then the Footwork Adaptor: three ConcatSquashLinear layers
  (151 -> 128 -> 128 -> 151, `W x * sigmoid(G c) + B c`, leaky ReLU 0.01 between) on the
  per-dancer root x/y displacement context; its output replaces the lower-body 6D rotations.

Samplers (`crates/dancegen-tcdiffpp/src/sampler.rs` + `dancegen_nn::diffusion::sample_with`):
EDGE cosine schedule T = 1000 (float64 tables), DDIM on EDGE's strided steps, eta 1, no x0
clamp, guidance w = 2: per step ONE forward of the conditional branch and ONE of the null
branch (as Rust, not one batched forward), x0 = unc + w (cond - unc).
- `lgds_5x1800f`: 1800 frames = 23 windows of 150 frames at stride 75, one after another
  (batch 1). Window w > 0: slots re-sorted by the previous window's tail (stage x at its first
  frame), roots re-based to its centroid, init = that tail noised to t = 999 on the first 75
  frames + fresh noise, the clean tail imposed on the first 75 frames after every step; the
  result mapped back and its second half appended; then denormalised.
- `parallel_5x1800f`: all 23 windows as one batch; after every step but the last each
  window's first half is overwritten by the previous window's second half re-based to its
  first-frame centroid; then the windows are placed, denormalised and stitched (linear
  cross-fade, quaternion slerp of every 6D rotation over the overlaps, float64).
"""

import argparse
import json
import math
import os
import sys
import time
import tomllib

import torch
import torch.nn as nn
import torch.nn.functional as F

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from torch_blocks import LN_EPS, EncoderLayer, FilmDecoderLayer  # noqa: E402, F401

# layout.rs, edge151.rs, denoiser.rs, footwork.rs, config.rs.
N_MAX, DIMS, MUSIC_DIMS = 5, 151, 35
GROUP_DIMS = N_MAX * DIMS
ROOT_HORIZONTAL = (4, 5)
ROT6D_START = 7
LOWER_BODY = [1, 2, 3, 4, 5, 7, 8, 10, 11]
LEAKY_SLOPE = 0.01
SWAP_DIMS = N_MAX * N_MAX
WINDOW = 150
TIMESTEPS = 1000
FRAMES, DANCERS = 1800, 5
# SamplingConfig::default().
# The model's sampling defaults, given by bench/group.sh from models/tcdiffpp-small/model.toml
# (the Rust side reads the same variables); SamplingConfig::default otherwise.
STEPS = int(os.environ.get("GROUP_BENCH_STEPS", 6))
ETA = 1.0
GUIDANCE = float(os.environ.get("GROUP_BENCH_GUIDANCE", 2.0))

_configs = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "configs")


def _table(file, key, defaults):
    with open(os.path.join(_configs, file), "rb") as f:
        return {**defaults, **tomllib.load(f).get("model", {}).get(key, {})}


# DenoiserConfig::default().
DEN = _table("tcdiffpp_small.toml", "denoiser",
             {"d_model": 128, "n_layers": 4, "n_heads": 4, "d_ff": 512, "music_layers": 2,
              "dropout": 0.1, "mixer": "cross_attention", "fusion_projection": True,
              "fusion_hidden": None, "positioning": True, "swap_mode": True, "footwork": True,
              "footwork_hidden": 128})
if DEN["mixer"] != "cross_attention":
    sys.exit(f"group_denoiser.py ports the cross_attention mixer only, not {DEN['mixer']!r}")
if not (DEN["fusion_projection"] and DEN["positioning"] and DEN["swap_mode"] and DEN["footwork"]):
    sys.exit("group_denoiser.py ports the full model only (no ablation switches)")
D, N_HEADS, D_FF = DEN["d_model"], DEN["n_heads"], DEN["d_ff"]
FUSION_HIDDEN = DEN["fusion_hidden"] or 2 * D


def sinusoidal(start, positions, d):
    """pos_encoding::sinusoidal: [positions, d], pe[p, 2i] = sin(p w_i), pe[p, 2i+1] = cos."""
    p = torch.arange(start, start + positions, dtype=torch.float64)[:, None]
    i = torch.arange((d + 1) // 2, dtype=torch.float64)
    a = p * torch.exp(-(2.0 * i) * math.log(10000.0) / d)[None]
    pe = torch.zeros(positions, d, dtype=torch.float64)
    pe[:, 0::2] = torch.sin(a)
    pe[:, 1::2] = torch.cos(a)[:, : d // 2]
    return pe.float()


def dancer_positions(frames, d):
    """pos_encoding::dancer_positions(0..N_MAX, frames, d, N_MAX): [frames N_MAX, d]."""
    time = sinusoidal(0, frames, d)[:, None]
    ids = sinusoidal(0, N_MAX, d)[None]
    return (time + ids).reshape(frames * N_MAX, d)


def sinusoidal_timestep(t, d):
    """timestep::sinusoidal_timestep: [B, d] = [sin(t w_i) | cos(t w_i)]."""
    half = d // 2
    w = torch.exp(-torch.arange(half, dtype=torch.float64) * (math.log(10000.0) / (half - 1)))
    a = t.double()[:, None] * w[None]
    return torch.cat([a.sin(), a.cos()], -1).float()


class TimestepMlp(nn.Module):
    def __init__(self, d):
        super().__init__()
        self.linear = nn.Linear(d, 4 * d)

    def forward(self, t):
        return F.mish(self.linear(sinusoidal_timestep(t, D)))


class SwapEmbedding(nn.Module):
    def __init__(self, d):
        super().__init__()
        self.linear1, self.linear2 = nn.Linear(SWAP_DIMS, d), nn.Linear(d, d)

    def forward(self, code):
        return F.gelu(self.linear2(F.gelu(self.linear1(code))))


class FusionProjection(nn.Module):
    def __init__(self, d, hidden):
        super().__init__()
        self.linear1 = nn.Linear(N_MAX * d, hidden)
        self.linear2 = nn.Linear(hidden, hidden)
        self.linear3 = nn.Linear(hidden, N_MAX * d)

    def forward(self, tokens, mask):
        b, k, d = tokens.shape
        stacked = (tokens * mask).reshape(b, k // N_MAX, N_MAX * d)
        h = F.relu(self.linear2(F.relu(self.linear1(stacked))))
        return self.linear3(h).reshape(b, k, d) * mask


class ConcatSquashLinear(nn.Module):
    def __init__(self, d_in, d_out, d_ctx):
        super().__init__()
        self.layer = nn.Linear(d_in, d_out)
        self.hyper_gate = nn.Linear(d_ctx, d_out)
        self.hyper_bias = nn.Linear(d_ctx, d_out, bias=False)

    def forward(self, x, ctx):
        return self.layer(x) * torch.sigmoid(self.hyper_gate(ctx)) + self.hyper_bias(ctx)


class FootworkAdaptor(nn.Module):
    def __init__(self, hidden):
        super().__init__()
        self.csl1 = ConcatSquashLinear(DIMS, hidden, 2)
        self.csl2 = ConcatSquashLinear(hidden, hidden, 2)
        self.csl3 = ConcatSquashLinear(hidden, DIMS, 2)
        sel = torch.zeros(DIMS)
        for j in LOWER_BODY:
            sel[ROT6D_START + 6 * j:ROT6D_START + 6 * j + 6] = 1.0
        self.register_buffer("sel", sel, persistent=False)

    @staticmethod
    def context(tokens):
        b, k, _ = tokens.shape
        t = k // N_MAX
        root = tokens[..., ROOT_HORIZONTAL[0]:ROOT_HORIZONTAL[0] + 2].reshape(b, t, N_MAX * 2)
        if t < 2:
            return tokens.new_zeros(b, k, 2)
        d = root[:, 1:] - root[:, :-1]
        return torch.cat([root.new_zeros(b, 1, N_MAX * 2), d], 1).reshape(b, k, 2)

    def forward(self, raw):
        ctx = self.context(raw)
        h = F.leaky_relu(self.csl1(raw, ctx), LEAKY_SLOPE)
        h = F.leaky_relu(self.csl2(h, ctx), LEAKY_SLOPE)
        adapted = self.csl3(h, ctx)
        return raw * (1.0 - self.sel) + adapted * self.sel


def self_attention(attn, h, pad):
    """`self_attn(h, h, h)` with key padding `pad` [B, Tk] (True = empty slot) when given."""
    if pad is None:
        return attn(h, h, h)
    b, t, d = h.shape
    k, v = attn.project_kv(h, h)
    o = F.scaled_dot_product_attention(attn.split(attn.q_proj(h)), k, v,
                                       attn_mask=~pad[:, None, None, :])
    return attn.out_proj(o.transpose(1, 2).reshape(b, t, d))


class GroupFilmDecoderLayer(FilmDecoderLayer):
    """`torch_blocks.FilmDecoderLayer` with a self-attention key padding mask (none with 5
    dancers, where it is the parent's forward)."""

    def forward(self, x, cond, kv=None, pad=None):
        if pad is None:
            return super().forward(x, cond, kv=kv)
        x = x + self.film1(self_attention(self.self_attn, self.norm1(x), pad), cond)
        x = x + self.film2(self.cross_attn(self.norm2(x), kv=kv), cond)
        return x + self.film3(self.ff(self.norm3(x)), cond)


class Denormalize(nn.Module):
    def __init__(self):
        super().__init__()
        self.scale = nn.Parameter(torch.ones(DIMS), requires_grad=False)
        self.shift = nn.Parameter(torch.zeros(DIMS), requires_grad=False)


class GroupDenoiser(nn.Module):
    def __init__(self):
        super().__init__()
        self.input = nn.Linear(DIMS + 1, D)
        self.time = TimestepMlp(D)
        self.time_cond = nn.Linear(4 * D, D)
        self.music_in = nn.Linear(MUSIC_DIMS, D)
        self.music_layers = nn.ModuleList(
            EncoderLayer(D, N_HEADS, D_FF) for _ in range(DEN["music_layers"]))
        self.music_pool = nn.Linear(D, D)
        self.null_music = nn.Parameter(torch.zeros(1, 1, D))
        self.swap = SwapEmbedding(D)
        self.fusion = FusionProjection(D, FUSION_HIDDEN)
        self.attn_layers = nn.ModuleList(
            GroupFilmDecoderLayer(D, N_HEADS, D_FF) for _ in range(DEN["n_layers"]))
        self.output = nn.Linear(D, DIMS)
        self.footwork = FootworkAdaptor(DEN["footwork_hidden"])
        self.denorm = Denormalize()
        self.register_buffer("pos", dancer_positions(WINDOW, D)[None], persistent=False)
        self.register_buffer("music_pos", sinusoidal(0, WINDOW, D)[None], persistent=False)

    def prepare(self, music, swap, keep):
        """`GroupDenoiser::prepare(c, [keep; B], project = true)`: each decoder layer's
        cross-attention K/V of [swap token | music tokens] and the FiLM base, [B, 1, d]."""
        b, t, _ = music.shape
        if keep:
            h = self.music_in(music) + self.music_pos[:, :t]
            for l in self.music_layers:
                h = l(h)
            tokens, pooled = h, self.music_pool(h.mean(1, keepdim=True))
        else:
            tokens, pooled = self.null_music.expand(b, t, D), self.null_music.expand(b, 1, D)
        e = self.swap(swap)[:, None]
        memory = torch.cat([e, tokens], 1)
        kv = [l.cross_attn.project_kv(memory, memory) for l in self.attn_layers]
        return kv, pooled + e

    def forward(self, x_t, t, control, mask, pad, prepared):
        """`forward_prepared`: x0 [B, T, 5 x 151] at 0-based timesteps t [B]."""
        kv, film = prepared
        b, frames, _ = x_t.shape
        tokens = x_t.reshape(b, frames * N_MAX, DIMS)
        h = self.input(torch.cat([tokens, control.reshape(b, frames * N_MAX, 1)], 2))
        h = (h + self.pos[:, :frames * N_MAX]) * mask
        h = self.fusion(h, mask)
        cond = film + self.time_cond(self.time(t))[:, None]
        for l, lkv in zip(self.attn_layers, kv):
            h = l(h, cond, kv=lkv, pad=pad) * mask
        out = self.footwork(self.output(h))
        return (out * mask).reshape(b, frames, GROUP_DIMS)


class Cond:
    """A batch's condition (`GroupCond`) with its masks and both prepared branches."""

    def __init__(self, net, music, dancers, swap, control, guided):
        b, t, _ = music.shape
        slot = (torch.arange(N_MAX) < dancers).float()
        self.control = control
        self.mask = slot.repeat(t)[None, :, None].expand(b, t * N_MAX, 1).contiguous()
        self.pad = None if dancers == N_MAX else (slot == 0).repeat(t)[None].expand(b, -1)
        self.full = net.prepare(music, swap, True)
        self.null = net.prepare(music, swap, False) if guided else None


def cosine_alphas_cumprod(timesteps, s=8e-3, max_beta=0.999):
    """schedule::Schedule::new(Cosine, T).alphas_cumprod, float64."""
    f = lambda i: math.cos((i / timesteps + s) / (1 + s) * math.pi / 2) ** 2
    f0, acc, out = f(0), 1.0, []
    for i in range(timesteps):
        beta = min(max(1.0 - (f(i + 1) / f0) / (f(i) / f0), 0.0), max_beta)
        acc *= 1.0 - beta
        out.append(acc)
    return out


def ddim_timesteps(timesteps, steps):
    """sampler::ddim_timesteps: (t, t_next) pairs of int(linspace(-1, T - 1, steps + 1)) reversed."""
    a, b = -1.0, timesteps - 1.0
    ts = [math.trunc(a + (b - a) * i / steps) for i in range(steps + 1)][::-1]
    return list(zip(ts[:-1], ts[1:]))


def sample(net, ac, shape, c, steps, guidance, gen, init=None, cues=(), between=None, eta=ETA):
    """`sample_with`: DDIM, EDGE guidance, hard clean cues, `between` after every step but
    the last (no x0 clamp: mean/std-normalised data)."""
    x = init if init is not None else torch.randn(shape, generator=gen)
    guided = c.null is not None
    for t, tn in ddim_timesteps(len(ac), steps):
        tt = torch.full((shape[0],), float(t))
        pc = net(x, tt, c.control, c.mask, c.pad, c.full)
        if guided:
            pu = net(x, tt, c.control, c.mask, c.pad, c.null)
            x0 = pu + (pc - pu) * guidance
        else:
            x0 = pc
        if tn < 0:
            x = x0
        else:
            a, an = ac[t], ac[tn]
            eps = (x * math.sqrt(1.0 / a) - x0) / math.sqrt(1.0 / a - 1.0)
            sigma = eta * math.sqrt((1.0 - a / an) * (1.0 - an) / (1.0 - a))
            cc = math.sqrt(max(1.0 - an - sigma * sigma, 0.0))
            x = x0 * math.sqrt(an) + eps * cc + torch.randn(shape, generator=gen) * sigma
            if between is not None:
                x = between(x)
        for value, mask in cues:
            x = value * mask + x * (1.0 - mask)
    return x


def roots(n):
    """Channel indices of the root x/y of slots 0..n, [n, 2]."""
    return torch.tensor([[s * DIMS + ch for ch in ROOT_HORIZONTAL] for s in range(n)])


def centroid(frame, n):
    """layout::centroid of one frame [..., 5 x 151] -> [..., 2]."""
    return frame[..., roots(n)].mean(-2)


def shift_roots(frames, n, offset):
    """layout::shift_roots: frames [..., T, 5 x 151] (a copy), offset [..., 2]."""
    out = frames.clone()
    r = roots(n)
    out[..., r] = frames[..., r] + offset[..., None, None, :]
    return out


def permute(frames, perm, inverse):
    """sampler::permute of [T, 5 x 151]: slot s <- dancer perm[s] (or back)."""
    out = frames.clone()
    v = frames.reshape(-1, N_MAX, DIMS)
    o = out.view(-1, N_MAX, DIMS)
    src, dst = (list(range(len(perm))), perm) if inverse else (perm, list(range(len(perm))))
    o[:, dst] = v[:, src]
    return out


def identity_code(n):
    code = torch.zeros(SWAP_DIMS)
    for s in range(n):
        code[s * N_MAX + s] = 1.0
    return code


def music_window(music, start):
    idx = torch.arange(start, start + WINDOW).clamp(max=music.shape[0] - 1)
    return music[idx]


def window_count(frames, window):
    half = window // 2
    return 1 if frames <= window else 1 + -(-(frames - window) // half)


def denormalise(frames, scale, shift, n):
    """Normalised -> raw, slots n.. zero; frames [..., 5 x 151]."""
    out = frames * scale.repeat(N_MAX) + shift.repeat(N_MAX)
    out[..., n * DIMS:] = 0.0
    return out


def lgds(net, ac, music, frames, n, steps, guidance, seed):
    half = WINDOW // 2
    gen = torch.Generator().manual_seed(seed)
    out = []
    identity = list(range(n))
    for w in range(window_count(frames, WINDOW)):
        start = w * half
        if w == 0:
            perm, origin, prefix = identity, torch.zeros(2), None
        else:
            tail = torch.cat(out)[-half:]
            perm = sorted(range(n), key=lambda s: (tail[0, s * DIMS + ROOT_HORIZONTAL[0]].item(), s))
            origin = centroid(tail[0], n)
            prefix = shift_roots(permute(tail, perm, False), n, -origin)
        c = Cond(net, music_window(music, start)[None], n, identity_code(n)[None],
                 torch.zeros(1, WINDOW, N_MAX), guidance != 1.0)
        shape = (1, WINDOW, GROUP_DIMS)
        init, cues = None, []
        if prefix is not None:
            value = torch.zeros(shape)
            value[0, :half] = prefix
            mask = torch.zeros(shape)
            mask[0, :half, :n * DIMS] = 1.0
            a = ac[TIMESTEPS - 1]
            noised = value * math.sqrt(a) + torch.randn(shape, generator=gen) * math.sqrt(1.0 - a)
            fresh = torch.randn(shape, generator=gen)
            init = noised * mask + fresh * (1.0 - mask)
            cues.append((value, mask))
        x = sample(net, ac, shape, c, steps, guidance, gen, init, cues)[0]
        x = shift_roots(permute(x, perm, True), n, origin)
        out.append(x if w == 0 else x[half:])
    return denormalise(torch.cat(out), net.denorm.scale, net.denorm.shift, n)[:frames]


def overwrite_first_halves_rebased(x, n):
    """sampler::overwrite_first_halves_rebased on [L, W, 5 x 151]."""
    if x.shape[0] < 2:
        return x
    half = x.shape[1] // 2
    src = x[:-1, half:]
    out = x.clone()
    out[1:, :half] = shift_roots(src, n, -centroid(src[:, 0], n))
    return out


def rot6d_to_quat(d6):
    """Mat3::from_6d then Mat3::to_quat (Shepperd, w >= 0), float64; [..., 6] -> [..., 4]."""
    b1 = d6[..., :3] / d6[..., :3].norm(dim=-1, keepdim=True).clamp(min=1e-12)
    a2 = d6[..., 3:]
    b2 = a2 - (b1 * a2).sum(-1, keepdim=True) * b1
    b2 = b2 / b2.norm(dim=-1, keepdim=True).clamp(min=1e-12)
    m = torch.stack([b1, b2, torch.cross(b1, b2, dim=-1)], -2)
    m00, m01, m02 = m[..., 0, 0], m[..., 0, 1], m[..., 0, 2]
    m10, m11, m12 = m[..., 1, 0], m[..., 1, 1], m[..., 1, 2]
    m20, m21, m22 = m[..., 2, 0], m[..., 2, 1], m[..., 2, 2]
    tr = m00 + m11 + m22
    s0 = 2.0 * (1.0 + tr).clamp(min=0).sqrt()
    s1 = 2.0 * (1.0 + m00 - m11 - m22).clamp(min=0).sqrt()
    s2 = 2.0 * (1.0 - m00 + m11 - m22).clamp(min=0).sqrt()
    s3 = 2.0 * (1.0 - m00 - m11 + m22).clamp(min=0).sqrt()
    q0 = torch.stack([0.25 * s0, (m21 - m12) / s0, (m02 - m20) / s0, (m10 - m01) / s0], -1)
    q1 = torch.stack([(m21 - m12) / s1, 0.25 * s1, (m01 + m10) / s1, (m02 + m20) / s1], -1)
    q2 = torch.stack([(m02 - m20) / s2, (m01 + m10) / s2, 0.25 * s2, (m12 + m21) / s2], -1)
    q3 = torch.stack([(m10 - m01) / s3, (m02 + m20) / s3, (m12 + m21) / s3, 0.25 * s3], -1)
    c0 = ((tr >= m00) & (tr >= m11) & (tr >= m22))[..., None]
    c1 = ((m00 >= m11) & (m00 >= m22))[..., None]
    c2 = (m11 >= m22)[..., None]
    q = torch.where(c0, q0, torch.where(c1, q1, torch.where(c2, q2, q3)))
    q = q / q.norm(dim=-1, keepdim=True)
    return torch.where(q[..., :1] < 0, -q, q)


def quat_to_rot6d(q):
    w, x, y, z = q.unbind(-1)
    return torch.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
                        2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1)


def slerp(a, b, t):
    """Quat::slerp (shortest arc, normalised-lerp fallback above a dot of 0.9995)."""
    d = (a * b).sum(-1, keepdim=True)
    b = torch.where(d < 0, -b, b)
    d = d.abs()
    omega = d.clamp(max=1.0).acos()
    so = omega.sin()
    lerp = d > 0.9995
    s0 = torch.where(lerp, 1.0 - t, ((1.0 - t) * omega).sin() / so)
    s1 = torch.where(lerp, t.expand_as(d), (t * omega).sin() / so)
    q = s0 * a + s1 * b
    return q / q.norm(dim=-1, keepdim=True)


def stitch(win, n):
    """longform::stitch of [L, W, C] (float64) with 6D groups on slots 0..n."""
    l, w, c = win.shape
    h = w // 2
    out = torch.zeros(w + (l - 1) * h, c, dtype=torch.float64)
    out[:h] = win[0, :h]
    out[(l - 1) * h + h:] = win[l - 1, h:]
    prev, nxt = win[:-1, h:], win[1:, :h]
    wt = torch.linspace(0.0, 1.0, h, dtype=torch.float64)[None, :, None]
    lin = (1.0 - wt) * prev + wt * nxt
    rot = torch.zeros(c, dtype=torch.bool)
    for s in range(n):
        rot[s * DIMS + ROT6D_START:(s + 1) * DIMS] = True
    shape = (l - 1, h, -1, 6)
    qa = rot6d_to_quat(prev[..., rot].reshape(shape))
    qb = rot6d_to_quat(nxt[..., rot].reshape(shape))
    lin[..., rot] = quat_to_rot6d(slerp(qa, qb, wt[..., None])).reshape(l - 1, h, -1)
    out[h:(l - 1) * h + h] = lin.reshape((l - 1) * h, c)
    return out


def parallel(net, ac, music, frames, n, steps, guidance, seed):
    half = WINDOW // 2
    gen = torch.Generator().manual_seed(seed)
    l = window_count(frames, WINDOW)
    c = Cond(net, torch.stack([music_window(music, w * half) for w in range(l)]), n,
             identity_code(n)[None].expand(l, -1), torch.zeros(l, WINDOW, N_MAX), guidance != 1.0)
    win = sample(net, ac, (l, WINDOW, GROUP_DIMS), c, steps, guidance, gen,
                 between=lambda x: overwrite_first_halves_rebased(x, n))
    for w in range(1, l):
        win[w] = shift_roots(win[w], n, centroid(win[w - 1, half], n))
    win = denormalise(win, net.denorm.scale, net.denorm.shift, n)
    out = stitch(win.double(), n).float()
    out[:, n * DIMS:] = 0.0
    return out[:frames]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--reps", type=int, default=int(os.environ.get("DANCEGEN_BENCH_REPS", 3)))
    ap.add_argument("only", nargs="?", default="")
    a = ap.parse_args()
    torch.set_num_threads(int(os.environ.get("OMP_NUM_THREADS", os.cpu_count())))
    torch.manual_seed(0)
    net = GroupDenoiser().eval()
    print(f"pytorch group denoiser parameters: {sum(p.numel() for p in net.parameters())} "
          f"({window_count(FRAMES, WINDOW)} windows of {WINDOW} frames)", file=sys.stderr)
    ac = cosine_alphas_cumprod(TIMESTEPS)
    music = torch.randn(FRAMES, MUSIC_DIMS)
    for name, sampler in [(f"lgds_{DANCERS}x{FRAMES}f", lgds),
                          (f"parallel_{DANCERS}x{FRAMES}f", parallel)]:
        if a.only not in name:
            continue

        def run(steps):
            out = sampler(net, ac, music, FRAMES, DANCERS, steps, GUIDANCE, 0)
            assert out.shape == (FRAMES, GROUP_DIMS), out.shape
            assert torch.isfinite(out).all()
            return out

        with torch.inference_mode():
            run(2)
            ms = []
            for _ in range(a.reps):
                t = time.perf_counter()
                run(STEPS)
                ms.append((time.perf_counter() - t) * 1e3)
        ms.sort()
        print(json.dumps({"impl": "pytorch", "case": name, "steps": STEPS,
                          "median_ms": round(ms[len(ms) // 2], 2), "min_ms": round(ms[0], 2),
                          "reps": a.reps}), flush=True)


if __name__ == "__main__":
    main()
