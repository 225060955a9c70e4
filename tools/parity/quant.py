"""Parity fixtures for the motion autoencoder pieces of `dancegen-nn`: the T2M-GPT conv
encoder/decoder, the EMA-reset VQ (forward, straight-through gradient, one EMA training step with
dead-code reset), MoMask residual VQ, SoulNet hierarchical RVQ, FSQ and ReactDance's grouped
residual FSQ.

The references are written here from the published formulas / reference code
(`Mael-zys/T2M-GPT:models/encdec.py, resnet.py, quantize_cnn.py`,
`EricGuo5513/momask-codes:models/vq/residual_vq.py`,
`xjli360/SoulDance-Official:models/vq/residual_hvq.py`, Mentzer et al. 2023 FSQ appendix,
residual FSQ scales of `vector-quantize-pytorch`), with the parameter names of the Rust modules.

    python tools/parity/quant.py
"""

import math

import torch
import torch.nn as nn
import torch.nn.functional as F

from common import randn, seeded, write


# ---- T2M-GPT conv encoder / decoder (descriptive names = the Rust modules) ----

class ResBlock(nn.Module):
    def __init__(self, w, d):
        super().__init__()
        self.conv1 = nn.Conv1d(w, w, 3, 1, d, d)
        self.conv2 = nn.Conv1d(w, w, 1, 1, 0)

    def forward(self, x):
        return x + self.conv2(F.relu(self.conv1(F.relu(x))))


class Resnet1D(nn.Module):
    def __init__(self, w, depth, growth, reverse):
        super().__init__()
        dil = [growth ** i for i in range(depth)]
        if reverse:
            dil = dil[::-1]
        self.blocks = nn.ModuleList([ResBlock(w, d) for d in dil])

    def forward(self, x):
        for b in self.blocks:
            x = b(x)
        return x


