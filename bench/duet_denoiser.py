"""PyTorch side of `bash bench/duet.sh`: ReactDance's latent diffusion transformer, its BLC
sampler with layer-wise decoupled guidance (LDCFG) and the HFSQ decoder, the same
architecture, shapes, step count and timing as
`crates/dancegen-reactdance/benches/blc_sampling.rs` (a warm-up run with 2 steps, then
`--reps` runs, median and min, one JSON line).

Sizes: `configs/reactdance_small_hfsq.toml` [model.autoencoder] and
`configs/reactdance_small_ldm.toml` [model.denoiser], read at import like the Rust bench does;
missing keys take the defaults of `crates/dancegen-reactdance/src/config.rs`. Both sides print
the denoiser's parameter count to stderr; they must agree.

Architecture (written from `crates/dancegen-reactdance/src/{denoiser,blc,autoencoder,config}.rs`
and the `dancegen-nn` layers they use; random weights; parameter names follow the Rust modules):
- f = 2^down_t frames a token, latent C = num_levels x 3 streams x groups x len(levels) channels
  (level-major), leader tokens 220 f wide, music tokens 35 f wide;
- input Linear(C -> d) + the phase-aligned encoding (`pos_encoding::phase_aligned`:
  [sin(pi k phi), cos(pi k phi)] interleaved, k = 1..d/2, phi = (p mod T)/T);
- timestep: sinusoidal(d) ([sin | cos], w_i = exp(-i ln 1e4 / (d/2 - 1))) -> Linear d -> 4d ->
  Mish, then `time_cond` Linear 4d -> d;
- leader: Linear(220 f -> d) + phase encoding + `leader_layers` post-norm encoder layers (GELU FF,
  PyTorch `TransformerEncoderLayer` semantics): the cross-attention memory; the null branch's
  memory is the learned `null_leader` token expanded to [B, N, d] (the encoder does not run);
- music: LayerNorm(35 f) + Linear(35 f -> d): a FiLM vector per token, added to the timestep's;
  the null branch uses the learned `null_music` vector, [B, 1, d];
- `n_layers` norm-first FiLM decoder layers (self-attention, cross-attention to the memory, GELU
  FF; each branch `x += film_k(c)(branch)`, film = Linear(Mish(c)) -> (scale, shift),
  `x * (scale + 1) + shift`), separate q/k/v/out Linear layers, the scaled dot product in
  `F.scaled_dot_product_attention` (no mask: `causal = false`, BLC's blocks are a batch);
- output Linear d -> C.
- HFSQ decoder (`HfsqAutoencoder::decode`): per stream, sum over levels r of the level's codes x
  s_r (s_r = (L - 1)^-r per FSQ dimension, tiled over the groups), then the T2M-GPT conv decoder
  (`dancegen_nn::conv::ConvDecoder`: Conv1d(code, width, 3) + ReLU, down_t x [Resnet1D of `depth`
  blocks `x + conv2(relu(conv1(relu(x))))` with dilations 3^i reversed, nearest x2 upsample,
  Conv1d(width, width, 3)], Conv1d(width, width, 3) + ReLU, Conv1d(width, out, 3)); the three
  stream outputs concatenated to 151 features.

Sampler (`blc::sample_latent` + `dancegen_nn::diffusion::sample`): the K-token condition cut
into ceil(K / T) blocks of T = block_tokens, the last padded by repeating the last token, all
blocks as one batch; cosine schedule (T = `timesteps`, s = 0.008, beta <= 0.999, tables in
float64); DDIM on EDGE's strided steps (int(linspace(-1, T - 1, steps + 1)) reversed), eta 1;
per step ONE forward of the conditional branch and ONE of the null branch (as Rust, not one
batched forward), `x0 = unc + w (cond - unc)` with w = 1 + s_r on level r's channels, x0 clamped
to [-1, 1]. As in Rust (`LatentDenoiser::prepare`, `PreparedDenoiser`), what does not change over
the steps is computed once per run for both branches: the leader memory, the music FiLM vectors
and every decoder layer's cross-attention keys/values. Then the whole [1, K, C] latent goes
through the decoder (as the Rust bench, which decodes the padded-off latent of K tokens).
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
from torch_blocks import LN_EPS, EncoderLayer, FilmDecoderLayer  # noqa: E402

# DuetFollower::STREAMS / DIMS, DuetLeader::DIMS (crates/dancegen-motion/src/repr/duet.rs), MUSIC_DIMS.
STREAMS = [(0, 90), (90, 142), (142, 151)]
FOLLOWER_DIMS, LEADER_DIMS, MUSIC_DIMS = 151, 220, 35
FRAMES = 2000

_configs = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "configs")


def _table(file, key, defaults):
    with open(os.path.join(_configs, file), "rb") as f:
        return {**defaults, **tomllib.load(f).get("model", {}).get(key, {})}


# Defaults: HfsqAutoencoderConfig::default(), DenoiserConfig::default(), SamplingDefaults::default().
AE = _table("reactdance_small_hfsq.toml", "autoencoder",
            {"width": 128, "depth": 2, "down_t": 2, "groups": 2, "levels": [7, 5, 5, 5],
             "num_levels": 3})
DEN = _table("reactdance_small_ldm.toml", "denoiser",
             {"d_model": 192, "n_layers": 4, "n_heads": 6, "d_ff": 384, "leader_layers": 1,
              "block_tokens": 60, "causal": False, "timesteps": 1000})
STEPS, GUIDANCE, ETA = 10, [2.0, 0.5], 1.0
DILATION_GROWTH = 3  # ConvCodecConfig default (the autoencoder does not override it)

F_TOKEN = 2 ** AE["down_t"]
STREAM_DIM = AE["groups"] * len(AE["levels"])
LEVEL_DIM = len(STREAMS) * STREAM_DIM
LATENT_DIM = AE["num_levels"] * LEVEL_DIM
D, N_HEADS, D_FF = DEN["d_model"], DEN["n_heads"], DEN["d_ff"]
BLOCK = DEN["block_tokens"]


def phase_aligned(n, block, d):
    """pos_encoding::phase_aligned(0, n, block, d): [n, d]."""
    phase = (torch.arange(n, dtype=torch.float64) % block) / block
    k = torch.arange(1, d // 2 + 1, dtype=torch.float64)
    a = math.pi * phase[:, None] * k[None]
    pe = torch.zeros(n, d, dtype=torch.float64)
    pe[:, 0::2] = torch.sin(a)
    pe[:, 1::2] = torch.cos(a)
    return pe.float()


def sinusoidal_timestep(t, d):
    """timestep::sinusoidal_timestep: [B, d] = [sin(t w_i) | cos(t w_i)]."""
    half = d // 2
    w = torch.exp(-torch.arange(half, dtype=torch.float64) * (math.log(10000.0) / (half - 1)))
    a = t.double()[:, None] * w[None]
    return torch.cat([a.sin(), a.cos()], -1).float()


class LatentDenoiser(nn.Module):
    def __init__(self):
        super().__init__()
        leader, music = LEADER_DIMS * F_TOKEN, MUSIC_DIMS * F_TOKEN
        self.input = nn.Linear(LATENT_DIM, D)
        self.time = nn.Module()
        self.time.linear = nn.Linear(D, 4 * D)
        self.time_cond = nn.Linear(4 * D, D)
        self.leader_in = nn.Linear(leader, D)
        self.leader_layers = nn.ModuleList(
            EncoderLayer(D, N_HEADS, D_FF) for _ in range(DEN["leader_layers"]))
        self.null_leader = nn.Parameter(torch.zeros(1, 1, D))
        self.music_norm = nn.LayerNorm(music, eps=LN_EPS)
        self.music_in = nn.Linear(music, D)
        self.null_music = nn.Parameter(torch.zeros(1, 1, D))
        self.layers = nn.ModuleList(
            FilmDecoderLayer(D, N_HEADS, D_FF) for _ in range(DEN["n_layers"]))
        self.output = nn.Linear(D, LATENT_DIM)
        self.causal = bool(DEN["causal"])
        self.register_buffer("pos", phase_aligned(BLOCK, BLOCK, D), persistent=False)

    def prepare(self, leader, music, keep):
        """`LatentDenoiser::prepare(c, [keep; B], Batched, project = true)`: the memory, the music
        FiLM vectors and each decoder layer's cross-attention K/V, once per run and branch."""
        b, n, _ = leader.shape
        if keep:
            memory = self.leader_in(leader) + self.pos[:n]
            for l in self.leader_layers:
                memory = l(memory)
            film = self.music_in(self.music_norm(music))
        else:
            memory = self.null_leader.expand(b, n, D)
            film = self.null_music.expand(b, 1, D)
        kv = [l.cross_attn.project_kv(memory, memory) for l in self.layers]
        return film, kv

    def forward(self, x_t, t, prepared):
        """`forward_prepared`: x0 [B, N, C] at 0-based timesteps t [B]."""
        film, kv = prepared
        n = x_t.shape[1]
        time = self.time_cond(F.mish(self.time.linear(sinusoidal_timestep(t, D))))[:, None]
        cond = film + time
        h = self.input(x_t) + self.pos[:n]
        for l, lkv in zip(self.layers, kv):
            h = l(h, cond, kv=lkv, causal=self.causal)
        return self.output(h)


