"""Noise schedules: β_1..β_T as float64 tensors (the process casts them at use).

ᾱ_t = ∏_{s≤t} (1 − β_s). Index 0 is the first (least noisy) step, index T−1 the last.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import torch


def cosine_betas(num_steps: int, s: float = 0.008, max_beta: float = 0.999) -> torch.Tensor:
    """Nichol & Dhariwal 2021 (MDM's default): ᾱ(t) = f(t)/f(0), f(t) = cos²(((t/T) + s)/(1 + s) · π/2).

    β_i = 1 − ᾱ((i+1)/T)/ᾱ(i/T), clipped at ``max_beta`` (only the last step reaches it: f(1) = 0).
    """

    def f(u: float) -> float:
        return math.cos((u + s) / (1 + s) * math.pi / 2) ** 2

    betas = [min(1 - f((i + 1) / num_steps) / f(i / num_steps), max_beta) for i in range(num_steps)]
    return torch.tensor(betas, dtype=torch.float64)


def linear_betas(num_steps: int, beta_start: float | None = None, beta_end: float | None = None) -> torch.Tensor:
    """DDPM (Ho et al. 2020): β linear from 1e-4 to 0.02 at T = 1000, both scaled by 1000/T so any T gives a similar ᾱ_T."""
    scale = 1000.0 / num_steps
    start = scale * 1e-4 if beta_start is None else beta_start
    end = scale * 0.02 if beta_end is None else beta_end
    return torch.linspace(start, end, num_steps, dtype=torch.float64)


def scaled_linear_betas(num_steps: int, beta_start: float = 8.5e-4, beta_end: float = 0.012) -> torch.Tensor:
    """Latent diffusion / MLD / GuidedMotion: β = linspace(√start, √end, T)² (defaults: GuidedMotion's 8.5e-4 → 0.012, not rescaled by T)."""
    return torch.linspace(math.sqrt(beta_start), math.sqrt(beta_end), num_steps, dtype=torch.float64) ** 2


SCHEDULES: dict[str, Callable[..., torch.Tensor]] = {
    "cosine": cosine_betas,
    "linear": linear_betas,
    "scaled_linear": scaled_linear_betas,
}


def make_betas(name: str, num_steps: int, **kw: float) -> torch.Tensor:
    """β schedule by name (``cosine`` | ``linear`` | ``scaled_linear``), shape (T,), float64; ``kw`` go to the schedule."""
    if name not in SCHEDULES:
        raise ValueError(f"unknown noise schedule {name!r}; choose one of {sorted(SCHEDULES)}")
    if int(num_steps) != num_steps or num_steps < 1:
        raise ValueError(f"num_steps must be a positive integer, got {num_steps!r}")
    betas = SCHEDULES[name](int(num_steps), **kw)
    if not bool(((betas > 0) & (betas < 1)).all()):
        raise ValueError(
            f"schedule {name!r} with {kw} gives betas outside (0, 1): min {betas.min():.3g}, max {betas.max():.3g}; pass a smaller beta_end or more steps"
        )
    return betas
