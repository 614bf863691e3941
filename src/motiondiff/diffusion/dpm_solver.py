"""DPM-Solver++ (Lu et al. 2022, "DPM-Solver++: Fast Solver for Guided Sampling of Diffusion Probabilistic Models",
arXiv 2211.01095): a multistep solver of the probability-flow ODE in data (x̂0) prediction, for few-step sampling.

With α_t = √ᾱ_t, σ_t = √(1 − ᾱ_t) and λ_t = log(α_t/σ_t), the ODE's exact solution from s to t (λ rises) is
x_t = (σ_t/σ_s) x_s + σ_t ∫_{λ_s}^{λ_t} e^λ x̂0(λ) dλ (variation of constants in λ). With h = λ_t − λ_s and u = λ − λ_s,
σ_t ∫ e^λ u^k/k! dλ = α_t c_k(h) with c_0 = 1 − e^{−h} and c_k = h^k/k! − c_{k−1}, so a Taylor expansion of x̂0 in λ
gives x_t = (σ_t/σ_s) x_s + α_t Σ_k c_k x̂0^{(k)}(λ_s). Multistep solvers estimate the derivatives from the x̂0 of
earlier steps, one network call per step: order 1 keeps k = 0 (DDIM with η = 0); order 2 is Algorithm 2 (2M), x̂0
replaced by D = (1 + 1/(2r)) x̂0_s − 1/(2r) x̂0_{s'} with r = h_{s'}/h; order 3 keeps k ≤ 2, with x̂0' and x̂0'' of the
quadratic through the last three x̂0. Data prediction keeps the steps bounded under guidance and x̂0 clipping, which
is why the paper prefers it to DPM-Solver's noise prediction for guided sampling.
The steps are evenly spaced in λ by default (``samplers.select_timesteps``, "logsnr"), the paper's choice for
low-dimensional data; on DDIM's evenly spaced t the shipped text model's FID at 10 steps was twice DDIM-50's, in λ
it matches it (docs/results/few_step_sampling.md). The order ramps up over the first steps (too little history) and down
over the last ones, the paper's lower-order final steps: the λ gap into t = 0 is several times the one before it,
and extrapolating x̂0 across it overshoots, so that step is first order and the one before it at most second. The
last step goes to ᾱ = 1 (h = ∞) and returns x̂0, as DDIM does.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import torch
from tqdm import tqdm  # plain: tqdm.auto warns in notebooks without ipywidgets

from motiondiff.diffusion.process import GaussianDiffusion
from motiondiff.diffusion.samplers import ModelFn, StepOptions, select_timesteps

ORDERS = (1, 2, 3)


def _step_orders(num: int, order: int) -> list[int]:
    """The order of each of ``num`` updates, first to last: it ramps up with the history at the start and down again
    at the end (the update into t = 0 is first order, the one before it at most second), and the last update, to
    ᾱ = 1, returns x̂0."""
    return [1 if j == num - 1 else min(order, j + 1, num - 1 - j) for j in range(num)]


def _update(
    x: torch.Tensor,
    history: list[torch.Tensor],
    lambdas: list[float],
    lam_t: float,
    alpha_t: float,
    sigma_ratio: float,
    order: int,
) -> torch.Tensor:
    """One multistep update from λ_s = lambdas[-1] to λ_t; ``history``: the x̂0 at ``lambdas`` (newest last)."""
    if math.isinf(lam_t):  # ᾱ_t = 1: σ_t = 0 and c_0 = 1, the clean sample is x̂0
        return history[-1]
    h = lam_t - lambdas[-1]
    c0 = -math.expm1(-h)
    m0 = history[-1]
    if order == 1:
        return sigma_ratio * x + (alpha_t * c0) * m0
    h0 = lambdas[-1] - lambdas[-2]
    m1 = history[-2]
    if order == 2:  # Algorithm 2: D = (1 + 1/(2r)) m0 − 1/(2r) m1, r = h0/h
        w = h / (2.0 * h0)
        return sigma_ratio * x + (alpha_t * c0 * (1.0 + w)) * m0 - (alpha_t * c0 * w) * m1
    h1 = lambdas[-2] - lambdas[-3]
    m2 = history[-3]
    c1 = h - c0
    c2 = 0.5 * h * h - c1
    # Newton's quadratic through (λ_{s''}, m2), (λ_{s'}, m1), (λ_s, m0): x̂0' ≈ d01 + h0 d012, x̂0'' ≈ 2 d012 (the
    # factor 2 matters: weighting d012 by c2 alone, half the Taylor term, leaves the update second order)
    d01 = (m0 - m1) / h0
    d012 = (d01 - (m1 - m2) / h1) / (h0 + h1)
    return sigma_ratio * x + (alpha_t * c0) * m0 + (alpha_t * c1) * (d01 + h0 * d012) + (2.0 * alpha_t * c2) * d012


@torch.inference_mode()
def dpmpp_sample(
    diffusion: GaussianDiffusion,
    model_fn: ModelFn,
    shape: Sequence[int],
    *,
    steps: int = 10,
    order: int = 2,
    spacing: str = "logsnr",
    **options,
) -> torch.Tensor:
    """DPM-Solver++ of ``order`` (1, 2: 2M, 3: 3M) on ``select_timesteps(T, steps, spacing)``: by default steps
    evenly spaced in log-SNR, the paper's choice for low-dimensional data (``uniform``: the steps DDIM takes).

    Deterministic given x_T (``noise``, else drawn from ``generator``). Hooks as in ``samplers.ddim_sample``:
    ``clip_x0``, ``x0_guide`` and ``x0_hook`` shape each step's x̂0 before it enters the history, and ``xt_hook``
    gets each step's result with t_prev (−1 for the clean one). ``resample`` exists for a uniform signature: RePaint's
    resampling re-noises x_t, which the multistep history cannot follow, so only 1 is accepted.
    """
    o = StepOptions(**options)
    if order not in ORDERS:
        raise ValueError(f"DPM-Solver++ order must be one of {list(ORDERS)}, got {order!r}")
    if o.resample != 1:
        raise ValueError(f"sampler dpmpp has no RePaint resampling (resample={o.resample}); use sampler=ddim for it")
    alpha_bar = diffusion.alphas_cumprod.tolist()
    kept = select_timesteps(diffusion.num_steps, steps, spacing, alpha_bar)
    # α, σ and λ of every kept step, then of the clean end (ᾱ = 1: σ = 0, λ = ∞): float64 on the host, read once
    levels = [alpha_bar[k] for k in kept[::-1]] + [1.0]
    alphas = [math.sqrt(a) for a in levels]
    sigmas = [math.sqrt(1.0 - a) for a in levels]
    lambdas = [math.inf if s == 0.0 else math.log(a / s) for a, s in zip(alphas, sigmas, strict=True)]
    orders = _step_orders(len(kept), order)
    x = o.initial_noise(shape)
    batch = x.shape[0]
    history: list[torch.Tensor] = []
    for j in tqdm(range(len(kept)), desc="DPM-Solver++", disable=not o.progress, leave=False):
        i = len(kept) - 1 - j  # index into kept, from T−1 down to 0
        t = torch.full((batch,), kept[i], dtype=torch.long, device=x.device)
        x0 = o.predict_x0(diffusion, model_fn, x, t, t, kept[i], alpha_bar[kept[i]])
        history = [*history[-2:], x0]
        ratio = sigmas[j + 1] / sigmas[j]
        x = _update(x, history, lambdas[max(0, j - 2) : j + 1], lambdas[j + 1], alphas[j + 1], ratio, orders[j])
        x = o.after_step(x, kept[i - 1] if i > 0 else -1)
    return x
