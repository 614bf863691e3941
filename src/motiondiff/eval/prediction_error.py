"""How well a trained diffusion model predicts the clean motion and the noise at chosen noise levels.

Issue 43's account of ε-prediction (docs/results/eps_fix, eps_probe) reads models this way: real clips noised to t
with fixed draws, the unconditioned branch, the RMS of x̂0 − x0 and of ε̂ − ε whatever the network predicts. The
two errors are tied at each t (x̂0 − x0 = −√((1 − ᾱ_t)/ᾱ_t) (ε̂ − ε)), so which one a loss weighs decides where a
model of limited capacity spends it. ``noise_floor`` is the least ε error a network can reach when its output layer
has fewer dimensions than the features: white noise in the rest cannot be predicted.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import torch


def prediction_errors(
    module, x0: torch.Tensor, t_values: Sequence[int], noises: int = 1, seed: int = 0
) -> list[tuple[int, float, float]]:
    """(t, RMS of x̂0 − x0, RMS of ε̂ − ε) for each t: the clips ``x0`` (B, T, D; normalised features, every frame
    valid) noised to t with ``noises`` draws each from one generator seeded with ``seed``, the unconditioned branch
    of ``module`` (a MotionDiffusionModule: its ``denoiser`` and ``diffusion``)."""
    mask = torch.ones(x0.shape[:2], dtype=torch.bool)
    drop = torch.ones(len(x0), dtype=torch.bool)
    generator, rows = torch.Generator().manual_seed(seed), []
    for t in t_values:
        steps = torch.full((len(x0),), int(t))
        se_x0 = se_eps = 0.0
        for _ in range(noises):
            eps = torch.randn(x0.shape, generator=generator)
            x_t = module.diffusion.q_sample(x0, steps, eps)
            with torch.no_grad():
                out = module.denoiser(x_t, steps, cond=None, mask=mask, drop_cond=drop)
                x0_hat = module.diffusion.to_x0(out, x_t, steps)
            eps_hat = module.diffusion.eps_from_x0(x0_hat, x_t, steps)
            se_x0 += float((x0_hat - x0).pow(2).mean()) / noises
            se_eps += float((eps_hat - eps).pow(2).mean()) / noises
        rows.append((int(t), math.sqrt(se_x0), math.sqrt(se_eps)))
    return rows


def noise_floor(feature_dim: int, output_rank: int) -> float:
    """The least RMS error of an ε̂ confined to an ``output_rank``-dimensional subspace of ``feature_dim`` features
    when ε is white noise: the projection keeps output_rank/feature_dim of its variance, so √(1 − rank/dim)."""
    if feature_dim <= 0 or output_rank < 0:
        raise ValueError(f"feature_dim must be > 0 and output_rank >= 0, got {feature_dim} and {output_rank}")
    return math.sqrt(max(0.0, 1.0 - output_rank / feature_dim))
