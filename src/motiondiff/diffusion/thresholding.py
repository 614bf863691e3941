"""Safe x̂0: keep a sampler's clean-sample estimate inside the data's range.

An ε model's x̂0 = (x_t − √(1−ᾱ_t) ε̂)/√ᾱ_t multiplies any error in ε̂ by 1/√ᾱ_t (about 2e4 at the last step of the
cosine schedule), and DDIM's first step carries that into x_t. Both rules are no-ops while x̂0 lies in the range:
- ``static``: clamp to [low, high] per feature (guided-diffusion's clip_denoised, images' [-1, 1] generalised);
- ``dynamic``: Imagen's dynamic thresholding (Saharia et al. 2022, §2.3) on the range mapped to [-1, 1]: s is the
  99.5th percentile of |x̂0| per sample; where s > 1, x̂0 is clamped to [-s, s] and divided by s, so an estimate
  blown up by noise keeps its shape at the range's scale instead of piling onto the bounds.
"""

from __future__ import annotations

from collections.abc import Callable

import torch

Threshold = Callable[[torch.Tensor], torch.Tensor]
RULES = ("static", "dynamic")


def static_clip(low: torch.Tensor, high: torch.Tensor) -> Threshold:
    def clip(x0: torch.Tensor) -> torch.Tensor:
        return x0.clamp(low.to(x0), high.to(x0))

    return clip


def dynamic_threshold(
    low: torch.Tensor, high: torch.Tensor, percentile: float = 0.995, mask: torch.Tensor | None = None
) -> Threshold:
    """``mask`` (B, N): the valid frames of (B, N, D) motions; the percentile ignores padding, whose x̂0 no loss
    ever constrained (one padded frame far out of range would otherwise shrink the whole motion at every step)."""

    def threshold(x0: torch.Tensor) -> torch.Tensor:
        centre, half = ((high + low) / 2).to(x0), ((high - low) / 2).clamp_min(1e-6).to(x0)
        z = (x0 - centre) / half
        size = z.abs().float()
        if mask is not None:
            size = size.masked_fill(~mask.to(z.device)[..., None].expand_as(size), float("nan"))
        s = torch.nanquantile(size.flatten(1), percentile, dim=1).clamp_min(1.0).to(x0)
        s = s.view(-1, *([1] * (z.dim() - 1)))
        return centre + half * z.clamp(-s, s) / s

    return threshold


def make_threshold(
    rule: str | None, low: torch.Tensor, high: torch.Tensor, mask: torch.Tensor | None = None
) -> Threshold | None:
    """The x̂0 rule by name (``static`` | ``dynamic``), or None for ``None``/``"none"``; ``mask`` (B, N): valid frames."""
    if rule in (None, "none", False):
        return None
    if rule not in RULES:
        raise ValueError(f"unknown x0 clipping {rule!r}; choose none, static or dynamic")
    return static_clip(low, high) if rule == "static" else dynamic_threshold(low, high, mask=mask)