class ResBlock(nn.Module):
    def __init__(self, w, dil):
        super().__init__()
        self.conv1 = nn.Conv1d(w, w, 3, padding=dil, dilation=dil)
        self.conv2 = nn.Conv1d(w, w, 1)

    def forward(self, x):
        return x + self.conv2(F.relu(self.conv1(F.relu(x))))


class Resnet1D(nn.Module):
    def __init__(self, w, depth):
        super().__init__()
        dil = [DILATION_GROWTH ** i for i in range(depth)][::-1]
        self.blocks = nn.ModuleList(ResBlock(w, d) for d in dil)

    def forward(self, x):
        for b in self.blocks:
            x = b(x)
        return x


class UpBlock(nn.Module):
    def __init__(self, w, depth):
        super().__init__()
        self.resnet = Resnet1D(w, depth)
        self.conv = nn.Conv1d(w, w, 3, padding=1)

    def forward(self, x):
        return self.conv(F.interpolate(self.resnet(x), scale_factor=2, mode="nearest"))


class ConvDecoder(nn.Module):
    """conv::ConvDecoder: [B, T', code] -> [B, T' 2^down_t, out]."""

    def __init__(self, code, out, w, depth, down_t):
        super().__init__()
        self.conv_in = nn.Conv1d(code, w, 3, padding=1)
        self.up = nn.ModuleList(UpBlock(w, depth) for _ in range(down_t))
        self.conv_mid = nn.Conv1d(w, w, 3, padding=1)
        self.conv_out = nn.Conv1d(w, out, 3, padding=1)

    def forward(self, z):
        h = F.relu(self.conv_in(z.transpose(1, 2)))
        for u in self.up:
            h = u(h)
        return self.conv_out(F.relu(self.conv_mid(h))).transpose(1, 2)


