"""Known-frame sampling (in-painting): generate the unknown part of a motion while the known part stays the input's.

Two ways to hold the known part, both on normalised features with a boolean ``keep`` mask:

- ``overwrite`` (MDM, Tevet et al. 2023 §4): at every step the network's x̂0 is replaced by the input where ``keep``,
  x̂0 ← keep ⊙ x_known + (1 − keep) ⊙ x̂0, so the next x_t is drawn around a clean estimate that already agrees with it.
- ``repaint`` (Lugmayr et al. 2022, without resampling): the step runs untouched, then the known part of x_{t−1} is
  replaced by a fresh forward-noised copy of the input, x_{t−1} ← keep ⊙ q(x_{t−1} | x_known) + (1 − keep) ⊙ x_{t−1}.

Either way the returned features equal the input exactly where ``keep`` (the last step is made clean on the mask).
How ``hold_from`` and ``reconstruction`` trade harmonisation for following the condition: ``edit.inpaint``.
``generate_features`` (the one generation chain) samples through `inpaint` when it is given known frames.
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
import torch

from motiondiff.diffusion.guidance import overwrite_known, reconstruction_guidance

EditMode = Literal["overwrite", "repaint"]
EDIT_MODES = ("overwrite", "repaint")


def renoise_known(
    diffusion,
    known: torch.Tensor,
    keep: torch.Tensor,
    generator: torch.Generator | None = None,
    below: int | None = None,
):
    """An ``xt_hook`` for RePaint-style editing: the known part of x_{t−1} becomes q_sample(x_known, t−1) (only
    for t−1 < ``below`` when given)."""

    def hook(x: torch.Tensor, t_prev: int) -> torch.Tensor:
        if t_prev < 0:  # the clean result: the known part is the input itself
            return torch.where(keep, known, x)
        if below is not None and t_prev >= below:
            return x
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
    hold_from: float = 1.0,
    reconstruction: float = 0.0,
    generator: torch.Generator | None = None,
    **sample_kwargs: Any,
) -> torch.Tensor:
    """Sample normalised features (B, N, D) with ``module.sample`` that agree with ``known`` (B, N, D, normalised)
    wherever ``keep`` (bool, broadcastable to (B, N, D)) is True, held at noise levels t < ``hold_from`` · T, with
    reconstruction guidance of weight ``reconstruction`` there (0: none).
    ``sample_kwargs``: guidance, sampler, steps, eta, resample, progress (see ``MotionDiffusionModule.sample``)."""
    if mode not in EDIT_MODES:
        raise ValueError(f"unknown edit mode {mode!r}; choose from {', '.join(EDIT_MODES)}")
    b, n, d = known.shape
    if len(lengths) != b or int(lengths.max()) != n:
        raise ValueError(f"known has shape {tuple(known.shape)} but lengths {lengths.tolist()} ask for another batch")
    known = known.to(module.device, torch.float32)
    if not 0 < hold_from <= 1:
        raise ValueError(f"hold_from is a share of the chain in (0, 1] (1: every step), got {hold_from}")
    if not 0 <= reconstruction < float("inf"):
        raise ValueError(f"reconstruction is a guidance weight >= 0 (0: off), got {reconstruction}")
    keep = keep.to(module.device).expand(b, n, d)
    below = None if hold_from == 1 else round(hold_from * module.diffusion.num_steps)
    hooks = (
        {"x0_hook": overwrite_known(known, keep, below)}
        if mode == "overwrite"
        else {"xt_hook": renoise_known(module.diffusion, known, keep, generator, below)}
    )
    if reconstruction > 0:
        hooks["x0_guide"] = reconstruction_guidance(known, keep, reconstruction, below)
    # a model trained with known_conditioning also reads the known part directly (others ignore it)
    out = module.sample(cond, lengths, generator=generator, known=known, keep=keep, **hooks, **sample_kwargs)
    return torch.where(keep, known, out)


def known_batch(module, known: list, keep: list, idx: list[int]) -> tuple[torch.Tensor, torch.Tensor]:
    """The batch of items ``idx``: their de-normalised features (N_i, D) as normalised (B, N, D), padded with zero
    features before normalising, and their keep masks (N_i, D) as (B, N, D) bool, False on the padding."""
    lengths = [len(known[i]) for i in idx]
    b, n, d = len(idx), max(lengths), module.representation.dim
    feats = torch.zeros(b, n, d)
    mask = torch.zeros(b, n, d, dtype=torch.bool)
    for row, i in enumerate(idx):
        feats[row, : lengths[row]] = torch.from_numpy(np.asarray(known[i], dtype=np.float32))
        mask[row, : lengths[row]] = torch.from_numpy(np.asarray(keep[i]))
    return module.normalise(feats), mask
