"""PyTorch twins of the dancegen-nn blocks the bench ports share (attention, feed-forward, FiLM,
post-norm encoder layer, FiLM decoder layer, rotary tables), with dancegen-nn's parameter names so the same weights load."""

import torch
import torch.nn as nn
import torch.nn.functional as F

# burn's LayerNorm epsilon, PyTorch's default too.
LN_EPS = 1e-5


class Attention(nn.Module):
    def __init__(self, d, h):
        super().__init__()
        self.h = h
        self.q_proj, self.k_proj = nn.Linear(d, d), nn.Linear(d, d)
        self.v_proj, self.out_proj = nn.Linear(d, d), nn.Linear(d, d)

    def split(self, x):
        b, t, d = x.shape
        return x.reshape(b, t, self.h, d // self.h).transpose(1, 2)

    def project_kv(self, k, v):
        """Key/value heads of a fixed memory, computed once per sampling run."""
        return self.split(self.k_proj(k)), self.split(self.v_proj(v))

    def forward(self, q, k=None, v=None, kv=None, causal=False):
        b, tq, d = q.shape
        kk, vv = kv if kv is not None else self.project_kv(k, v)
        o = F.scaled_dot_product_attention(self.split(self.q_proj(q)), kk, vv, is_causal=causal)
        return self.out_proj(o.transpose(1, 2).reshape(b, tq, d))


class Mlp(nn.Module):
    def __init__(self, d, ff):
        super().__init__()
        self.linear1, self.linear2 = nn.Linear(d, ff), nn.Linear(ff, d)

    def forward(self, x):
        return self.linear2(F.gelu(self.linear1(x)))


class Film(nn.Module):
    def __init__(self, d):
        super().__init__()
        self.linear = nn.Linear(d, 2 * d)

    def forward(self, x, cond):
        """cond [B, d] (one vector per window: Lodge++) or [B, N, d] (one per token: ReactDance)."""
        if cond.dim() == 2:
            cond = cond[:, None]
        scale, shift = self.linear(F.mish(cond)).chunk(2, -1)
        return x * (scale + 1) + shift


class EncoderLayer(nn.Module):
    """transformer::EncoderLayer: post-norm (PyTorch's TransformerEncoderLayer default), GELU."""

    def __init__(self, d, h, ff):
        super().__init__()
        self.self_attn, self.ff = Attention(d, h), Mlp(d, ff)
        self.norm1, self.norm2 = nn.LayerNorm(d, eps=LN_EPS), nn.LayerNorm(d, eps=LN_EPS)

    def forward(self, x):
        x = self.norm1(x + self.self_attn(x, x, x))
        return self.norm2(x + self.ff(x))


def rotary_tables(t, d, theta=10000.0):
    """(cos, sin) [1, T, d], each frequency repeated for the interleaved pair (2i, 2i + 1)."""
    f = theta ** (-(2.0 * torch.arange(d // 2, dtype=torch.float64)) / d)
    a = torch.arange(t, dtype=torch.float64)[:, None] * f[None]
    a = a.repeat_interleave(2, dim=1)
    return a.cos().float()[None], a.sin().float()[None]


def rotate(x, tables):
    cos, sin = tables
    b, t, d = x.shape
    pairs = x.reshape(b, t, d // 2, 2)
    half = torch.stack([-pairs[..., 1], pairs[..., 0]], -1).reshape(b, t, d)
    return x * cos + half * sin


class FilmDecoderLayer(nn.Module):
    """transformer::FilmDecoderLayer: norm-first, FiLM after each sub-layer; rotary on the
    self-attention q/k input when tables are given (Lodge++), within-block causal on request."""

    def __init__(self, d, h, ff):
        super().__init__()
        self.self_attn, self.cross_attn, self.ff = Attention(d, h), Attention(d, h), Mlp(d, ff)
        self.norm1 = nn.LayerNorm(d, eps=LN_EPS)
        self.norm2 = nn.LayerNorm(d, eps=LN_EPS)
        self.norm3 = nn.LayerNorm(d, eps=LN_EPS)
        self.film1, self.film2, self.film3 = Film(d), Film(d), Film(d)

    def forward(self, x, cond, memory=None, kv=None, rotary=None, causal=False):
        """Cross-attends `memory`, or its precomputed key/value heads `kv`."""
        h = self.norm1(x)
        qk = rotate(h, rotary) if rotary is not None else h
        x = x + self.film1(self.self_attn(qk, qk, h, causal=causal), cond)
        x = x + self.film2(self.cross_attn(self.norm2(x), memory, memory, kv), cond)
        return x + self.film3(self.ff(self.norm3(x)), cond)
