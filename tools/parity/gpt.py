"""Parity fixtures for the token models of `dancegen-nn`: the GPT (Lodge++ choreography network,
T2M-GPT) with a conditioning prefix, and the MoMask-style masked transformer (SoulNet).

References written from the architectures' definitions: GPT-2 pre-norm blocks (causal
self-attention via `F.scaled_dot_product_attention(is_causal=True)`, GELU MLP), learned
positions; masked transformer = `[cond token; embeddings + sinusoidal PE]` through
`nn.TransformerEncoderLayer` (post-norm, GELU), linear head.

    python tools/parity/gpt.py
"""

import math

import torch
import torch.nn as nn
import torch.nn.functional as F

from common import randn, seeded, split_mha, write


class Block(nn.Module):
    def __init__(self, d, h):
        super().__init__()
        self.h = h
        self.ln1, self.ln2 = nn.LayerNorm(d), nn.LayerNorm(d)
        self.q_proj, self.k_proj, self.v_proj, self.out_proj = (nn.Linear(d, d) for _ in range(4))
        self.linear1, self.linear2 = nn.Linear(d, 4 * d), nn.Linear(4 * d, d)

    def forward(self, x):
        B, T, D = x.shape
        a = self.ln1(x)
        split = lambda t: t.view(B, T, self.h, D // self.h).transpose(1, 2)
        o = F.scaled_dot_product_attention(split(self.q_proj(a)), split(self.k_proj(a)),
                                           split(self.v_proj(a)), is_causal=True)
        x = x + self.out_proj(o.transpose(1, 2).reshape(B, T, D))
        return x + self.linear2(F.gelu(self.linear1(self.ln2(x))))


class Gpt(nn.Module):
    def __init__(self, vocab, d, layers, h, max_len):
        super().__init__()
        self.tok_emb = nn.Embedding(vocab, d)
        self.pos = nn.Parameter(torch.randn(max_len, d) * 0.5)
        self.blocks = nn.ModuleList(Block(d, h) for _ in range(layers))
        self.ln_f = nn.LayerNorm(d)
        self.head = nn.Linear(d, vocab)

    def forward(self, prefix, tokens):
        x = torch.cat([prefix, self.tok_emb(tokens)], dim=1)
        x = x + self.pos[: x.shape[1]]
        for b in self.blocks:
            x = b(x)
        h = self.ln_f(x)[:, prefix.shape[1] - 1: prefix.shape[1] - 1 + tokens.shape[1]]
        return self.head(h)

    def state(self):
        s = {"tok_emb.weight": self.tok_emb.weight, "pos_emb.weight": self.pos,
             "ln_f.weight": self.ln_f.weight, "ln_f.bias": self.ln_f.bias,
             "head.weight": self.head.weight, "head.bias": self.head.bias}
        for i, b in enumerate(self.blocks):
            p = f"blocks.{i}."
            for n in ["ln1", "ln2"]:
                m = getattr(b, n)
                s[p + n + ".weight"], s[p + n + ".bias"] = m.weight, m.bias
            for n in ["q_proj", "k_proj", "v_proj", "out_proj"]:
                m = getattr(b, n)
                s[p + "attn." + n + ".weight"], s[p + "attn." + n + ".bias"] = m.weight, m.bias
            for n in ["linear1", "linear2"]:
                m = getattr(b, n)
                s[p + "mlp." + n + ".weight"], s[p + "mlp." + n + ".bias"] = m.weight, m.bias
        return s


def gpt():
    g = seeded(11)
    V, D, L, H, M = 23, 16, 2, 4, 32
    model = Gpt(V, D, L, H, M)
    with torch.no_grad():
        for p in model.parameters():
            p.mul_(3.0)  # sharper logits: greedy decoding far from ties
    prefix = randn(g, 2, 3, D)
    tokens = torch.randint(0, V, (2, 6), generator=g)
    logits = model(prefix, tokens)
    # Greedy decoding of 8 tokens by full recomputation (no cache): the Rust KV-cache decoder
    # must produce the same tokens.
    seq = torch.zeros(2, 0, dtype=torch.long)
    with torch.no_grad():
        for _ in range(8):
            full = model(prefix, torch.cat([seq, torch.zeros(2, 1, dtype=torch.long)], 1))
            seq = torch.cat([seq, full[:, -1].argmax(-1, keepdim=True)], 1)
    write("gpt", model.state(),
          {"in.prefix": prefix, "in.tokens": tokens, "out.logits": logits, "out.greedy": seq},
          {"vocab": V, "d_model": D, "n_layers": L, "n_heads": H, "max_len": M})


def masked_transformer():
    g = seeded(12)
    V, D, L, H, FF, DC, T = 19, 16, 2, 4, 32, 10, 7
    tok = nn.Embedding(V + 1, D)
    cond_proj = nn.Linear(DC, D)
    layers = nn.ModuleList(nn.TransformerEncoderLayer(D, H, FF, dropout=0.0, activation=F.gelu,
                                                      batch_first=True) for _ in range(L))
    head = nn.Linear(D, V)
    tokens = torch.randint(0, V + 1, (2, T), generator=g)
    cond = randn(g, 2, DC)
    pos = torch.arange(T, dtype=torch.float64)[:, None]
    div = torch.exp(torch.arange(0, D, 2, dtype=torch.float64) * (-math.log(10000.0) / D))
    pe = torch.zeros(T, D, dtype=torch.float64)
    pe[:, 0::2], pe[:, 1::2] = torch.sin(pos * div), torch.cos(pos * div)
    x = torch.cat([cond_proj(cond)[:, None], tok(tokens) + pe.float()], 1)
    for l in layers:
        x = l(x)
    logits = head(x[:, 1:])
    s = {"tok_emb.weight": tok.weight, "cond_proj.weight": cond_proj.weight,
         "cond_proj.bias": cond_proj.bias, "head.weight": head.weight, "head.bias": head.bias}
    for i, l in enumerate(layers):
        p = f"layers.{i}."
        s |= split_mha(p + "self_attn", l.self_attn)
        s |= {p + "ff.linear1.weight": l.linear1.weight, p + "ff.linear1.bias": l.linear1.bias,
              p + "ff.linear2.weight": l.linear2.weight, p + "ff.linear2.bias": l.linear2.bias,
              p + "norm1.weight": l.norm1.weight, p + "norm1.bias": l.norm1.bias,
              p + "norm2.weight": l.norm2.weight, p + "norm2.bias": l.norm2.bias}
    write("masked_transformer", s, {"in.tokens": tokens, "in.cond": cond, "out.logits": logits},
          {"vocab": V, "d_model": D, "n_layers": L, "n_heads": H, "d_ff": FF, "d_cond": DC})


def losses():
    g = seeded(13)
    d6 = randn(g, 5, 6)
    a1, a2 = d6[:, :3], d6[:, 3:]
    b1 = F.normalize(a1, dim=-1)
    b2 = F.normalize(a2 - (b1 * a2).sum(-1, keepdim=True) * b1, dim=-1)
    mat = torch.stack([b1, b2, torch.cross(b1, b2, dim=-1)], dim=-2)
    a, b = randn(g, 6, 8), randn(g, 6, 8)
    logits = F.normalize(a, dim=-1) @ F.normalize(b, dim=-1).T / 0.07
    lab = torch.arange(6)
    nce = (F.cross_entropy(logits, lab) + F.cross_entropy(logits.T, lab)) / 2
    p, q = randn(g, 2, 9, 5), randn(g, 2, 9, 5)
    write("losses", {}, {"in.d6": d6, "out.matrix": mat, "in.a": a, "in.b": b,
                         "out.info_nce": nce.reshape(1), "in.p": p, "in.q": q,
                         "out.smooth_l1": F.smooth_l1_loss(p, q).reshape(1),
                         "out.velocity_l2": F.mse_loss(p.diff(dim=1), q.diff(dim=1)).reshape(1),
                         "out.acceleration_l1": F.l1_loss(p.diff(dim=1).diff(dim=1),
                                                          q.diff(dim=1).diff(dim=1)).reshape(1)},
          {"temperature": 0.07})


if __name__ == "__main__":
    torch.set_num_threads(1)
    gpt()
    masked_transformer()
    losses()
