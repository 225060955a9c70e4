"""Parity fixtures for the Transformer building blocks of `dancegen-nn`.

The references are PyTorch's own modules where one exists (`nn.MultiheadAttention`,
`nn.TransformerEncoderLayer`, `F.scaled_dot_product_attention`) and, for EDGE's FiLM decoder
layer, rotary embedding and timestep embedding, small modules written from their published
formulas (EDGE `model/model.py`, `model/utils.py`, `rotary-embedding-torch`; see the Rust docs).

    python tools/parity/blocks.py
"""

import math

import torch
import torch.nn as nn
import torch.nn.functional as F

from common import mask_pattern, randn, seeded, split_mha, write


def mha_masks():
    g = seeded(1)
    B, T, D, H = 2, 12, 16, 4
    mha = nn.MultiheadAttention(D, H, batch_first=True)
    x = randn(g, B, T, D).requires_grad_(True)
    probe = randn(g, B, T, D)
    pad = torch.zeros(B, T, dtype=torch.bool)
    pad[1, -3:] = True
    io = {"in.x": x, "in.probe": probe, "in.key_padding": pad}
    for kind, block in [("full", 0), ("causal", 0), ("block_diagonal", 4),
                        ("periodic_block_causal", 4)]:
        m = None if kind == "full" else mask_pattern(kind, T, T, block)
        y, _ = mha(x, x, x, attn_mask=m, need_weights=False)
        io[f"out.{kind}"] = y
        if kind == "causal":
            (gx, gw) = torch.autograd.grad((y * probe).sum(), [x, mha.in_proj_weight])
            io["grad.causal.x"] = gx
            io["grad.causal.q_proj.weight"] = gw[:D]
    y, _ = mha(x, x, x, key_padding_mask=pad, attn_mask=mask_pattern("causal", T, T),
               need_weights=False)
    io["out.causal_key_padding"] = y
    write("mha_masks", split_mha("", mha) | {}, io, {"d_model": D, "n_heads": H, "block": 4})


def cross_attention():
    g = seeded(2)
    B, Tq, Tk, D, Dc, H = 2, 7, 10, 16, 12, 4
    mha = nn.MultiheadAttention(D, H, kdim=Dc, vdim=Dc, batch_first=True)
    q = randn(g, B, Tq, D)
    kv = randn(g, B, Tk, Dc)
    pad = torch.zeros(B, Tk, dtype=torch.bool)
    pad[0, -4:] = True
    y, _ = mha(q, kv, kv, key_padding_mask=pad, need_weights=False)
    w = {
        "q_proj.weight": mha.q_proj_weight, "q_proj.bias": mha.in_proj_bias[:D],
        "k_proj.weight": mha.k_proj_weight, "k_proj.bias": mha.in_proj_bias[D:2 * D],
        "v_proj.weight": mha.v_proj_weight, "v_proj.bias": mha.in_proj_bias[2 * D:],
        "out_proj.weight": mha.out_proj.weight, "out_proj.bias": mha.out_proj.bias,
    }
    write("cross_attention", w, {"in.q": q, "in.kv": kv, "in.key_padding": pad, "out.y": y},
          {"d_model": D, "d_context": Dc, "n_heads": H})


def encoder_layers():
    for norm_first in [False, True]:
        g = seeded(3 + norm_first)
        B, T, D, H, FF = 2, 9, 16, 4, 32
        layer = nn.TransformerEncoderLayer(D, H, FF, dropout=0.0, activation=F.gelu,
                                           batch_first=True, norm_first=norm_first)
        x = randn(g, B, T, D).requires_grad_(True)
        probe = randn(g, B, T, D)
        y = layer(x)
        gx, = torch.autograd.grad((y * probe).sum(), [x])
        w = split_mha("self_attn", layer.self_attn) | {
            "ff.linear1.weight": layer.linear1.weight, "ff.linear1.bias": layer.linear1.bias,
            "ff.linear2.weight": layer.linear2.weight, "ff.linear2.bias": layer.linear2.bias,
            "norm1.weight": layer.norm1.weight, "norm1.bias": layer.norm1.bias,
            "norm2.weight": layer.norm2.weight, "norm2.bias": layer.norm2.bias,
        }
        name = "encoder_pre_norm" if norm_first else "encoder_post_norm"
        write(name, w, {"in.x": x, "in.probe": probe, "out.y": y, "grad.x": gx},
              {"d_model": D, "n_heads": H, "d_ff": FF, "norm_first": norm_first})


