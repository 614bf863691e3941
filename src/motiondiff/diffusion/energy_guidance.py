"""GuidedMotion's local-action energy guidance (paper §3.2): after each action-level denoising step,

    z_{t-1} <- z~_{t-1} - sum_k lambda_t^k grad_{z_t} E(c^k, z_t),   E(c, z) = ||z - c||^2,
    lambda_t^k = rho_t * e~^k * w_k,

so grad_{z_t} E = 2 (z_t - c^k): each local action's latent c^k pulls the sample towards itself with the graph
attention e~^k (``models.graph.action_weights``) times the user's weight w_k (default 1; 0 switches an action off).
The gradient is analytic; ``energy`` is kept for checking it against autograd.
"""

from __future__ import annotations

import torch

DEFAULT_RHO = 0.01  # the paper's rho


def energy(z: torch.Tensor, reference: torch.Tensor) -> torch.Tensor:
    """E(c, z) = ||z - c||^2 per sample (sum over every non-batch dim)."""
    return (z - reference).pow(2).flatten(1).sum(-1)


def guidance_weights(attention: torch.Tensor, user_weights=None, rho: float = DEFAULT_RHO) -> torch.Tensor:
    """lambda^k = rho · e~^k · w_k for K local actions; ``attention`` (..., K), ``user_weights`` (K,) or None."""
    w = torch.ones(attention.shape[-1]) if user_weights is None else torch.as_tensor(user_weights, dtype=torch.float32)
    if w.shape != attention.shape[-1:]:
        raise ValueError(f"{len(w)} user weights for {attention.shape[-1]} local actions: give one per action")
    return rho * attention * w.to(attention)


def energy_guidance_step(
    z_prev: torch.Tensor, z_t: torch.Tensor, references: torch.Tensor, weights: torch.Tensor
) -> torch.Tensor:
    """z_{t-1} - sum_k lambda^k · 2 (z_t - c^k). ``z_prev``, ``z_t``: (B, ...); ``references``: (B, K, ...) latents
    of the local actions; ``weights``: (B, K) lambda^k (0 for padded actions)."""
    if references.shape[:2] != weights.shape or references.shape[2:] != z_t.shape[1:]:
        raise ValueError(
            f"references {tuple(references.shape)} must be (B, K, *latent) with latent {tuple(z_t.shape[1:])} and "
            f"weights (B, K), got weights {tuple(weights.shape)}"
        )
    w = weights.reshape(*weights.shape, *([1] * (z_t.dim() - 1)))
    grad = (w * 2 * (z_t[:, None] - references)).sum(1)
    return z_prev - grad
