"""Diffusion in-painting: generate the unknown part of a motion while the known part stays the input's.

Two ways to hold the known part, both on normalised features with a boolean ``keep`` mask:

- ``overwrite`` (MDM, Tevet et al. 2023 §4): at every step the network's x̂0 is replaced by the input where ``keep``,
  x̂0 ← keep ⊙ x_known + (1 − keep) ⊙ x̂0, so the next x_t is drawn around a clean estimate that already agrees with it.
- ``repaint`` (Lugmayr et al. 2022, without resampling): the step runs untouched, then the known part of x_{t−1} is
  replaced by a fresh forward-noised copy of the input, x_{t−1} ← keep ⊙ q(x_{t−1} | x_known) + (1 − keep) ⊙ x_{t−1}.

Either way the returned features equal the input exactly where ``keep`` (the last step is made clean on the mask).
A model trained with ``known_conditioning`` (in-painting-aware) is also given the clean known part as an input.
``resample=U`` (a sampler option, ``diffusion.samplers``) adds RePaint's resampling to either mode.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields, replace
from typing import Any, Literal

import torch

from motiondiff.diffusion.guidance import overwrite_known

EditMode = Literal["overwrite", "repaint"]
EDIT_MODES = ("overwrite", "repaint")
SAMPLERS = ("ddim", "ddpm")


@dataclass(frozen=True)
class SamplingOptions:
    """How an edit (in-betweening, body parts, a long motion's overlaps) samples: one definition for every caller.

    ``guidance=None``: the model's default when conditioned, unused when not. ``steps=None``: every step of the
    sampler. ``resample``: RePaint's repeats per step (1: none)."""

    mode: EditMode = "overwrite"
    guidance: float | None = None
    sampler: str = "ddim"
    steps: int | None = 50
    eta: float = 0.0
    resample: int = 1

    @classmethod
    def from_kwargs(cls, kwargs: dict, error: type[Exception] = ValueError) -> SamplingOptions:
        names = [f.name for f in fields(cls)]
        unknown = sorted(set(kwargs) - set(names))
        if unknown:
            raise error(f"unknown sampling option(s) {', '.join(unknown)}; the options are {', '.join(names)}")
        return cls(**kwargs)

    def resolved(self, module, conditioned: bool, error: type[Exception] = ValueError) -> SamplingOptions:
        """Checked against the model, with the guidance settled (the model's default, or None unconditioned)."""
        if self.mode not in EDIT_MODES:
            raise error(f"unknown edit mode {self.mode!r}; choose from {', '.join(EDIT_MODES)}")
        if self.sampler not in SAMPLERS:
            raise error(f"unknown sampler {self.sampler!r}; choose from {', '.join(SAMPLERS)}")
        if self.steps is not None and not 1 <= int(self.steps) <= module.diffusion.num_steps:
            raise error(f"steps must be between 1 and the model's {module.diffusion.num_steps}, got {self.steps}")
        if int(self.resample) != self.resample or self.resample < 1:
            raise error(f"resample must be a whole number >= 1 (1: no RePaint resampling), got {self.resample}")
        guidance = None
        if conditioned:
            guidance = module.default_guidance if self.guidance is None else float(self.guidance)
            if guidance < 0:
                raise error(f"guidance must be >= 0, got {guidance}")
        return replace(self, guidance=guidance, eta=float(self.eta), resample=int(self.resample))

    def as_dict(self) -> dict:
        return asdict(self)

    def inpaint_kwargs(self) -> dict:
        """Keyword arguments of ``inpaint`` (guidance only when there is one)."""
        kwargs = asdict(self)
        if kwargs["guidance"] is None:
            del kwargs["guidance"]
        return kwargs


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
    wherever ``keep`` (bool, broadcastable to (B, N, D)) is True. ``sample_kwargs``:
    guidance, sampler, steps, eta, resample, progress (see ``MotionDiffusionModule.sample``)."""
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
    # a model trained with known_conditioning also reads the known part directly (others ignore it)
    out = module.sample(cond, lengths, generator=generator, known=known, keep=keep, **hooks, **sample_kwargs)
    return torch.where(keep, known, out)
