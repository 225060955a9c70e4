"""Parity fixture for `dancegen_train::optim::EdgeAdan`: EDGE's Adan optimizer
(`Stanford-TML/EDGE:model/adan.py`, itself lucidrains' `adan-pytorch`; Xie et al. 2022,
arXiv 2208.06677, Algorithm 1) stepped in PyTorch float32 on a seeded [3, 4] parameter with
seeded gradients, EDGE's recipe (lr 4e-4, weight decay 0.02, betas (0.02, 0.08, 0.01);
anchors.md D.1).

Writes `crates/dancegen-train/tests/fixtures/adan_edge.json`. Run by developers with PyTorch CPU
(`/tmp/torchvenv/bin/python tools/parity/adan.py`), never by CI; the fixture is committed.
"""

import json
import os

import torch

OUT = os.path.join(os.path.dirname(__file__), "..", "..", "crates", "dancegen-train", "tests",
                   "fixtures", "adan_edge.json")


class EdgeAdan(torch.optim.Optimizer):
    """The update of EDGE's `model/adan.py` (`restart_cond` unused, as in EDGE)."""

    def __init__(self, params, lr, betas, eps, weight_decay):
        super().__init__(params, dict(lr=lr, betas=betas, eps=eps, weight_decay=weight_decay))

    @torch.no_grad()
    def step(self):
        for group in self.param_groups:
            lr, (b1, b2, b3) = group["lr"], group["betas"]
            wd, eps = group["weight_decay"], group["eps"]
            for p in group["params"]:
                grad = p.grad
                state = self.state[p]
                if len(state) == 0:
                    state["step"] = 0
                    for k in ("prev_grad", "m", "v", "n"):
                        state[k] = torch.zeros_like(grad)
                step, m, v, n = state["step"], state["m"], state["v"], state["n"]
                if step > 0:
                    m.mul_(1 - b1).add_(grad, alpha=b1)
                    grad_diff = grad - state["prev_grad"]
                    v.mul_(1 - b2).add_(grad_diff, alpha=b2)
                    next_n = (grad + (1 - b2) * grad_diff) ** 2
                    n.mul_(1 - b3).add_(next_n, alpha=b3)
                step += 1
                cm, cv, cn = (1 / (1 - (1 - b) ** step) for b in (b1, b2, b3))
                size = lr / (n * cn).sqrt().add_(eps)
                p.addcmul_(size, (m * cm + (1 - b2) * v * cv), value=-1.0).div_(1 + wd * lr)
                state["prev_grad"].copy_(grad)
                state["step"] = step


def main():
    g = torch.Generator().manual_seed(5)
    lr, wd, betas, eps, steps = 4e-4, 0.02, (0.02, 0.08, 0.01), 1e-8, 6
    theta = torch.nn.Parameter(torch.randn(3, 4, generator=g, dtype=torch.float32))
    theta0 = theta.detach().clone()
    opt = EdgeAdan([theta], lr=lr, betas=betas, eps=eps, weight_decay=wd)
    grads, thetas = [], []
    for _ in range(steps):
        grad = torch.randn(3, 4, generator=g, dtype=torch.float32)
        theta.grad = grad.clone()
        opt.step()
        grads.append(grad.flatten().tolist())
        thetas.append(theta.detach().flatten().tolist())
    fixture = dict(torch=torch.__version__, shape=[3, 4], lr=lr, weight_decay=wd,
                   betas=list(betas), eps=eps, theta0=theta0.flatten().tolist(), grads=grads,
                   thetas=thetas)
    os.makedirs(os.path.dirname(OUT), exist_ok=True)
    with open(OUT, "w") as f:
        json.dump(fixture, f, indent=1)
    print(f"adan_edge: {steps} steps of a {list(theta.shape)} parameter -> {OUT}")


if __name__ == "__main__":
    main()
