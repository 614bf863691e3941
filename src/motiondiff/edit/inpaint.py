"""Diffusion in-painting: generate the unknown part of a motion while the known part stays the input's.

Two ways to hold the known part, both on normalised features with a boolean ``keep`` mask:

- ``overwrite`` (MDM, Tevet et al. 2023 §4): at every step the network's x̂0 is replaced by the input where ``keep``,
  x̂0 ← keep ⊙ x_known + (1 − keep) ⊙ x̂0, so the next x_t is drawn around a clean estimate that already agrees with it.
- ``repaint`` (Lugmayr et al. 2022, without resampling): the step runs untouched, then the known part of x_{t−1} is
  replaced by a fresh forward-noised copy of the input, x_{t−1} ← keep ⊙ q(x_{t−1} | x_known) + (1 − keep) ⊙ x_{t−1}.

Either way the returned features equal the input exactly where ``keep`` (the last step is made clean on the mask).
"""

from __future__ import annotations

from typing import Any, Literal

import torch

from motiondiff.diffusion.guidance import overwrite_known

EditMode = Literal["overwrite", "repaint"]
EDIT_MODES = ("overwrite", "repaint")


def renoise_known(diffusion, known: torch.Tensor, keep: torch.Tensor, generator: torch.Generator | None = None):
    """An ``xt_hook`` for RePaint-style editing: the known part of x_{t−1} becomes q_sample(x_known, t−1)."""

    def hook(x: torch.Tensor, t_prev: int) -> torch.Tensor:
        if t_prev < 0:  # the clean result: the known part is the input itself
            return torch.where(keep, known, x)
        t = torch.full((x.shape[0],), t_prev, dtype=torch.long, device=x.device)
        noise = torch.randn(x.shape, generator=generator, device=x.device, dtype=x.dtype)
        return torch.where(keep, diffusion.q_sample(known, t, noise), x)

    return hook


def inpaint(
    module,
    cond: Any,
    known: torch.Tensor,
    keep: torch.Tensor,
    lengths: torch.Tensor,
    *,
    mode: EditMode = "overwrite",
    generator: torch.Generator | None = None,
    **sample_kwargs: Any,
) -> torch.Tensor:
    """Sample normalised features (B, N, D) with ``module.sample`` that agree with ``known`` (B, N, D, normalised)
    wherever ``keep`` (bool, broadcastable to (B, N, D)) is True. ``sample_kwargs``: guidance, sampler, steps, eta,
    progress (see ``MotionDiffusionModule.sample``)."""
    if mode not in EDIT_MODES:
        raise ValueError(f"unknown edit mode {mode!r}; choose from {', '.join(EDIT_MODES)}")
    b, n, d = known.shape
    if len(lengths) != b or int(lengths.max()) != n:
        raise ValueError(f"known has shape {tuple(known.shape)} but lengths {lengths.tolist()} ask for another batch")
    known = known.to(module.device, torch.float32)
    keep = keep.to(module.device).expand(b, n, d)
    hooks = (
        {"x0_hook": overwrite_known(known, keep)}
        if mode == "overwrite"
        else {"xt_hook": renoise_known(module.diffusion, known, keep, generator)}
    )
    out = module.sample(cond, lengths, generator=generator, **hooks, **sample_kwargs)
    return torch.where(keep, known, out)
