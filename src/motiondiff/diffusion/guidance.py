"""Guidance wrappers that turn a conditional network into a sampler's ``model_fn(x_t, t)``.

The network interface: ``model(x [B, N, D], t [B] long, cond=..., mask=[B, N] bool, drop_cond=[B] bool | None) -> [B, N, D]``,
where ``drop_cond[b] = True`` makes sample b unconditional (the null condition ∅ learnt with condition dropout).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import torch

from motiondiff.diffusion.samplers import ModelFn, X0Guide, X0Hook


def _double(value: Any, batch: int) -> Any:
    """Repeat per-sample values for the [conditional; unconditional] batch: tensors with leading dim B (and dicts of
    them) are concatenated with themselves; anything else (scalars, None, non-batched tensors) passes unchanged."""
    if isinstance(value, torch.Tensor) and value.ndim > 0 and value.shape[0] == batch:
        return torch.cat([value, value])
    if isinstance(value, dict):
        return {k: _double(v, batch) for k, v in value.items()}
    return value


def classifier_free_guidance(
    model: Callable[..., torch.Tensor],
    x_t: torch.Tensor,
    t: torch.Tensor,
    cond: Any,
    scale: float | torch.Tensor,
    **model_kwargs: Any,
) -> torch.Tensor:
    """G_s = G(x_t, t, ∅) + s · (G(x_t, t, c) − G(x_t, t, ∅)) (Ho & Salimans 2022; MDM uses s = 2.5), in ONE forward.

    The batch is doubled: first half conditional (drop_cond False), second half unconditional (drop_cond True);
    ``t``, ``cond`` and every batched tensor in ``model_kwargs`` (e.g. ``mask``) are doubled with it.
    ``scale`` may be a float or a per-sample tensor (B,). Shortcuts: s = 1 is exactly the conditional forward and s = 0
    exactly the unconditional one (half the compute). ``cond=None`` means the model has no condition, so there is
    nothing to guide: the plain forward ``model(x_t, t, cond=None, **model_kwargs)`` is returned.
    """
    if "drop_cond" in model_kwargs:
        raise TypeError("classifier_free_guidance sets drop_cond itself; do not pass it in model_kwargs")
    if cond is None:
        return model(x_t, t, cond=None, **model_kwargs)
    batch = x_t.shape[0]
    keep = torch.zeros(batch, dtype=torch.bool, device=x_t.device)
    if not isinstance(scale, torch.Tensor) and scale in (0, 1):
        return model(x_t, t, cond=cond, drop_cond=keep if scale == 1 else ~keep, **model_kwargs)
    out = model(
        torch.cat([x_t, x_t]),
        torch.cat([t, t]),
        cond=_double(cond, batch),
        drop_cond=torch.cat([keep, ~keep]),
        **{k: _double(v, batch) for k, v in model_kwargs.items()},
    )
    conditional, unconditional = out[:batch], out[batch:]
    if isinstance(scale, torch.Tensor):
        scale = scale.to(device=out.device, dtype=out.dtype).reshape(scale.shape + (1,) * (out.ndim - scale.ndim))
    return unconditional + scale * (conditional - unconditional)


def guided_model_fn(
    model: Callable[..., torch.Tensor], cond: Any, scale: float | torch.Tensor, **model_kwargs: Any
) -> ModelFn:
    """``model_fn(x_t, t)`` for the samplers: classifier-free guidance at ``scale`` with fixed ``cond`` and kwargs (mask …)."""

    def model_fn(x_t: torch.Tensor, t: torch.Tensor) -> torch.Tensor:
        return classifier_free_guidance(model, x_t, t, cond, scale, **model_kwargs)

    return model_fn


def overwrite_known(known: torch.Tensor, keep: torch.Tensor, below: int | None = None) -> X0Hook:
    """An ``x0_hook`` for editing (MDM in-betweening, body-part editing): x̂0 ← where(keep, known, x̂0) at every step
    (or only at steps t < ``below``, so the first steps sample from the condition alone).

    ``keep`` is a bool tensor broadcastable to x (e.g. (B, N, 1) for frames, (1, 1, D) for feature dims); which
    frames or dims to keep is the caller's business (the representation knows the body parts).
    """

    def hook(x0_hat: torch.Tensor, t: int) -> torch.Tensor:
        if below is not None and t >= below:
            return x0_hat
        return torch.where(keep.to(x0_hat.device), known.to(x0_hat), x0_hat)

    return hook


def reconstruction_guidance(
    known: torch.Tensor, keep: torch.Tensor, weight: float, below: int | None = None
) -> X0Guide:
    """An ``x0_guide`` for editing: reconstruction guidance (Ho et al. 2022, Video Diffusion Models §3.1),

        x̃0 = x̂0 − (w_r √ᾱ_t / 2) ∇_{x_t} ‖keep ⊙ (x_known − x̂0(x_t))‖²,

    so the generated part moves with what the network would need to have predicted the known part itself.
    Overwriting x̂0 alone (MDM) fixes the known part but leaves the rest to follow it only through later steps; the
    gradient reaches the generated frames at once (a fast punch kept at the ends gets a fast middle). ``weight``
    is w_r (0 would be MDM; Ho et al. find w_r > 1 best); steps at t >= ``below`` are left alone, like the hooks.
    One backward pass through the network per step.
    """

    def guide(predict: Callable[[torch.Tensor], torch.Tensor], x_t: torch.Tensor, alpha_bar: float, t: int):
        if below is not None and t >= below:
            return predict(x_t)
        # the samplers run in inference mode: this step's graph needs ordinary tensors
        with torch.inference_mode(False), torch.enable_grad():
            x = x_t.clone().requires_grad_(True)
            x0_hat = predict(x)
            miss = torch.where(keep.clone().to(x.device), known.clone().to(x0_hat) - x0_hat, 0.0)
            (grad,) = torch.autograd.grad(miss.square().sum(), x)
        return (x0_hat - (weight * math.sqrt(alpha_bar) / 2) * grad).detach()

    return guide