class HfsqDecoder(nn.Module):
    """`HfsqAutoencoder::decode` (decoders only; the encoders and the parameter-free FSQ are not
    used at sampling time)."""

    def __init__(self):
        super().__init__()
        self.decoders = nn.ModuleList(
            ConvDecoder(STREAM_DIM, hi - lo, AE["width"], AE["depth"], AE["down_t"])
            for lo, hi in STREAMS)
        for r in range(AE["num_levels"]):
            s = torch.tensor([(l - 1.0) ** -r for l in AE["levels"]] * AE["groups"])
            self.register_buffer(f"scale{r}", s.float(), persistent=False)

    def forward(self, latent):
        ns, sd = len(STREAMS), STREAM_DIM
        outs = []
        for s, dec in enumerate(self.decoders):
            q = sum(latent[..., (r * ns + s) * sd:(r * ns + s + 1) * sd] * getattr(self, f"scale{r}")
                    for r in range(AE["num_levels"]))
            outs.append(dec(q))
        return torch.cat(outs, 2)


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


def level_weights(scales, levels, level_dim):
    """blc::level_guidance as per-channel EDGE weights w = 1 + s_r, or None (conditional only)."""
    s = [scales[r] if r < len(scales) else (scales[-1] if scales else 0.0) for r in range(levels)]
    if all(v == 0.0 for v in s):
        return None
    return torch.tensor([1.0 + s[c // level_dim] for c in range(levels * level_dim)]).float()


def to_blocks(x, block):
    """blc::to_blocks: [1, K, C] -> [ceil(K / T), T, C], the tail padded with the last token."""
    _, k, c = x.shape
    nb = -(-k // block)
    pad = nb * block - k
    if pad:
        x = torch.cat([x, x[:, -1:].expand(1, pad, c)], 1)
    return x.reshape(nb, block, c)


def sample_latent(net, ac, leader, music, steps, guidance, eta=ETA):
    """blc::sample_latent (LongForm::Blc) with the shared DDIM sampler."""
    k = leader.shape[1]
    lb, mb = to_blocks(leader, BLOCK), to_blocks(music, BLOCK)
    nb = lb.shape[0]
    w = level_weights(guidance, AE["num_levels"], LEVEL_DIM)
    full = net.prepare(lb, mb, True)
    null = net.prepare(lb, mb, False) if w is not None else None
    x = torch.randn(nb, BLOCK, LATENT_DIM)
    for t, tn in ddim_timesteps(len(ac), steps):
        tt = torch.full((nb,), float(t))
        pc = net(x, tt, full)
        x0 = pc if w is None else (lambda pu: pu + (pc - pu) * w)(net(x, tt, null))
        x0 = x0.clamp(-1.0, 1.0)
        if tn < 0:
            x = x0
            continue
        a, an = ac[t], ac[tn]
        eps = (x * math.sqrt(1.0 / a) - x0) / math.sqrt(1.0 / a - 1.0)
        sigma = eta * math.sqrt((1.0 - a / an) * (1.0 - an) / (1.0 - a))
        c = math.sqrt(max(1.0 - an - sigma * sigma, 0.0))
        x = x0 * math.sqrt(an) + eps * c + torch.randn_like(x) * sigma
    return x.reshape(1, nb * BLOCK, LATENT_DIM)[:, :k]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--reps", type=int, default=int(os.environ.get("DANCEGEN_BENCH_REPS", 3)))
    ap.add_argument("only", nargs="?", default="")
    a = ap.parse_args()
    torch.set_num_threads(int(os.environ.get("OMP_NUM_THREADS", os.cpu_count())))
    torch.manual_seed(0)
    net = LatentDenoiser().eval()
    dec = HfsqDecoder().eval()
    n = sum(p.numel() for p in net.parameters())
    print(f"pytorch duet denoiser parameters: {n} (HFSQ decoders: "
          f"{sum(p.numel() for p in dec.parameters())})", file=sys.stderr)
    ac = cosine_alphas_cumprod(DEN["timesteps"])
    k = -(-FRAMES // F_TOKEN)
    leader = torch.randn(1, k, LEADER_DIMS * F_TOKEN)
    music = torch.randn(1, k, MUSIC_DIMS * F_TOKEN)
    name = f"blc_ldcfg_{FRAMES}f"
    if a.only not in name:
        return

    def run(steps):
        out = dec(sample_latent(net, ac, leader, music, steps, GUIDANCE))
        assert out.shape == (1, k * F_TOKEN, FOLLOWER_DIMS), out.shape
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
