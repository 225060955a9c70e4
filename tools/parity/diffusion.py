"""Parity fixtures for `dancegen_nn::diffusion` (tests/parity_diffusion.rs).

Written from the published formulas (see the Rust module docs for each source):
- EDGE (`model/utils.py`, `model/diffusion.py`): cosine / linear schedules and their tables,
  the strided DDIM step with classifier-free guidance and x0 clamp, the DDPM posterior step,
  the long-form window overwrite and the final cross-fade / slerp stitching.
- ReactDance's layer-decoupled guidance `(1 + s_r) cond - s_r unc` per channel group.
- Lodge++ PDDM (paper eq. 9, 13): residual-shifting forward process and reverse step, with
  ResShift's eta schedule.

Tables are computed in float64; tensors are float32 like the Rust side.

    python tools/parity/diffusion.py
"""

import math

import torch

from common import randn, seeded, write

T = 1000
PROBE_T = [0, 1, 2, 10, 100, 500, 900, 979, 998, 999]


def make_betas(kind, n=T):
    if kind == "cosine":
        s = 8e-3
        ts = torch.arange(n + 1, dtype=torch.float64) / n + s
        a = torch.cos(ts / (1 + s) * math.pi / 2).pow(2)
        a = a / a[0]
        return (1 - a[1:] / a[:-1]).clamp(0, 0.999)
    return torch.linspace(1e-4 ** 0.5, 2e-2 ** 0.5, n, dtype=torch.float64) ** 2


def tables(betas):
    ac = torch.cumprod(1 - betas, 0)
    acp = torch.cat([torch.ones(1, dtype=torch.float64), ac[:-1]])
    pv = betas * (1 - acp) / (1 - ac)
    return {
        "betas": betas,
        "alphas_cumprod": ac,
        "alphas_cumprod_prev": acp,
        "sqrt_alphas_cumprod": ac.sqrt(),
        "sqrt_one_minus_alphas_cumprod": (1 - ac).sqrt(),
        "sqrt_recip_alphas_cumprod": (1 / ac).sqrt(),
        "sqrt_recipm1_alphas_cumprod": (1 / ac - 1).sqrt(),
        "posterior_variance": pv,
        "posterior_log_variance_clipped": pv.clamp(min=1e-20).log(),
        "posterior_mean_coef1": betas * acp.sqrt() / (1 - ac),
        "posterior_mean_coef2": (1 - acp) * (1 - betas).sqrt() / (1 - ac),
    }


COS = tables(make_betas("cosine"))


def schedule():
    io = {}
    idx = torch.tensor(PROBE_T)
    for kind in ["cosine", "linear"]:
        for k, v in tables(make_betas(kind)).items():
            io[f"out.{kind}.{k}"] = v[idx].float()
    g = seeded(10)
    x0 = randn(g, 3, 4, 5)
    noise = randn(g, 3, 4, 5)
    ts = [0, 500, 999]
    a = COS["sqrt_alphas_cumprod"][ts].float().view(3, 1, 1)
    s = COS["sqrt_one_minus_alphas_cumprod"][ts].float().view(3, 1, 1)
    io |= {"in.x0": x0, "in.noise": noise, "in.t": torch.tensor(ts), "out.q_sample": a * x0 + s * noise}
    for steps in [50, 7]:
        times = torch.linspace(-1, T - 1, steps=steps + 1)
        io[f"out.ddim_times_{steps}"] = torch.tensor(list(reversed(times.int().tolist())))
    write("diffusion_schedule", {}, io, {"probe_t": PROBE_T, "timesteps": T})


def ddim_cfg():
    g = seeded(11)
    B, L, C = 2, 6, 5
    x_t = randn(g, B, L, C)
    cond = randn(g, B, L, C, scale=0.8)
    unc = randn(g, B, L, C, scale=0.8)
    noise = randn(g, B, L, C)
    t, tn, eta, w = 979, 959, 1.0, 2.0
    groups, default_s = [((0, 2), 1.5), ((2, 4), 0.25)], 0.5

    def step(x0):
        x0 = x0.clamp(-1, 1)
        a, an = COS["alphas_cumprod"][t].item(), COS["alphas_cumprod"][tn].item()
        eps = (COS["sqrt_recip_alphas_cumprod"][t].item() * x_t - x0) / \
            COS["sqrt_recipm1_alphas_cumprod"][t].item()
        sigma = eta * math.sqrt((1 - a / an) * (1 - an) / (1 - a))
        c = math.sqrt(1 - an - sigma ** 2)
        return x0 * math.sqrt(an) + c * eps + sigma * noise

    wc = torch.full((C,), 1 + default_s)
    for (lo, hi), s in groups:
        wc[lo:hi] = 1 + s
    io = {
        "in.x_t": x_t, "in.x0_cond": cond, "in.x0_uncond": unc, "in.noise": noise,
        "out.next": step(unc + w * (cond - unc)),
        "out.next_ldcfg": step((1 + wc - 1) * cond - (wc - 1) * unc),
        "out.last": (unc + w * (cond - unc)).clamp(-1, 1),
    }
    write("diffusion_ddim_cfg", {}, io, {
        "t": t, "t_next": tn, "eta": eta, "w": w, "default_s": default_s,
        "groups": [[lo, hi, s] for (lo, hi), s in groups]})


def ddpm():
    g = seeded(12)
    x_t = randn(g, 2, 5, 3)
    x0 = randn(g, 2, 5, 3, scale=0.5)
    noise = randn(g, 2, 5, 3)
    io = {"in.x_t": x_t, "in.x0": x0, "in.noise": noise}
    for t in [500, 1, 0]:
        mean = COS["posterior_mean_coef1"][t].item() * x0 + COS["posterior_mean_coef2"][t].item() * x_t
        sd = math.exp(0.5 * COS["posterior_log_variance_clipped"][t].item())
        io[f"out.t{t}"] = mean + (sd * noise if t > 0 else 0)
    write("diffusion_ddpm", {}, io, {"ts": [500, 1, 0]})


