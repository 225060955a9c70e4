"""PyTorch side of `bash bench/holistic.sh`: the holistic (SoulNet) system's generation of 60 s
(1800 frames) of dance, the same networks, sizes, window layout, decoding steps and timing as
`crates/dancegen-soulnet/benches/holistic_sampling.rs`, which times
`dancegen_soulnet::pipeline::generate` (a warm-up run with 2 steps, then `--reps` runs, median
and min, one JSON line).

Sizes: `model.toml` of $HOLISTIC_MODEL (default models/soulnet-small) [vq] [mmr] [generator]
[sampling] when it exists, otherwise `configs/soulnet_small_vq.toml` [model],
`configs/soulnet_small_mmr.toml` [model], `configs/soulnet_small_generator.toml`
[model.generator] with `SamplingDefaults::for_window` (overlap = window / 4), as the Rust bench
reads them; missing keys take the defaults of `crates/dancegen-soulnet/src/config.rs`. Both
sides print every network's parameter count and the forward counts to stderr; they must agree
(the forward counts are also in the JSON line, and bench/holistic.sh compares them).

Networks (written from `crates/dancegen-soulnet/src/{pipeline,generator,config,bundle}.rs` and
`crates/dancegen-nn/src/{masked,residual_transformer,retrieval,part_autoencoder,conv,
transformer,attention,pos_encoding}.rs`; random weights, parameter names follow the Rust
modules):
- sinusoidal positions `pos_encoding::sinusoidal`: [p, 2i] = sin(p w_i), [p, 2i + 1] =
  cos(p w_i), w_i = exp(-2i ln 1e4 / d);
- masked transformer (`MaskedTransformer`, parts = 3, d_frame = fpt x 35): token embedding
  (vocab + 1 ids, the last is [MASK]) + the part context (time positions of a part block
  repeated for the 3 parts + learned part embedding + Linear(d_frame -> d) of each token's music
  frames, added to all 3 parts), a Linear(d_cond -> d) condition token in front, `n_layers`
  post-norm encoder layers (`torch_blocks.EncoderLayer`: PyTorch TransformerEncoderLayer
  semantics, exact GELU FF, separate q/k/v/out Linear layers, `F.scaled_dot_product_attention`),
  head Linear(d -> vocab) on the token outputs;
- residual transformer (`ResidualTransformer`): the part context + the sum of the embeddings of
  levels < j (one Embedding per input level) + a level embedding, the condition token,
  `residual_layers` post-norm layers, one head per predicted level;
- MMR music encoder (`retrieval::SequenceEncoder`): Linear(35 -> d), a learned summary token in
  front, sinusoidal positions over the T + 1 tokens, `n_layers` **pre-norm** (norm_first) GELU
  encoder layers, Linear(d -> latent) of the summary token;
- part autoencoder decoding (`PartAutoencoder::decode`): per part the sum over levels of the
  codebook rows of its indices (HRVQ `decode_indices`), concatenated to [1, T', 3 code_dim],
  then the T2M-GPT conv decoder (`conv::ConvDecoder`: Conv1d(3 code_dim, width, 3) + ReLU,
  down_t x [Resnet1D of `depth` blocks x + conv2(relu(conv1(relu(x)))) with dilations
  growth^i reversed, nearest x2 upsample, Conv1d(width, width, 3)], Conv1d(width, width, 3) +
  ReLU, Conv1d(width, 675, 3)); then the normaliser's inverse in float64.

Sampling (`pipeline::generate`): n = ceil(1800 / fpt) tokens per part; windows of w =
window_tokens, starts from `window_starts` (each new window `overlap` tokens before the end of
the last, the last one ending at n). Per window: the window's music frames through the MMR
music encoder (the clip condition, [1, latent]) and as per-token frames [1, w, fpt x 35]; the
tokens already made are given as known (inpainting); then `MaskedTransformer::sample_with`:
`steps` iterations, each re-masking the least confident free positions
(n = max(1, round(cos(pi/2 s/(steps - 1)) free)), known positions never), ONE forward of a
batch of 2: the conditional row and the unconditional one (condition and frames zeroed), as
Rust does since commit 8f8f102; logits u + scale (c - u), softmax confidence, top
ceil((1 - thres) V) codes drawn by Gumbel-max at the temperature, unmasked positions'
confidence 1e5; then `ResidualTransformer::sample`: levels 1..Q one after the other, one
batch-2 forward each (residual guidance scale), top-k Gumbel at the residual temperature. The new positions' tokens are kept; after the last window all
tokens are decoded at once.

What PyTorch does its own way (same shapes and forwards, idiomatic code): the sinusoidal
position tables are computed once per length and cached (Rust recomputes them on the host at
every forward); the top-k Gumbel draw runs vectorised over every position of the window with
`torch.topk` and picks the masked ones (MoMask's code; Rust sorts and draws only at the masked
positions on the host); the codebook lookup skips the negative-index masking (no index is
negative here).
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
from torch_blocks import LN_EPS, Attention, EncoderLayer, Mlp  # noqa: E402

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
FRAMES = 1800
MUSIC_DIMS = 35
TOTAL_DIMS = 675  # layout::TOTAL_DIMS (body 263 + hands 360 + face 52)
PARTS = 3

# config.rs defaults.
VQ_DEFAULTS = {"quantizer": "hrvq", "num_quantizers": 6, "nb_code": 512, "code_dim": 128,
               "width": 256, "depth": 2, "down_t": 2, "dilation_growth_rate": 3}
MMR_DEFAULTS = {"d_model": 128, "n_layers": 2, "n_heads": 4, "d_ff": 256, "latent_dim": 256}
GEN_DEFAULTS = {"d_model": 256, "n_layers": 4, "n_heads": 4, "d_ff": 768, "residual_layers": 3,
                "music": "clip_and_frames", "window_tokens": 32}
SAMPLING_DEFAULTS = {"steps": 18, "cond_scale": 4.0, "temperature": 1.0,
                     "topk_filter_thres": 0.9, "residual_cond_scale": 5.0,
                     "residual_temperature": 0.8, "overlap_tokens": 8}


def _model_table(file, sub=None):
    with open(os.path.join(ROOT, "configs", file), "rb") as f:
        t = dict(tomllib.load(f)["model"])
    t.pop("kind", None)
    return t[sub] if sub else t


def load_config():
    """(vq, mmr, generator, sampling, source) as the Rust bench's `bundle_config`."""
    model = os.environ.get("HOLISTIC_MODEL", os.path.join(ROOT, "models", "soulnet-small"))
    path = os.path.join(model, "model.toml")
    if os.path.isfile(path):
        with open(path, "rb") as f:
            doc = tomllib.load(f)
        vq, mmr, gen = doc["vq"], doc["mmr"], doc["generator"]
        sampling = {**SAMPLING_DEFAULTS, **doc.get("sampling", {})}
        source = path
    else:
        vq = _model_table("soulnet_small_vq.toml")
        mmr = _model_table("soulnet_small_mmr.toml")
        gen = _model_table("soulnet_small_generator.toml", "generator")
        w = gen.get("window_tokens", GEN_DEFAULTS["window_tokens"])
        sampling = {**SAMPLING_DEFAULTS, "overlap_tokens": max(w // 4, 1)}
        source = "configs/soulnet_small_{vq,mmr,generator}.toml"
    return ({**VQ_DEFAULTS, **vq}, {**MMR_DEFAULTS, **mmr}, {**GEN_DEFAULTS, **gen}, sampling,
            source)


VQ, MMR, GEN, SAMPLING, SOURCE = load_config()
FPT = 2 ** VQ["down_t"]
LEVELS = 1 if VQ["quantizer"] == "vq" else VQ["num_quantizers"]
D_FRAME = FPT * MUSIC_DIMS if GEN["music"] == "clip_and_frames" else 0

_pos_cache = {}


def sinusoidal(positions, d):
    """pos_encoding::sinusoidal(0, positions, d) [positions, d], cached per shape."""
    key = (positions, d)
    if key not in _pos_cache:
        p = torch.arange(positions, dtype=torch.float64)[:, None]
        i = torch.arange((d + 1) // 2, dtype=torch.float64)[None]
        a = p * torch.exp(-2.0 * i * math.log(10000.0) / d)
        pe = torch.zeros(positions, d, dtype=torch.float64)
        pe[:, 0::2] = torch.sin(a)
        pe[:, 1::2] = torch.cos(a)[:, : d // 2]
        _pos_cache[key] = pe.float()
    return _pos_cache[key]


class PartContext(nn.Module):
    """masked::part_context: time positions per part block + part embedding + per-time music."""

    def __init__(self, d, parts, d_frame):
        super().__init__()
        self.parts = parts
        self.part_emb = nn.Embedding(parts, d) if parts > 1 else None
        self.frame_proj = nn.Linear(d_frame, d) if d_frame > 0 else None

    def forward(self, b, length, d, frame):
        t = length // self.parts
        ctx = sinusoidal(t, d).repeat(self.parts, 1)[None].expand(b, length, d)
        if self.part_emb is not None:
            ctx = ctx + self.part_emb.weight.repeat_interleave(t, 0)[None]
        if self.frame_proj is not None and frame is not None:
            ctx = ctx + self.frame_proj(frame).repeat(1, self.parts, 1)
        return ctx


class Counted(nn.Module):
    """Counts forwards and records their input shapes (the work check against Rust)."""

    def __init__(self):
        super().__init__()
        self.calls = 0
        self.shapes = set()

    def count(self, shape):
        self.calls += 1
        self.shapes.add(tuple(shape))


class MaskedTransformer(Counted):
    def __init__(self, vocab, d, layers, heads, ff, d_cond, parts, d_frame):
        super().__init__()
        self.vocab, self.d = vocab, d
        self.tok_emb = nn.Embedding(vocab + 1, d)
        self.cond_proj = nn.Linear(d_cond, d)
        self.layers = nn.ModuleList(EncoderLayer(d, heads, ff) for _ in range(layers))
        self.head = nn.Linear(d, vocab)
        self.ctx = PartContext(d, parts, d_frame)

    def forward(self, tokens, cond, frame):
        """Logits [B, T, vocab] of tokens [B, T] under cond [B, d_cond] and frame [B, T/3, df]."""
        self.count(tokens.shape)
        b, t = tokens.shape
        x = self.tok_emb(tokens) + self.ctx(b, t, self.d, frame)
        h = torch.cat([self.cond_proj(cond)[:, None], x], 1)
        for layer in self.layers:
            h = layer(h)
        return self.head(h[:, 1:])


class ResidualTransformer(Counted):
    def __init__(self, vocab, levels, d, layers, heads, ff, d_cond, parts, d_frame):
        super().__init__()
        n = levels - 1
        self.vocab, self.d, self.levels = vocab, d, levels
        self.tok_emb = nn.ModuleList(nn.Embedding(vocab, d) for _ in range(n))
        self.level_emb = nn.Embedding(n, d)
        self.cond_proj = nn.Linear(d_cond, d)
        self.ctx = PartContext(d, parts, d_frame)
        self.layers = nn.ModuleList(EncoderLayer(d, heads, ff) for _ in range(layers))
        self.heads = nn.ModuleList(nn.Linear(d, vocab) for _ in range(n))

    def forward(self, tokens, level, cond, frame):
        """Logits [B, L, vocab] of level `level` from tokens [B, L, Q] (levels < level read)."""
        self.count(tokens.shape)
        b, length, _ = tokens.shape
        x = self.ctx(b, length, self.d, frame)
        for q in range(level):
            x = x + self.tok_emb[q](tokens[:, :, q])
        x = x + self.level_emb.weight[level - 1]
        h = torch.cat([self.cond_proj(cond)[:, None], x], 1)
        for layer in self.layers:
            h = layer(h)
        return self.heads[level - 1](h[:, 1:])


class PreNormEncoderLayer(nn.Module):
    """transformer::EncoderLayer with norm_first (the MMR encoders), GELU."""

    def __init__(self, d, h, ff):
        super().__init__()
        self.self_attn, self.ff = Attention(d, h), Mlp(d, ff)
        self.norm1, self.norm2 = nn.LayerNorm(d, eps=LN_EPS), nn.LayerNorm(d, eps=LN_EPS)

    def forward(self, x):
        h = self.norm1(x)
        x = x + self.self_attn(h, h, h)
        return x + self.ff(self.norm2(x))


class SequenceEncoder(Counted):
    """retrieval::SequenceEncoder (the MMR music encoder)."""

    def __init__(self, input_dim, d, layers, heads, ff, latent):
        super().__init__()
        self.embed = nn.Linear(input_dim, d)
        self.summary = nn.Parameter(torch.randn(1, 1, d) * 0.02)
        self.layers = nn.ModuleList(PreNormEncoderLayer(d, heads, ff) for _ in range(layers))
        self.head = nn.Linear(d, latent)

    def forward(self, x):
        self.count(x.shape)
        b, t, _ = x.shape
        h = self.embed(x)
        d = h.shape[2]
        h = torch.cat([self.summary.expand(b, 1, d), h], 1) + sinusoidal(t + 1, d)
        for layer in self.layers:
            h = layer(h)
        return self.head(h[:, 0])


class ResBlock(nn.Module):
    def __init__(self, w, dil):
        super().__init__()
        self.conv1 = nn.Conv1d(w, w, 3, padding=dil, dilation=dil)
        self.conv2 = nn.Conv1d(w, w, 1)

    def forward(self, x):
        return x + self.conv2(F.relu(self.conv1(F.relu(x))))


class UpBlock(nn.Module):
    def __init__(self, w, depth, growth):
        super().__init__()
        dil = [growth ** i for i in range(depth)][::-1]
        self.resnet = nn.ModuleList(ResBlock(w, d) for d in dil)
        self.conv = nn.Conv1d(w, w, 3, padding=1)

    def forward(self, x):
        for blk in self.resnet:
            x = blk(x)
        return self.conv(F.interpolate(x, scale_factor=2, mode="nearest"))


class ConvDecoder(Counted):
    """conv::ConvDecoder: [B, T', code] -> [B, T' 2^down_t, out]."""

    def __init__(self, code, out, w, depth, down_t, growth):
        super().__init__()
        self.conv_in = nn.Conv1d(code, w, 3, padding=1)
        self.up = nn.ModuleList(UpBlock(w, depth, growth) for _ in range(down_t))
        self.conv_mid = nn.Conv1d(w, w, 3, padding=1)
        self.conv_out = nn.Conv1d(w, out, 3, padding=1)

    def forward(self, z):
        self.count(z.shape)
        h = F.relu(self.conv_in(z.transpose(1, 2)))
        for u in self.up:
            h = u(h)
        return self.conv_out(F.relu(self.conv_mid(h))).transpose(1, 2)


class PartDecoder(nn.Module):
    """PartAutoencoder::decode: HRVQ codebook sums per part, then the conv decoder."""

    def __init__(self):
        super().__init__()
        d = VQ["code_dim"]
        # codebook[level][part], buffers as Rust's RunningState (not parameters).
        for lv in range(LEVELS):
            for p in range(PARTS):
                self.register_buffer(f"codebook_{lv}_{p}", torch.randn(VQ["nb_code"], d),
                                     persistent=False)
        self.decoder = ConvDecoder(PARTS * d, TOTAL_DIMS, VQ["width"], VQ["depth"],
                                   VQ["down_t"], VQ["dilation_growth_rate"])

    def forward(self, idx):
        """idx [1, 3 T', Q] -> [1, T' fpt, 675]."""
        t = idx.shape[1] // PARTS
        codes = [sum(F.embedding(idx[:, p * t:(p + 1) * t, lv], getattr(self, f"codebook_{lv}_{p}"))
                     for lv in range(idx.shape[2]))
                 for p in range(PARTS)]
        return self.decoder(torch.cat(codes, 2))


class Holistic(nn.Module):
    def __init__(self):
        super().__init__()
        lat = MMR["latent_dim"]
        g = GEN
        self.masked = MaskedTransformer(VQ["nb_code"], g["d_model"], g["n_layers"], g["n_heads"],
                                        g["d_ff"], lat, PARTS, D_FRAME)
        self.residual = (ResidualTransformer(VQ["nb_code"], LEVELS, g["d_model"],
                                             g["residual_layers"], g["n_heads"], g["d_ff"], lat,
                                             PARTS, D_FRAME) if LEVELS > 1 else None)
        self.mmr_music = SequenceEncoder(MUSIC_DIMS, MMR["d_model"], MMR["n_layers"],
                                         MMR["n_heads"], MMR["d_ff"], lat)
        self.vq = PartDecoder()
        self.register_buffer("mean", torch.zeros(TOTAL_DIMS, dtype=torch.float64), persistent=False)
        self.register_buffer("std", torch.ones(TOTAL_DIMS, dtype=torch.float64), persistent=False)


def window_starts(n, w, overlap):
    """pipeline::window_starts."""
    if n <= w:
        return [0]
    starts = [0]
    step = w - min(overlap, w - 1)
    while starts[-1] + w < n:
        starts.append(min(starts[-1] + step, n - w))
    return starts


def topk_gumbel(logits, keep, temperature, gen):
    """masked::gumbel_top_k for every row of logits [N, V] at once: the top `keep` codes, Gumbel-max
    at `temperature` (float64 noise and values, as Rust)."""
    val, idx = logits.topk(keep, -1)
    u = torch.rand(val.shape, generator=gen, dtype=torch.float64).clamp(1e-20, 1.0 - 1e-12)
    g = -torch.log(-torch.log(u))
    pick = (val.double() / max(temperature, 1e-6) + g).argmax(-1, keepdim=True)
    return idx.gather(-1, pick)[:, 0]


def keep_count(thres, v):
    return min(max(math.ceil((1.0 - thres) * v), 1), v)


def masked_sample(net, cond, frame, length, known, s, gen):
    """MaskedTransformer::sample_with for one row (B = 1)."""
    v, mask_id = net.vocab, net.vocab
    given = known >= 0
    ids = torch.where(given, known.clamp(max=v - 1), torch.full_like(known, mask_id))
    scores = torch.where(given, torch.full((length,), math.inf, dtype=torch.float64),
                         torch.zeros(length, dtype=torch.float64))
    free = length - int(given.sum())
    uncond = torch.zeros_like(cond)
    frame_uncond = torch.zeros_like(frame) if frame is not None else None
    keep = keep_count(s["topk_filter_thres"], v)
    steps = max(s["steps"], 1)
    for st in range(steps):
        if free == 0:
            break
        frac = 0.0 if steps == 1 else st / (steps - 1)
        # Rust's f64::round (half away from zero) on a non-negative value.
        n_mask = max(math.floor(math.cos(frac * math.pi / 2) * free + 0.5), 1)
        order = torch.argsort(scores, stable=True)
        is_mask = torch.zeros(length, dtype=torch.bool)
        is_mask[order[:min(n_mask, free)]] = True
        ids = ids.masked_fill(is_mask, mask_id)
        if s["cond_scale"] == 1.0:
            logits = net(ids[None], cond, frame)[0]
        else:
            # Conditional and unconditional rows in one batch of 2, as Rust (since 8f8f102).
            both = net(torch.stack([ids, ids]), torch.cat([cond, uncond]),
                       torch.cat([frame, frame_uncond]) if frame is not None else None)
            c, u = both[0], both[1]
            logits = u + (c - u) * s["cond_scale"]
        probs = logits.softmax(-1)
        pred = topk_gumbel(logits, keep, s["temperature"], gen)
        conf = probs.gather(-1, pred[:, None])[:, 0].double()
        ids = torch.where(is_mask, pred, ids)
        scores = torch.where(is_mask, conf,
                             torch.where(torch.isfinite(scores), torch.full_like(scores, 1e5),
                                         scores))
    return ids


def residual_sample(net, base, cond, frame, s, gen):
    """ResidualTransformer::sample for one row: [L] -> [L, Q]."""
    length, q = base.shape[0], net.levels
    ids = torch.zeros(length, q, dtype=torch.long)
    ids[:, 0] = base
    uncond = torch.zeros_like(cond)
    frame_uncond = torch.zeros_like(frame) if frame is not None else None
    keep = keep_count(s["topk_filter_thres"], net.vocab)
    for level in range(1, q):
        if s["residual_cond_scale"] == 1.0:
            logits = net(ids[None], level, cond, frame)[0]
        else:
            both = net(torch.stack([ids, ids]), level, torch.cat([cond, uncond]),
                       torch.cat([frame, frame_uncond]) if frame is not None else None)
            c, u = both[0], both[1]
            logits = u + (c - u) * s["residual_cond_scale"]
        ids[:, level] = topk_gumbel(logits, keep, s["residual_temperature"], gen)
    return ids


def window_condition(m, music, frames, start, length):
    """pipeline::window_condition: (clip [1, latent], frames [1, len / fpt, fpt 35] or None)."""
    idx = torch.arange(start, start + length).clamp(max=frames - 1)
    win = music[idx][None]
    clip = m.mmr_music(win)
    fr = win.reshape(1, length // FPT, FPT * MUSIC_DIMS) if D_FRAME > 0 else None
    return clip, fr


def generate(m, music, s, seed=0):
    """pipeline::generate: music [frames, 35] -> rows [frames, 675] (and the window count)."""
    frames = music.shape[0]
    n = -(-frames // FPT)
    w = min(GEN["window_tokens"], n)
    starts = window_starts(n, w, s["overlap_tokens"])
    tokens = torch.full((PARTS, n, LEVELS), -1, dtype=torch.long)
    made = 0
    for k, st in enumerate(starts):
        gen = torch.Generator().manual_seed(seed * 1000003 + k)
        clip, fr = window_condition(m, music, frames, st * FPT, w * FPT)
        old = torch.arange(st, st + w) < made  # [w], the same for every part
        known = torch.where(old[None], tokens[:, st:st + w, 0], -1).reshape(PARTS * w)
        base = masked_sample(m.masked, clip, fr, PARTS * w, known, s, gen)
        if m.residual is not None:
            allq = residual_sample(m.residual, base, clip, fr, s, gen)
        else:
            allq = base[:, None]
        allq = allq.reshape(PARTS, w, LEVELS)
        new = ~old
        tokens[:, st:st + w][:, new] = allq[:, new]
        made = st + w
    dec = m.vq(tokens.reshape(1, PARTS * n, LEVELS))
    rows = (dec[0, :frames].double() * m.std + m.mean).float()
    return rows, len(starts)


def music_features(gen):
    """35 EDGE features a frame in their usual ranges (as the Rust bench's `music`)."""
    u = lambda *shape: torch.rand(*shape, generator=gen)
    env = u(FRAMES, 1)
    mfcc0 = -200.0 + 100.0 * (u(FRAMES, 1) - 0.5)
    mfcc = 40.0 * (u(FRAMES, 19) - 0.5)
    chroma = u(FRAMES, 12)
    peak = (u(FRAMES, 1) < 1.0 / 8.0).float()
    beat = (u(FRAMES, 1) < 1.0 / 15.0).float()
    return torch.cat([env, mfcc0, mfcc, chroma, peak, beat], 1)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--reps", type=int, default=int(os.environ.get("DANCEGEN_BENCH_REPS", 3)))
    ap.add_argument("only", nargs="?", default="")
    a = ap.parse_args()
    threads = int(os.environ.get("OMP_NUM_THREADS", os.cpu_count()))
    torch.set_num_threads(threads)
    torch.manual_seed(0)
    m = Holistic().eval()
    npar = lambda mod: sum(p.numel() for p in mod.parameters()) if mod is not None else 0
    print(f"pytorch holistic parameters ({SOURCE}): masked {npar(m.masked)}, residual "
          f"{npar(m.residual)}, mmr music {npar(m.mmr_music)}, conv decoder {npar(m.vq.decoder)}",
          file=sys.stderr)
    music = music_features(torch.Generator().manual_seed(7))
    name = "holistic_1800f"
    if a.only not in name:
        return
    nets = [m.masked, m.residual, m.mmr_music, m.vq.decoder]

    def run(steps):
        for net in nets:
            if net is not None:
                net.calls, net.shapes = 0, set()
        rows, windows = generate(m, music, {**SAMPLING, "steps": steps})
        assert rows.shape == (FRAMES, TOTAL_DIMS), rows.shape
        assert torch.isfinite(rows).all()
        return windows

    with torch.inference_mode():
        run(2)
        ms = []
        for _ in range(a.reps):
            t = time.perf_counter()
            windows = run(SAMPLING["steps"])
            ms.append((time.perf_counter() - t) * 1e3)
    ms.sort()
    res = m.residual.calls if m.residual is not None else 0

    def batch(net):
        """The one batch size the network's forwards ran at."""
        if net is None or not net.shapes:
            return 0
        sizes = {sh[0] for sh in net.shapes}
        assert len(sizes) == 1, net.shapes
        return sizes.pop()

    shape = lambda net: ", ".join(str(list(s)) for s in sorted(net.shapes)) if net else "-"
    print(f"pytorch holistic work: {windows} windows; forwards: masked {m.masked.calls} "
          f"({shape(m.masked)}), residual {res} ({shape(m.residual)}), mmr music "
          f"{m.mmr_music.calls} ({shape(m.mmr_music)}), conv decoder {m.vq.decoder.calls} "
          f"({shape(m.vq.decoder)})", file=sys.stderr)
    print(json.dumps({"impl": "pytorch", "case": name, "steps": SAMPLING["steps"],
                      "windows": windows, "masked_forwards": m.masked.calls,
                      "masked_batch": batch(m.masked), "residual_forwards": res,
                      "residual_batch": batch(m.residual), "mmr_forwards": m.mmr_music.calls,
                      "median_ms": round(ms[len(ms) // 2], 2), "min_ms": round(ms[0], 2),
                      "reps": a.reps, "threads": threads}), flush=True)


if __name__ == "__main__":
    main()