def rotary_rotate(x, start=0, theta=10000.0):
    """Interleaved-pair rotary over the last dim of `[B, T, D]` (rotary-embedding-torch)."""
    B, T, D = x.shape
    inv = theta ** (-torch.arange(0, D, 2, dtype=torch.float64) / D)
    pos = torch.arange(start, start + T, dtype=torch.float64)
    ang = (pos[:, None] * inv[None, :]).repeat_interleave(2, dim=1)  # [T, D]
    cos, sin = ang.cos().float(), ang.sin().float()
    pairs = x.reshape(B, T, D // 2, 2)
    half = torch.stack([-pairs[..., 1], pairs[..., 0]], dim=-1).reshape(B, T, D)
    return x * cos + half * sin


def film(linear, x, cond):
    ss = linear(F.mish(cond)).unsqueeze(1)
    scale, shift = ss.chunk(2, dim=-1)
    return (scale + 1) * x + shift


class FilmDecoderLayer(nn.Module):
    """EDGE `FiLMTransformerDecoderLayer`, norm-first, GELU, rotary on the self-attn q/k input."""

    def __init__(self, D, H, FF, Dc):
        super().__init__()
        self.self_attn = nn.MultiheadAttention(D, H, batch_first=True)
        self.cross_attn = nn.MultiheadAttention(D, H, kdim=Dc, vdim=Dc, batch_first=True)
        self.linear1, self.linear2 = nn.Linear(D, FF), nn.Linear(FF, D)
        self.norm1, self.norm2, self.norm3 = nn.LayerNorm(D), nn.LayerNorm(D), nn.LayerNorm(D)
        self.film1, self.film2, self.film3 = (nn.Linear(D, 2 * D) for _ in range(3))

    def forward(self, x, memory, cond, rotary_start, self_mask):
        h = self.norm1(x)
        qk = rotary_rotate(h, rotary_start)
        sa, _ = self.self_attn(qk, qk, h, attn_mask=self_mask, need_weights=False)
        x = x + film(self.film1, sa, cond)
        h = self.norm2(x)
        ca, _ = self.cross_attn(h, memory, memory, need_weights=False)
        x = x + film(self.film2, ca, cond)
        ff = self.linear2(F.gelu(self.linear1(self.norm3(x))))
        return x + film(self.film3, ff, cond)


def film_decoder():
    g = seeded(5)
    B, T, Tm, D, H, FF, Dc = 2, 10, 9, 16, 4, 32, 12
    layer = FilmDecoderLayer(D, H, FF, Dc)
    x = randn(g, B, T, D).requires_grad_(True)
    memory = randn(g, B, Tm, Dc)
    cond = randn(g, B, D)
    probe = randn(g, B, T, D)
    mask = mask_pattern("block_diagonal", T, T, 5)
    y = layer(x, memory, cond, 3, mask)
    gx, gn, gf = torch.autograd.grad((y * probe).sum(),
                                     [x, layer.norm1.weight, layer.film2.weight])
    cm = layer.cross_attn
    w = split_mha("self_attn", layer.self_attn) | {
        "cross_attn.q_proj.weight": cm.q_proj_weight, "cross_attn.q_proj.bias": cm.in_proj_bias[:D],
        "cross_attn.k_proj.weight": cm.k_proj_weight,
        "cross_attn.k_proj.bias": cm.in_proj_bias[D:2 * D],
        "cross_attn.v_proj.weight": cm.v_proj_weight,
        "cross_attn.v_proj.bias": cm.in_proj_bias[2 * D:],
        "cross_attn.out_proj.weight": cm.out_proj.weight,
        "cross_attn.out_proj.bias": cm.out_proj.bias,
        "ff.linear1.weight": layer.linear1.weight, "ff.linear1.bias": layer.linear1.bias,
        "ff.linear2.weight": layer.linear2.weight, "ff.linear2.bias": layer.linear2.bias,
    }
    for i in (1, 2, 3):
        n, f = getattr(layer, f"norm{i}"), getattr(layer, f"film{i}")
        w |= {f"norm{i}.weight": n.weight, f"norm{i}.bias": n.bias,
              f"film{i}.linear.weight": f.weight, f"film{i}.linear.bias": f.bias}
    write("film_decoder", w,
          {"in.x": x, "in.memory": memory, "in.cond": cond, "in.probe": probe, "out.y": y,
           "grad.x": gx, "grad.norm1.weight": gn, "grad.film2.linear.weight": gf},
          {"d_model": D, "n_heads": H, "d_ff": FF, "d_context": Dc, "rotary_start": 3,
           "block": 5})


def timestep_and_encodings():
    g = seeded(6)
    D = 16
    t = torch.tensor([0.0, 1.0, 37.0, 999.0])
    half = D // 2
    freqs = torch.exp(torch.arange(half, dtype=torch.float64) * -(math.log(10000) / (half - 1)))
    emb = (t.double()[:, None] * freqs[None, :])
    emb = torch.cat([emb.sin(), emb.cos()], dim=-1).float()
    lin = nn.Linear(D, 4 * D)
    h = F.mish(lin(emb))
    x = randn(g, 2, 7, D)
    rot = rotary_rotate(x, 5)
    pos = torch.arange(0, 20, dtype=torch.float64)[:, None]
    div = torch.exp(torch.arange(0, D, 2, dtype=torch.float64) * (-math.log(10000.0) / D))
    pe = torch.zeros(20, D, dtype=torch.float64)
    pe[:, 0::2] = torch.sin(pos * div)
    pe[:, 1::2] = torch.cos(pos * div)
    write("timestep", {"linear.weight": lin.weight, "linear.bias": lin.bias},
          {"in.t": t, "in.x": x, "out.sinusoidal_t": emb, "out.mlp": h, "out.rotary": rot,
           "out.sinusoidal_pe": pe.float()},
          {"d": D, "rotary_start": 5})


if __name__ == "__main__":
    torch.set_num_threads(1)
    mha_masks()
    cross_attention()
    encoder_layers()
    film_decoder()
    timestep_and_encodings()