class Down(nn.Module):
    def __init__(self, w, depth, growth, stride):
        super().__init__()
        self.conv = nn.Conv1d(w, w, 2 * stride, stride, stride // 2)
        self.resnet = Resnet1D(w, depth, growth, True)


class Up(nn.Module):
    def __init__(self, w, depth, growth):
        super().__init__()
        self.resnet = Resnet1D(w, depth, growth, True)
        self.conv = nn.Conv1d(w, w, 3, 1, 1)


class Encoder(nn.Module):
    def __init__(self, c):
        super().__init__()
        w = c["width"]
        self.conv_in = nn.Conv1d(c["input_dim"], w, 3, 1, 1)
        self.down = nn.ModuleList([Down(w, c["depth"], c["dilation_growth_rate"], c["stride_t"])
                                   for _ in range(c["down_t"])])
        self.conv_out = nn.Conv1d(w, c["code_dim"], 3, 1, 1)

    def forward(self, x):  # [B, T, C]
        h = F.relu(self.conv_in(x.transpose(1, 2)))
        for d in self.down:
            h = d.resnet(d.conv(h))
        return self.conv_out(h).transpose(1, 2)


class Decoder(nn.Module):
    def __init__(self, c):
        super().__init__()
        w = c["width"]
        self.conv_in = nn.Conv1d(c["code_dim"], w, 3, 1, 1)
        self.up = nn.ModuleList([Up(w, c["depth"], c["dilation_growth_rate"])
                                 for _ in range(c["down_t"])])
        self.conv_mid = nn.Conv1d(w, w, 3, 1, 1)
        self.conv_out = nn.Conv1d(w, c["output_dim"], 3, 1, 1)

    def forward(self, z):
        h = F.relu(self.conv_in(z.transpose(1, 2)))
        for u in self.up:
            h = u.conv(F.interpolate(u.resnet(h), scale_factor=2, mode="nearest"))
        return self.conv_out(F.relu(self.conv_mid(h))).transpose(1, 2)


def conv_codec():
    g = seeded(11)
    c = dict(input_dim=6, output_dim=6, width=8, depth=2, down_t=2, stride_t=2,
             dilation_growth_rate=3, code_dim=5)
    enc, dec = Encoder(c), Decoder(c)
    x = randn(g, 2, 16, 6).requires_grad_(True)
    y = enc(x)
    probe = randn(g, *y.shape)
    gx, = torch.autograd.grad((y * probe).sum(), [x])
    write("conv_encoder", enc.state_dict(), {"in.x": x, "in.probe": probe, "out.y": y,
                                             "grad.x": gx}, c)
    z = randn(g, 2, 4, 5).requires_grad_(True)
    y = dec(z)
    probe = randn(g, *y.shape)
    gz, gw = torch.autograd.grad((y * probe).sum(), [z, dec.conv_in.weight])
    write("conv_decoder", dec.state_dict(), {"in.z": z, "in.probe": probe, "out.y": y,
                                             "grad.z": gz, "grad.conv_in.weight": gw}, c)


# ---- T2M-GPT QuantizeEMAReset on [N, d] ----

class EmaVq(nn.Module):
    def __init__(self, k, d, mu=0.99):
        super().__init__()
        self.k, self.d, self.mu = k, d, mu
        self.register_buffer("codebook", torch.zeros(k, d))
        self.register_buffer("code_sum", torch.zeros(k, d))
        self.register_buffer("code_count", torch.ones(k))
        self.register_buffer("initialised", torch.zeros(1))

    def set_codebook(self, cb):
        self.codebook = cb.clone()
        self.code_sum = cb.clone()
        self.code_count = torch.ones(self.k)
        self.initialised = torch.ones(1)

    def tile(self, x):  # N >= K in the fixtures: no noise
        assert x.shape[0] >= self.k
        return x[:self.k]

    def quantize(self, x):
        kw = self.codebook.t()
        dist = (x ** 2).sum(-1, keepdim=True) - 2 * x @ kw + (kw ** 2).sum(0, keepdim=True)
        return dist.argmin(-1)

    @torch.no_grad()
    def update(self, x, idx):
        onehot = torch.zeros(self.k, x.shape[0])
        onehot.scatter_(0, idx.view(1, -1), 1)
        code_sum = onehot @ x
        code_count = onehot.sum(-1)
        rand = self.tile(x)
        self.code_sum = self.mu * self.code_sum + (1 - self.mu) * code_sum
        self.code_count = self.mu * self.code_count + (1 - self.mu) * code_count
        usage = (self.code_count.view(-1, 1) >= 1.0).float()
        self.codebook = usage * (self.code_sum / self.code_count.view(-1, 1)) + (1 - usage) * rand
        p = code_count / code_count.sum()
        return torch.exp(-(p * torch.log(p + 1e-7)).sum())

    def forward(self, x3, training):  # [B, T, d]
        b, t, d = x3.shape
        x = x3.reshape(b * t, d)
        if training and self.initialised.item() < 0.5:
            self.set_codebook(self.tile(x.detach()))
        idx = self.quantize(x.detach())
        q = self.codebook[idx]
        if training:
            perp = self.update(x.detach(), idx)
        else:
            cnt = torch.bincount(idx, minlength=self.k).float()
            p = cnt / cnt.sum()
            perp = torch.exp(-(p * torch.log(p + 1e-7)).sum())
        commit = F.mse_loss(x, q.detach())
        out = x + (q - x).detach()
        return out.view(b, t, d), idx.view(b, t, 1), commit, perp


def vq_ema():
    g = seeded(21)
    K, D = 8, 4
    x = randn(g, 2, 10, D).requires_grad_(True)
    probe = randn(g, 2, 10, D)
    cb = randn(g, K, D)
    io = {"in.x": x, "in.probe": probe, "in.codebook": cb}
    # inference
    vq = EmaVq(K, D)
    vq.set_codebook(cb)
    q, idx, commit, perp = vq(x, False)
    gx, = torch.autograd.grad((q * probe).sum() + commit, [x])
    io |= {"out.eval.quantized": q, "out.eval.indices": idx, "out.eval.commit": commit.view(1),
           "out.eval.perplexity": perp.view(1), "grad.eval.x": gx}
    # one training step (EMA update + dead-code reset to the first K inputs)
    q, idx, commit, perp = vq(x, True)
    io |= {"out.train.quantized": q, "out.train.indices": idx, "out.train.perplexity": perp.view(1),
           "out.train.codebook": vq.codebook, "out.train.code_sum": vq.code_sum,
           "out.train.code_count": vq.code_count}
    # first training call on a fresh quantizer: initialise from the inputs, then update
    fresh = EmaVq(K, D)
    fresh(x, True)
    io |= {"out.init.codebook": fresh.codebook}
    write("vq_ema", {}, io, {"nb_code": K, "code_dim": D, "mu": 0.99})


def rvq():
    g = seeded(31)
    K, D, Q = 8, 4, 3
    x = randn(g, 2, 9, D).requires_grad_(True)
    probe = randn(g, 2, 9, D)
    layers = [EmaVq(K, D) for _ in range(Q)]
    w = {}
    for i, l in enumerate(layers):
        l.set_codebook(randn(g, K, D, scale=0.7 ** i))
        w |= {f"layers.{i}.{k}": v for k, v in l.state_dict().items()}
    io = {"in.x": x, "in.probe": probe}
    for keep in [Q, 2]:
        res, out, ids, losses = x, 0, [], []
        for i, l in enumerate(layers):
            if i >= keep:
                ids.append(torch.full((2, 9, 1), -1, dtype=torch.long))
                continue
            q, idx, commit, _ = l(res, False)
            res = res - q.detach()
            out = out + q
            ids.append(idx)
            losses.append(commit)
        commit = sum(losses) / len(losses)
        gx, = torch.autograd.grad((out * probe).sum() + commit, [x])
        io |= {f"out.keep{keep}.quantized": out, f"out.keep{keep}.indices": torch.cat(ids, -1),
               f"out.keep{keep}.commit": commit.view(1), f"grad.keep{keep}.x": gx}
    write("rvq", w, io, {"nb_code": K, "code_dim": D, "num_quantizers": Q})


def hrvq():
    g = seeded(41)
    K, D, Q, B, T = 8, 4, 2, 2, 6
    body = [EmaVq(K, D) for _ in range(Q)]
    hands = [EmaVq(K, D) for _ in range(Q)]
    face = [EmaVq(K, D) for _ in range(Q)]
    lin = nn.Linear(D, D)
    conv = nn.Conv1d(2 * D, D, 3, 1, 1)
    w = {"transformation.linear.weight": lin.weight, "transformation.linear.bias": lin.bias,
         "conv1d.weight": conv.weight, "conv1d.bias": conv.bias}
    for name, stack in [("layers_body", body), ("layers_hands", hands), ("layers_face", face)]:
        for i, l in enumerate(stack):
            l.set_codebook(randn(g, K, D, scale=0.7 ** i))
            w |= {f"{name}.{i}.{k}": v for k, v in l.state_dict().items()}

    def transformation(qx):  # the reference's TransformationLayer on [B, D, T]
        b, d, t = qx.shape
        return lin(qx.permute(0, 2, 1).reshape(-1, d)).reshape(b, -1, t)

    def link(q_prev, res):  # [B, T, D] in, [B, T, D] out
        h = conv(torch.cat((transformation(q_prev.transpose(1, 2)), res.transpose(1, 2)), 1))
        return h.transpose(1, 2)

    x = randn(g, B, T, 3 * D).requires_grad_(True)
    probe = randn(g, B, T, 3 * D)
    rb, rh, rf = x[..., :D], x[..., D:2 * D], x[..., 2 * D:]
    ob = oh = of = 0
    ids, losses = [], []
    for i in range(Q):
        qb, ib, cb, _ = body[i](rb, False)
        rb = rb - qb.detach()
        ob = ob + qb
        qh, ih, ch, _ = hands[i](link(qb, rh), False)
        rh = rh - qh.detach()
        oh = oh + qh
        qf, if_, cf, _ = face[i](link(qh, rf), False)
        rf = rf - qf.detach()
        of = of + qf
        ids.append(torch.cat((ib, ih, if_), 1))
        losses.append(cb + ch + cf)
    out = torch.cat((ob, oh, of), -1)
    commit = sum(losses) / len(losses)
    gx, gc = torch.autograd.grad((out * probe).sum() + commit, [x, conv.weight])
    io = {"in.x": x, "in.probe": probe, "out.quantized": out, "out.indices": torch.cat(ids, -1),
          "out.commit": commit.view(1), "grad.x": gx, "grad.conv1d.weight": gc}
    write("hrvq", w, io, {"nb_code": K, "code_dim": D, "num_quantizers": Q})


# ---- FSQ (Mentzer et al. 2023) ----

class Fsq:
    def __init__(self, levels):
        self.levels = torch.tensor(levels)
        self.basis = torch.cumprod(torch.tensor([1] + levels[:-1]), 0)

    def bound(self, z, eps=1e-3):
        half = (self.levels - 1) * (1 + eps) / 2
        offset = torch.where(self.levels % 2 == 0, 0.5, 0.0)
        shift = (offset / half).atanh()
        return (z + shift).tanh() * half - offset

    def quantize(self, z):
        b = self.bound(z)
        return (b + (b.round() - b).detach()) / (self.levels // 2)

    def codes_to_indices(self, c):
        hw = self.levels // 2
        return ((c * hw + hw) * self.basis).sum(-1, keepdim=True).round().long()

    def indices_to_codes(self, idx):
        hw = self.levels // 2
        return ((idx // self.basis) % self.levels - hw) / hw


def fsq():
    g = seeded(51)
    levels = [8, 5, 5, 3]
    f = Fsq(levels)
    x = randn(g, 2, 7, 4, scale=2.0).requires_grad_(True)
    probe = randn(g, 2, 7, 4)
    c = f.quantize(x)
    idx = f.codes_to_indices(c)
    gx, = torch.autograd.grad((c * probe).sum(), [x])
    all_idx = torch.arange(math.prod(levels)).view(1, -1, 1)
    io = {"in.x": x, "in.probe": probe, "out.codes": c, "out.indices": idx, "grad.x": gx,
          "out.all_codes": f.indices_to_codes(all_idx)}
    write("fsq", {}, io, {"levels": levels})


def hfsq():
    g = seeded(61)
    levels, G, R = [8, 5, 5, 3], 2, 3
    f = Fsq(levels)
    n = len(levels)
    x = randn(g, 2, 6, G * n, scale=1.5).requires_grad_(True)
    probe = randn(g, 2, 6, G * n)
    lv = [[] for _ in range(R)]
    ids = []
    for gi in range(G):
        e = x[..., gi * n:(gi + 1) * n]
        for r in range(R):
            s = (f.levels.float() - 1) ** (-r)
            v = f.quantize(e / s)
            ids.append(f.codes_to_indices(v))
            c = v * s
            e = e - c.detach()
            lv[r].append(c)
    levels_out = [torch.cat(p, -1) for p in lv]
    out = sum(levels_out)
    gx, = torch.autograd.grad((out * probe).sum(), [x])
    io = {"in.x": x, "in.probe": probe, "out.quantized": out, "out.indices": torch.cat(ids, -1),
          "grad.x": gx}
    io |= {f"out.level{r}": l for r, l in enumerate(levels_out)}
    write("hfsq", {}, io, {"levels": levels, "groups": G, "num_levels": R, "dim": G * n})


if __name__ == "__main__":
    torch.set_num_threads(1)
    conv_codec()
    vq_ema()
    rvq()
    hrvq()
    fsq()
    hfsq()
