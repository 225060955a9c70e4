"""PyTorch side of `bash bench/solo.sh`: Lodge++'s PDDM denoiser and reverse residual-shift
process, the same architecture, shapes, step count and timing as
`crates/dancegen-lodgepp/benches/pddm_sampling.rs` (warm-up of 2 steps at the case's batch, then
`--reps` runs, median and min).

Sizes: `configs/lodgepp_small_pddm.toml` [model.pddm], read at import like the Rust bench does
(both print their parameter count to stderr; they must agree).

Architecture (written from `crates/dancegen-lodgepp/src/denoiser.rs`, `foot_refine.rs`,
`kinematics.rs` and the `dancegen-nn` layers they use; random weights, identity normaliser):
- input Linear([d_t; d_p; mask] 303 -> d);
- timestep: sinusoidal(d) -> Linear d -> 4d -> Mish, then Linear 4d -> d;
- music: Linear 35 -> d + sinusoidal positions + `music_layers` post-norm Transformer encoder
  layers (GELU FF, no rotary); CFG's null branch mixes in a learned null token exactly as the
  Rust model does (`enc * keep + null * (1 - keep)` over the 2B windows);
- genre Embedding(genres + 1, d) (last row = null genre), one memory token;
- FiLM vector = time + genre + mean of the music tokens;
- `n_layers` norm-first FiLM decoder layers (self-attention with rotary on the q/k input,
  interleaved pairs; cross-attention to [music tokens; genre token]; GELU FF; each branch
  modulated by `Linear(Mish(c))` -> (scale, shift), `x * (scale + 1) + shift`), separate
  q/k/v/out Linear layers, the scaled dot product in `F.scaled_dot_product_attention`;
- output Linear d -> 151;
- Foot Refine Block: de-normalise x0, rot6d -> matrix (Gram-Schmidt), SMPL 24 FK (the chain and
  offsets of `dancegen_motion::skeleton::Skeleton::smpl24()`), the 4 foot joints, their
  per-frame displacement, soft contact scores, contact labels -> 32 features -> Linear 32 -> d
  -> one FiLM decoder layer (no rotary) from the decoder's hidden states -> Linear d -> 151,
  added to x0.

Sampler (`crates/dancegen-lodgepp/src/sampler.rs`, `dancegen_nn::diffusion::pddm`): ResShift
eta table (T 50, kappa 2, p 0.3), `d_T = d_p + kappa sqrt(eta_T) z`, 50 steps, each ONE batched
forward of [cond; uncond] (2B windows), `x0 = u + w (c - u)` with w = 2, the posterior step,
hard cues written after every step. As in Rust, what does not change between steps is computed
once before the loop (`PddmDenoiser.prepare`): the music encoding (B windows), the memory, the
step-free part of the FiLM vector and each decoder layer's cross-attention keys/values; a
version without this caching did ~35 % more work per step. No penetration guidance (the Rust bench reports that case
alone). The GPT + VQ-VAE stage of the full pipeline is not re-implemented: the issue's
comparison is the denoiser; the end-to-end `dancegen generate` times in solo.sh include it.
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
from torch_blocks import EncoderLayer, FilmDecoderLayer, rotary_tables  # noqa: E402

D_MOTION, MUSIC_DIMS, FOOT_FEATURES = 151, 35, 32
# Sizes from the shipped config's [model.pddm] (the Rust bench reads the same file); the
# defaults are dancegen_lodgepp::config::PddmConfig::default().
CONFIG = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "configs",
                      "lodgepp_small_pddm.toml")
with open(CONFIG, "rb") as f:
    _pddm = {"d_model": 256, "n_layers": 4, "n_heads": 8, "d_ff": 512, "music_layers": 2,
             "window": 128, "foot_refine": True,
             **tomllib.load(f).get("model", {}).get("pddm", {})}
D, N_LAYERS, N_HEADS, D_FF = _pddm["d_model"], _pddm["n_layers"], _pddm["n_heads"], _pddm["d_ff"]
MUSIC_LAYERS, WINDOW = _pddm["music_layers"], _pddm["window"]
assert _pddm["foot_refine"], "the benchmark times the Foot Refine Block"
GENRES = 10
STEPS, GUIDANCE = 50, 2.0
BOUNDARY_FRAMES = 4
ROOT, ROT6D_START = slice(4, 7), 7
CONTACTS = slice(0, 4)
FEET = [7, 8, 10, 11]
CONTACT_HEIGHT = [0.12, 0.12, 0.05, 0.05]
CONTACT_STEP, HEIGHT_SOFTNESS, STEP_SOFTNESS, FPS = 0.01, 0.02, 0.003, 30.0

# Skeleton::smpl24() (crates/dancegen-motion/src/skeleton.rs).
SMPL24_PARENTS = [-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21]
SMPL24_OFFSETS = [
    [0.0, 0.0, 0.0],
    [0.05858135, -0.08228004, -0.01766408],
    [-0.06030973, -0.09051332, -0.01354254],
    [0.00443945, 0.12440352, -0.03838522],
    [0.04345142, -0.38646945, 0.008037],
    [-0.04325663, -0.38368791, -0.00484304],
    [0.00448844, 0.1379564, 0.02682033],
    [-0.01479032, -0.42687458, -0.037428],
    [0.01905555, -0.4200455, -0.03456167],
    [-0.00226458, 0.05603239, 0.00285505],
    [0.04105436, -0.06028581, 0.12204243],
    [-0.03483987, -0.06210566, 0.13032329],
    [-0.0133902, 0.21163553, -0.03346758],
    [0.07170245, 0.11399969, -0.01889817],
    [-0.08295366, 0.11247234, -0.02370739],
    [0.01011321, 0.08893734, 0.05040987],
    [0.12292141, 0.04520509, -0.019046],
    [-0.11322832, 0.04685326, -0.00847207],
    [0.2553319, -0.01564902, -0.02294649],
    [-0.26012748, -0.01436928, -0.03126873],
    [0.26570925, 0.01269811, -0.00737473],
    [-0.26910836, 0.00679372, -0.00602676],
    [0.08669055, -0.01063603, -0.01559429],
    [-0.0887537, -0.00865157, -0.01010708],
]


def sinusoidal_positions(t, d):
    """pe[p, 2i] = sin(p w_i), pe[p, 2i + 1] = cos(p w_i), w_i = 10000^(-2i/d)."""
    p = torch.arange(t, dtype=torch.float64)[:, None]
    w = torch.exp(-(2.0 * torch.arange(d // 2, dtype=torch.float64)) * math.log(10000.0) / d)
    pe = torch.zeros(t, d, dtype=torch.float64)
    pe[:, 0::2] = torch.sin(p * w)
    pe[:, 1::2] = torch.cos(p * w)
    return pe.float()


def timestep_embedding(t, d):
    half = d // 2
    f = torch.exp(torch.arange(half, dtype=torch.float64) * -(math.log(10000.0) / (half - 1)))
    e = t.double()[:, None] * f[None]
    return torch.cat([e.sin(), e.cos()], -1).float()


def rot6d_to_matrix(d6):
    """[N, 6] -> [N, 3, 3], rows b1, b2, b3 (Gram-Schmidt), as dancegen_nn::loss."""
    b1 = F.normalize(d6[:, :3], dim=1, eps=1e-12)
    a2 = d6[:, 3:]
    b2 = F.normalize(a2 - b1 * (b1 * a2).sum(1, keepdim=True), dim=1, eps=1e-12)
    return torch.stack([b1, b2, torch.cross(b1, b2, dim=1)], 1)


def forward_kinematics(rot, root, offsets):
    """World joints [N, J, 3] from local matrices [N, J, 3, 3] and root [N, 3]."""
    world_rot, world_pos = [], []
    for k, p in enumerate(SMPL24_PARENTS):
        local = rot[:, k]
        if p < 0:
            world_rot.append(local)
            world_pos.append(root)
        else:
            world_pos.append(world_pos[p] + world_rot[p] @ offsets[k])
            world_rot.append(world_rot[p] @ local)
    return torch.stack(world_pos, 1)


class FootRefine(nn.Module):
    def __init__(self, d, h, ff):
        super().__init__()
        self.features = nn.Linear(FOOT_FEATURES, d)
        self.layer = FilmDecoderLayer(d, h, ff)
        self.output = nn.Linear(d, D_MOTION)
        nn.init.zeros_(self.output.weight)
        nn.init.zeros_(self.output.bias)
        self.register_buffer("offsets", torch.tensor(SMPL24_OFFSETS, dtype=torch.float32))
        self.register_buffer("height", torch.tensor(CONTACT_HEIGHT))

    def foot_features(self, raw):
        b, t, _ = raw.shape
        j = len(SMPL24_PARENTS)
        mats = rot6d_to_matrix(raw[..., ROT6D_START:ROT6D_START + 6 * j].reshape(b * t * j, 6))
        joints = forward_kinematics(mats.reshape(b * t, j, 3, 3), raw[..., ROOT].reshape(b * t, 3),
                                    self.offsets).reshape(b, t, j, 3)
        f = joints[:, :, FEET]
        step = torch.cat([torch.zeros_like(f[:, :1]), f[:, 1:] - f[:, :-1]], 1)
        low = torch.sigmoid((self.height - f[..., 2]) / HEIGHT_SOFTNESS)
        speed = step.pow(2).sum(3).sqrt()
        still = torch.sigmoid((CONTACT_STEP - speed) / STEP_SOFTNESS)
        return torch.cat([f.reshape(b, t, 12), step.reshape(b, t, 12) * FPS, low * still,
                          raw[..., CONTACTS]], 2)

    def forward(self, h, x0_main, cond, scale, shift):
        tokens = self.features(self.foot_features(x0_main * scale + shift))
        return self.output(self.layer(h, cond, memory=tokens))


class PddmDenoiser(nn.Module):
    def __init__(self):
        super().__init__()
        self.input = nn.Linear(2 * D_MOTION + 1, D)
        self.time = nn.Linear(D, 4 * D)
        self.time_cond = nn.Linear(4 * D, D)
        self.music_in = nn.Linear(MUSIC_DIMS, D)
        self.music_layers = nn.ModuleList(EncoderLayer(D, N_HEADS, D_FF) for _ in range(MUSIC_LAYERS))
        self.null_music = nn.Parameter(torch.zeros(1, 1, D))
        self.genre = nn.Embedding(GENRES + 1, D)
        self.layers = nn.ModuleList(FilmDecoderLayer(D, N_HEADS, D_FF) for _ in range(N_LAYERS))
        self.output = nn.Linear(D, D_MOTION)
        self.refine = FootRefine(D, N_HEADS, D_FF)
        self.register_buffer("scale", torch.ones(D_MOTION))
        self.register_buffer("shift", torch.zeros(D_MOTION))
        self.register_buffer("music_pos", sinusoidal_positions(WINDOW, D))
        cos, sin = rotary_tables(WINDOW, D)
        self.register_buffer("rot_cos", cos)
        self.register_buffer("rot_sin", sin)

    def prepare(self, music, genre, keep):
        """What stays the same over the denoising steps (as `PddmDenoiser::prepare` in Rust):
        the music encoded once for the B windows of `music`, the memory of the 2B = len(keep)
        windows (`enc * keep + null * (1 - keep)`, genre token), the step-free part of the FiLM
        vector, and every decoder layer's cross-attention keys/values of the memory."""
        b, frames, _ = music.shape
        enc = self.music_in(music) + self.music_pos[:frames]
        for l in self.music_layers:
            enc = l(enc)
        enc = enc.repeat(len(keep) // b, 1, 1)
        null = self.null_music.expand(len(keep), frames, D)
        k = keep[:, None, None]
        mixed = enc * k + null * (1 - k)
        g = self.genre(torch.where(keep > 0, genre, torch.full_like(genre, GENRES)))[:, None]
        memory = torch.cat([mixed, g], 1)
        kv = [l.cross_attn.project_kv(memory, memory) for l in self.layers]
        return memory, g[:, 0] + mixed.mean(1), kv

    def forward(self, x_t, t, prims, mask, prepared):
        memory, film_static, kv = prepared
        frames = x_t.shape[1]
        film = self.time_cond(F.mish(self.time(timestep_embedding(t, D)))) + film_static
        rotary = (self.rot_cos[:, :frames], self.rot_sin[:, :frames])
        h = self.input(torch.cat([x_t, prims, mask], 2))
        for l, lkv in zip(self.layers, kv):
            h = l(h, film, memory=memory, kv=lkv, rotary=rotary)
        main = self.output(h)
        return main + self.refine(h, main, film, self.scale, self.shift)


def resshift_eta(steps=STEPS, kappa=2.0, p=0.3, eta_t=0.999):
    """dancegen_nn::diffusion::pddm::ResidualShiftConfig::lodgepp().init()."""
    eta_1 = min((0.04 / kappa) ** 2, 1e-3)
    b0 = math.exp(math.log(eta_t / eta_1) / (2.0 * (steps - 1)))
    eta = [0.0]
    for i in range(1, steps + 1):
        beta = ((i - 1) / (steps - 1)) ** p * (steps - 1)
        eta.append((math.sqrt(eta_1) * b0 ** beta) ** 2)
    return eta, kappa


def strided(big_t, n):
    n = max(1, min(n, big_t))
    v = []
    for i in range(n):
        s = big_t - round(i * big_t / n)
        if not v or v[-1] != s:
            v.append(s)
    return v


def sample_windows(net, cond, cues, steps, w=GUIDANCE):
    """sampler.rs::sample_windows with hard cues, guidance w, no penetration guidance."""
    music, genre, prims, mask = cond
    cue_v, cue_m = cues
    after = lambda d: cue_v * cue_m + d * (1 - cue_m)
    eta, kappa = resshift_eta()
    big_t = len(eta) - 1
    b = prims.shape[0]
    d = after(prims + torch.randn_like(prims) * (kappa * math.sqrt(eta[big_t])))
    genre2 = torch.cat([genre, genre])
    prims2, mask2 = torch.cat([prims, prims]), torch.cat([mask, mask])
    keep = torch.cat([torch.ones(b), torch.zeros(b)])
    prepared = net.prepare(music, genre2, keep)
    ts = strided(big_t, steps)
    for i, t in enumerate(ts):
        s = ts[i + 1] if i + 1 < len(ts) else 0
        tt = torch.full((2 * b,), float(t - 1))
        both = net(torch.cat([d, d]), tt, prims2, mask2, prepared)
        c, u = both[:b], both[b:]
        x0 = u + (c - u) * w
        noise = torch.randn_like(d)
        if s == 0:
            d = x0
        else:
            e, es = eta[t], eta[s]
            a = e - es
            d = d * (es / e) + x0 * (a / e) + noise * (kappa * math.sqrt(es * a / e))
        d = after(d)
    return d


def inputs(b, n=WINDOW):
    mask = torch.zeros(b, n, 1)
    for f in list(range(8)) + list(range(n // 2 - 4, n // 2 + 4)) + list(range(n - 8, n)):
        mask[:, f] = 1.0
    prims = torch.randn(b, n, D_MOTION) * mask
    cue_m = torch.zeros(b, n, D_MOTION)
    cue_m[:, :BOUNDARY_FRAMES] = 1.0
    cue_m[:, n - BOUNDARY_FRAMES:] = 1.0
    cond = (torch.randn(b, n, MUSIC_DIMS), torch.arange(b) % GENRES, prims, mask)
    return cond, (prims, cue_m)


def timed(name, reps, warm_up, f):
    warm_up()
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
    ap.add_argument("--reps", type=int, default=int(os.environ.get("DANCEGEN_BENCH_REPS", 3)))
    ap.add_argument("--reps-long", type=int,
                    default=int(os.environ.get("DANCEGEN_BENCH_REPS_LONG", 1)))
    ap.add_argument("only", nargs="?", default="")
    a = ap.parse_args()
    torch.set_num_threads(int(os.environ.get("OMP_NUM_THREADS", os.cpu_count())))
    torch.manual_seed(0)
    net = PddmDenoiser().eval()
    n = sum(p.numel() for p in net.parameters()) + net.scale.numel() + net.shift.numel()
    print(f"pytorch PDDM parameters (+ 302 normaliser values): {n}", file=sys.stderr)
    cases = [("pddm50_cfg_1024f_b8", math.ceil(1024 / WINDOW), a.reps),
             ("pddm50_cfg_5min_b71", math.ceil(9000 / WINDOW), a.reps_long)]
    with torch.inference_mode():
        for name, b, reps in cases:
            if a.only not in name:
                continue
            cond, cues = inputs(b)
            timed(name, reps, lambda: sample_windows(net, cond, cues, 2),
                  lambda: sample_windows(net, cond, cues, STEPS))


if __name__ == "__main__":
    main()
