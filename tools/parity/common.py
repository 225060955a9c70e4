"""Shared helpers of the parity fixture scripts: seeded tensors, writing the two safetensors
files per fixture that `crates/dancegen-nn/tests/common/mod.rs` reads.

Run by developers (PyTorch CPU from PyPI), never by CI; the fixtures are committed.
"""

import json
import os

import torch
from safetensors.torch import save_file

OUT = os.path.join(os.path.dirname(__file__), "..", "..", "crates", "dancegen-nn", "tests",
                   "fixtures", "parity")


def seeded(seed):
    torch.manual_seed(seed)
    g = torch.Generator().manual_seed(seed)
    return g


def randn(g, *shape, scale=1.0):
    return torch.randn(*shape, generator=g, dtype=torch.float32) * scale


def write(name, weights, io, config):
    """`weights`: state dict in PyTorch layout (may be empty); `io`: in.* / out.* / grad.*."""
    os.makedirs(OUT, exist_ok=True)
    contig = lambda d: {k: v.detach().contiguous().clone() for k, v in d.items()}
    if weights:
        save_file(contig(weights), os.path.join(OUT, f"{name}.weights.safetensors"))
    save_file(contig(io), os.path.join(OUT, f"{name}.io.safetensors"),
              metadata={"config": json.dumps(config), "torch": torch.__version__})
    n = sum(v.numel() for v in list(weights.values()) + list(io.values()))
    print(f"{name}: {len(weights)} weights, {len(io)} io tensors, {n} values")


def split_mha(prefix, mha):
    """`nn.MultiheadAttention` packed in-projection → our `q_proj/k_proj/v_proj/out_proj`."""
    d = mha.embed_dim
    w, b = mha.in_proj_weight, mha.in_proj_bias
    p = f"{prefix}." if prefix else ""
    out = {}
    for i, n in enumerate(["q_proj", "k_proj", "v_proj"]):
        out[f"{p}{n}.weight"] = w[i * d:(i + 1) * d]
        out[f"{p}{n}.bias"] = b[i * d:(i + 1) * d]
    out[f"{p}out_proj.weight"] = mha.out_proj.weight
    out[f"{p}out_proj.bias"] = mha.out_proj.bias
    return out


def mask_pattern(kind, tq, tk, block=0):
    """Boolean `[tq, tk]`, True = blocked (the Rust convention); queries at the last tq of tk."""
    off = tk - tq
    m = torch.zeros(tq, tk, dtype=torch.bool)
    for i in range(tq):
        a = i + off
        for j in range(tk):
            if kind == "causal":
                m[i, j] = j > a
            elif kind == "block_diagonal":
                m[i, j] = a // block != j // block
            elif kind == "periodic_block_causal":
                m[i, j] = a // block != j // block or j > a
    return m
