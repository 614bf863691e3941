"""Reverse-process samplers as plain loops: DDPM (ancestral, optionally respaced) and DDIM.

``model_fn(x_t, t) -> raw network output`` (of the diffusion's prediction type), t a long tensor (B,) of ORIGINAL step
indices even when fewer steps are taken. Masks, conditions and guidance live in model_fn (see ``guidance.py``).
``x0_hook(x0_hat, t) -> x0_hat`` runs on every step's x̂0 (t the original step index, decreasing): editing overwrites
the known part there (MDM). ``xt_hook(x_prev, t_prev) -> x_prev`` runs on every step's result, t_prev the original
index of x_prev's noise level or -1 for the clean result: RePaint-style editing re-noises the known part there.
``x0_guide(predict_x0, x_t, alpha_bar_t, t) -> x0_hat`` (before ``x0_hook``) replaces the plain x̂0 = predict_x0(x_t)
with one that may differentiate through the network: reconstruction guidance (``guidance.reconstruction_guidance``).
``resample=U > 1`` (RePaint, Lugmayr et al. 2022, jump length 1) takes every step U times: after each of the first
U − 1 tries, x_{t_prev} is noised back to x_t by q(x_t | x_{t_prev}) and the step is taken again, giving the model U
looks at the hooked result so the generated part can agree with the known one. It costs U model calls per step.
No host sync inside the loops: per-step scalars come from float64 tables read once up front.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import torch
from tqdm import tqdm  # plain: tqdm.auto warns in notebooks without ipywidgets

from motiondiff.diffusion.process import GaussianDiffusion

ModelFn = Callable[[torch.Tensor, torch.Tensor], torch.Tensor]
X0Hook = Callable[[torch.Tensor, int], torch.Tensor]
XtHook = Callable[[torch.Tensor, int], torch.Tensor]
X0Guide = Callable[[Callable[[torch.Tensor], torch.Tensor], torch.Tensor, float, int], torch.Tensor]
# safe x̂0: a bound c (clamp to [−c, c], guided-diffusion's clip_denoised) or a rule x̂0 -> x̂0 (diffusion.thresholding)
ClipX0 = float | Callable[[torch.Tensor], torch.Tensor] | None


SPACINGS = ("uniform", "leading", "logsnr")


@dataclass(frozen=True)
class StepOptions:
    """What every sampler takes besides its own schedule, declared once: the start (``noise`` is x_T, else drawn from
    ``generator`` on ``device``/``dtype``), the hooks that shape each step (see the module docstring), RePaint's
    ``resample`` and a progress bar. The samplers take these as keywords (``ddim_sample(..., generator=g)``)."""

    noise: torch.Tensor | None = None
    generator: torch.Generator | None = None
    x0_hook: X0Hook | None = None
    xt_hook: XtHook | None = None
    x0_guide: X0Guide | None = None
    clip_x0: ClipX0 = None
    progress: bool = False
    resample: int = 1
    device: torch.device | str | None = None
    dtype: torch.dtype | None = None

    def initial_noise(self, shape: Sequence[int]) -> torch.Tensor:
        return _initial_noise(shape, self.noise, self.generator, self.device, self.dtype)

    def predict_x0(self, diffusion, model_fn, x, t_model, t_proc, t_index: int, alpha_bar_t: float) -> torch.Tensor:
        return _predict_x0(diffusion, model_fn, x, t_model, t_proc, self.clip_x0, self.x0_hook, t_index,
                           self.x0_guide, alpha_bar_t)  # fmt: skip

    def after_step(self, x: torch.Tensor, t_prev: int) -> torch.Tensor:
        return x if self.xt_hook is None else self.xt_hook(x, t_prev)


def select_timesteps(
    num_steps: int, steps: int | None = None, spacing: str = "uniform", alphas_cumprod: Sequence[float] | None = None
) -> list[int]:
    """``steps`` distinct indices in [0, T−1], ascending, always including 0 and, except for ``leading``, T−1.

    ``uniform`` (this project's DDIM default): k_i = round(i (T−1)/(S−1)); the spacing is ≥ 1 for S ≤ T.
    ``leading`` (the official MDM code's DDIM respacing, improved-diffusion's "ddimS"; S must divide T): k_i = i T/S,
    so DDIM-50 on T = 1000 takes 980, 960, …, 0 and never the last step, where ᾱ ≈ 2e-9 makes an ε model's x̂0 =
    (x_t − √(1−ᾱ) ε̂)/√ᾱ multiply ε̂'s error by ~2e4 (docs/results/eps_probe). ``logsnr`` (DPM-Solver's choice for
    low-dimensional data): the indices nearest to S values of λ = ½ log(ᾱ/(1−ᾱ)) evenly spaced from λ_{T−1}
    to λ_0 (``alphas_cumprod`` gives ᾱ), taken strictly decreasing from T−1 so that S stay distinct where λ crowds
    (the cosine schedule's last steps). ``None`` keeps all T.
    """
    steps = num_steps if steps is None else int(steps)
    if not 1 <= steps <= num_steps:
        raise ValueError(f"steps must be in [1, {num_steps}] (the process has {num_steps} steps), got {steps}")
    if spacing not in SPACINGS:
        raise ValueError(f"unknown timestep spacing {spacing!r}; choose one of {', '.join(SPACINGS)}")
    if spacing == "leading":
        if num_steps % steps:  # as space_timesteps("ddimS"), which refuses a stride that does not fit exactly
            fits = [s for s in range(1, num_steps + 1) if num_steps % s == 0]
            near = sorted(fits, key=lambda s: abs(s - steps))[:2]
            raise ValueError(
                f"leading timestep spacing takes a number of steps that divides {num_steps} (the "
                f"process's steps), got {steps}; the nearest are {' and '.join(map(str, sorted(near)))}"
            )
        return [i * (num_steps // steps) for i in range(steps)]
    if steps == 1:
        return [num_steps - 1]
    if spacing == "uniform" or steps == num_steps:
        return [(2 * i * (num_steps - 1) + steps - 1) // (2 * (steps - 1)) for i in range(steps)]
    if alphas_cumprod is None or len(alphas_cumprod) != num_steps:
        raise ValueError(f"logsnr spacing needs the process's {num_steps} values of alphas_cumprod")
    lam = [0.5 * math.log(a / (1.0 - a)) for a in alphas_cumprod]  # decreasing in t
    kept, previous = [], num_steps
    for i in range(steps):  # noisiest first
        target = lam[-1] + (lam[0] - lam[-1]) * i / (steps - 1)
        nearest = min(range(num_steps), key=lambda k: abs(lam[k] - target))
        previous = max(min(nearest, previous - 1), steps - 1 - i)  # distinct, and room left for the rest
        kept.append(previous)
    kept[-1] = 0
    return kept[::-1]


def _initial_noise(
    shape: Sequence[int],
    noise: torch.Tensor | None,
    generator: torch.Generator | None,
    device: torch.device | str | None,
    dtype: torch.dtype | None,
) -> torch.Tensor:
    if noise is not None:
        if tuple(noise.shape) != tuple(shape):
            raise ValueError(f"noise has shape {tuple(noise.shape)} but shape={tuple(shape)} was asked for")
        return noise.to(device=device or noise.device, dtype=dtype or noise.dtype)
    if device is None and generator is not None:
        device = generator.device
    return torch.randn(tuple(shape), generator=generator, device=device, dtype=dtype or torch.float32)


def _check_resample(resample: int) -> int:
    if int(resample) != resample or resample < 1:
        raise ValueError(f"resample must be a whole number >= 1 (1: no resampling), got {resample}")
    return int(resample)


def renoise_step(
    x_prev: torch.Tensor, alpha_bar: float, alpha_bar_prev: float, generator: torch.Generator | None
) -> torch.Tensor:
    """x_t ~ q(x_t | x_prev) = N(√(ᾱ_t/ᾱ_prev) x_prev, (1 − ᾱ_t/ᾱ_prev) I): one step back up the chain (RePaint)."""
    ratio = alpha_bar / alpha_bar_prev
    z = torch.randn(x_prev.shape, generator=generator, device=x_prev.device, dtype=x_prev.dtype)
    return math.sqrt(ratio) * x_prev + math.sqrt(1.0 - ratio) * z


def _predict_x0(
    diffusion: GaussianDiffusion,
    model_fn: ModelFn,
    x: torch.Tensor,
    t_model: torch.Tensor,
    t_proc: torch.Tensor,
    clip_x0: ClipX0,
    x0_hook: X0Hook | None,
    t_index: int,
    x0_guide: X0Guide | None,
    alpha_bar_t: float,
) -> torch.Tensor:
    def predict(x_t: torch.Tensor) -> torch.Tensor:
        x0_hat = diffusion.to_x0(model_fn(x_t, t_model), x_t, t_proc)
        if clip_x0 is None:
            return x0_hat
        return clip_x0(x0_hat) if callable(clip_x0) else x0_hat.clamp(-clip_x0, clip_x0)

    x0 = predict(x) if x0_guide is None else x0_guide(predict, x, alpha_bar_t, t_index)
    return x0 if x0_hook is None else x0_hook(x0, t_index)


@torch.inference_mode()
def ddpm_sample(
    diffusion: GaussianDiffusion,
    model_fn: ModelFn,
    shape: Sequence[int],
    *,
    steps: int | None = None,
    spacing: str = "uniform",
    **options,
) -> torch.Tensor:
    """Ancestral sampling (Ho et al. 2020; MDM): x̂0 = to_x0(model_fn(x_t, t)), then x_{t−1} ~ q(x_{t−1} | x_t, x̂0).

    ``steps=S < T`` samples the respaced process (``GaussianDiffusion.respace`` on ``select_timesteps(T, S,
    spacing)``).
    ``noise`` is x_T (else drawn from ``generator``); the last step adds no noise, so the result is the last x̂0.
    """
    o = StepOptions(**options)
    kept = select_timesteps(diffusion.num_steps, steps, spacing, diffusion.alphas_cumprod.tolist())
    resample, generator = _check_resample(o.resample), o.generator
    proc = diffusion if len(kept) == diffusion.num_steps else diffusion.respace(kept)
    alpha_bar = proc.alphas_cumprod.tolist()  # indexed like t_proc
    x = o.initial_noise(shape)
    batch = x.shape[0]
    for i in tqdm(range(len(kept) - 1, -1, -1), desc="DDPM", disable=not o.progress, leave=False):
        t_model = torch.full((batch,), kept[i], dtype=torch.long, device=x.device)
        t_proc = t_model if proc is diffusion else torch.full((batch,), i, dtype=torch.long, device=x.device)
        i_proc = kept[i] if proc is diffusion else i
        for u in range(resample if i > 0 else 1):
            if u > 0:
                x = renoise_step(x, alpha_bar[i_proc], alpha_bar[i_proc - 1], generator)
            x0 = o.predict_x0(proc, model_fn, x, t_model, t_proc, kept[i], alpha_bar[i_proc])
            mean, _, log_var = proc.q_posterior(x0, x, t_proc)
            if i == 0:
                x = mean
            else:
                z = torch.randn(x.shape, generator=generator, device=x.device, dtype=x.dtype)
                x = mean + (0.5 * log_var).exp() * z
            x = o.after_step(x, kept[i - 1] if i > 0 else -1)
    return x


def ddim_coefficients(alpha_bar: float, alpha_bar_prev: float, eta: float) -> tuple[float, float, float]:
    """DDIM step x_prev = c_x0 · x̂0 + c_eps · ε̂ + σ z (Song et al. 2021, eq. 12 and 16), returns (c_x0, c_eps, σ).

    σ = η √((1 − ᾱ_prev)/(1 − ᾱ_t)) √(1 − ᾱ_t/ᾱ_prev), c_x0 = √ᾱ_prev, c_eps = √(1 − ᾱ_prev − σ²).
    With consecutive steps and η = 1, σ² is the DDPM posterior variance β̃_t and the mean is the posterior mean.
    """
    sigma = (
        eta * math.sqrt((1 - alpha_bar_prev) / (1 - alpha_bar)) * math.sqrt(max(1 - alpha_bar / alpha_bar_prev, 0.0))
    )
    return math.sqrt(alpha_bar_prev), math.sqrt(max(1 - alpha_bar_prev - sigma**2, 0.0)), sigma


@torch.inference_mode()
def ddim_sample(
    diffusion: GaussianDiffusion,
    model_fn: ModelFn,
    shape: Sequence[int],
    *,
    steps: int = 50,
    eta: float = 0.0,
    spacing: str = "uniform",
    **options,
) -> torch.Tensor:
    """DDIM on ``select_timesteps(T, steps, spacing)`` from the highest kept step (T−1 but for ``leading``) down to 0;
    η = 0 is deterministic, η = 1 is DDPM-like.

    ε̂ is recomputed from the (clipped, hooked) x̂0, so edits made in ``x0_hook`` carry into the next x_t.
    The step from t = 0 goes to ᾱ_prev = 1, i.e. returns x̂0.
    """
    o = StepOptions(**options)
    alpha_bar = diffusion.alphas_cumprod.tolist()
    kept = select_timesteps(diffusion.num_steps, steps, spacing, alpha_bar)
    resample, generator = _check_resample(o.resample), o.generator
    x = o.initial_noise(shape)
    batch = x.shape[0]
    for i in tqdm(range(len(kept) - 1, -1, -1), desc="DDIM", disable=not o.progress, leave=False):
        t = torch.full((batch,), kept[i], dtype=torch.long, device=x.device)
        c_x0, c_eps, sigma = ddim_coefficients(alpha_bar[kept[i]], alpha_bar[kept[i - 1]] if i > 0 else 1.0, eta)
        for u in range(resample if i > 0 else 1):
            if u > 0:
                x = renoise_step(x, alpha_bar[kept[i]], alpha_bar[kept[i - 1]], generator)
            x0 = o.predict_x0(diffusion, model_fn, x, t, t, kept[i], alpha_bar[kept[i]])
            eps = diffusion.eps_from_x0(x0, x, t)
            x = c_x0 * x0 + c_eps * eps
            if sigma > 0:
                x = x + sigma * torch.randn(x.shape, generator=generator, device=x.device, dtype=x.dtype)
            x = o.after_step(x, kept[i - 1] if i > 0 else -1)
    return x