def resshift_etas(steps, kappa, p, eta_1, eta_t):
    b0 = math.exp(math.log(eta_t / eta_1) / (2 * (steps - 1)))
    beta = (torch.arange(steps, dtype=torch.float64) / (steps - 1)) ** p * (steps - 1)
    return torch.cat([torch.zeros(1, dtype=torch.float64), (math.sqrt(eta_1) * b0 ** beta) ** 2])


def pddm():
    steps, kappa, p = 50, 2.0, 0.3
    eta_1, eta_t = min((0.04 / kappa) ** 2, 1e-3), 0.999
    eta = resshift_etas(steps, kappa, p, eta_1, eta_t)
    g = seeded(13)
    B, L, C = 3, 4, 6
    d0 = randn(g, B, L, C, scale=0.5)
    dp = randn(g, B, L, C, scale=0.5)
    noise = randn(g, B, L, C)
    ts = [1, 25, 50]
    e = eta[ts].float().view(B, 1, 1)
    sd = (kappa * eta[ts].sqrt()).float().view(B, 1, 1)
    q = d0 + e * (dp - d0) + sd * noise  # eq. (9)
    x0 = randn(g, B, L, C, scale=0.5)
    z = randn(g, B, L, C)
    t = 30
    a = (eta[t] - eta[t - 1]).item()
    et, ep = eta[t].item(), eta[t - 1].item()
    step = ep / et * q + a / et * x0 + kappa * math.sqrt(ep * a / et) * z  # eq. (13)
    io = {"in.d0": d0, "in.dp": dp, "in.noise": noise, "in.t": torch.tensor(ts),
          "in.x0": x0, "in.z": z, "out.eta": eta.float(), "out.q_sample": q, "out.step": step}
    write("diffusion_pddm", {}, io, {"steps": steps, "kappa": kappa, "p": p, "eta_1": eta_1,
                                     "eta_t": eta_t, "step_t": t})


def rot6d_to_matrix(d):
    a1, a2 = d[..., :3], d[..., 3:]
    b1 = a1 / a1.norm(dim=-1, keepdim=True)
    b2 = a2 - (b1 * a2).sum(-1, keepdim=True) * b1
    b2 = b2 / b2.norm(dim=-1, keepdim=True)
    return torch.stack([b1, b2, torch.cross(b1, b2, dim=-1)], -2)


def matrix_to_quat(m):
    m = [[m[i][j].item() for j in range(3)] for i in range(3)]
    tr = m[0][0] + m[1][1] + m[2][2]
    if tr > 0:
        s = math.sqrt(tr + 1) * 2
        q = [0.25 * s, (m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s]
    elif m[0][0] > m[1][1] and m[0][0] > m[2][2]:
        s = math.sqrt(1 + m[0][0] - m[1][1] - m[2][2]) * 2
        q = [(m[2][1] - m[1][2]) / s, 0.25 * s, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s]
    elif m[1][1] > m[2][2]:
        s = math.sqrt(1 + m[1][1] - m[0][0] - m[2][2]) * 2
        q = [(m[0][2] - m[2][0]) / s, (m[0][1] + m[1][0]) / s, 0.25 * s, (m[1][2] + m[2][1]) / s]
    else:
        s = math.sqrt(1 + m[2][2] - m[0][0] - m[1][1]) * 2
        q = [(m[1][0] - m[0][1]) / s, (m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, 0.25 * s]
    q = torch.tensor(q, dtype=torch.float64)
    return q / q.norm()


def quat_to_matrix(q):
    w, x, y, z = q.tolist()
    return torch.tensor([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]], dtype=torch.float64)


def slerp(a, b, w):
    dot = float((a * b).sum())
    if dot < 0:
        b, dot = -b, -dot
    if dot > 0.9995:
        r = a + w * (b - a)
        return r / r.norm()
    th = math.acos(min(dot, 1.0))
    r = math.sin((1 - w) * th) / math.sin(th) * a + math.sin(w * th) / math.sin(th) * b
    return r / r.norm()


def longform():
    g = seeded(14)
    N, W, C = 3, 8, 13  # channel 0 linear, 1..13 = two 6D rotations
    x = randn(g, N, W, C)
    h = W // 2
    over = x.clone()
    over[1:, :h] = x[:-1, h:]  # EDGE long_ddim_sample
    xs = over.double()
    out = torch.zeros(W + (N - 1) * h, C, dtype=torch.float64)
    out[:h] = xs[0, :h]
    out[N * h:] = xs[-1, h:]
    wts = torch.linspace(0, 1, h, dtype=torch.float64)
    for i in range(N - 1):
        for j in range(h):
            w = wts[j].item()
            f = (i + 1) * h + j
            a, b = xs[i, h + j], xs[i + 1, j]
            out[f, 0] = (1 - w) * a[0] + w * b[0]
            for gch in [1, 7]:
                qa = matrix_to_quat(rot6d_to_matrix(a[gch:gch + 6]))
                qb = matrix_to_quat(rot6d_to_matrix(b[gch:gch + 6]))
                m = quat_to_matrix(slerp(qa, qb, w))
                out[f, gch:gch + 6] = m[:2].reshape(6)
    write("diffusion_longform", {}, {"in.x": x, "out.overwritten": over, "out.stitched": out.float()},
          {"rot6d": [[1, 13]]})


if __name__ == "__main__":
    schedule()
    ddim_cfg()
    ddpm()
    pddm()
    longform()
