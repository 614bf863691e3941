"""Diffusion in-painting: generate the unknown part of a motion while the known part stays the input's.

Two ways to hold the known part, both on normalised features with a boolean ``keep`` mask:

- ``overwrite`` (MDM, Tevet et al. 2023 §4): at every step the network's x̂0 is replaced by the input where ``keep``,
  x̂0 ← keep ⊙ x_known + (1 − keep) ⊙ x̂0, so the next x_t is drawn around a clean estimate that already agrees with it.
- ``repaint`` (Lugmayr et al. 2022, without resampling): the step runs untouched, then the known part of x_{t−1} is
  replaced by a fresh forward-noised copy of the input, x_{t−1} ← keep ⊙ q(x_{t−1} | x_known) + (1 − keep) ⊙ x_{t−1}.

Either way the returned features equal the input exactly where ``keep`` (the last step is made clean on the mask).

``hold_from`` (a fraction of the chain, 1: every step, as MDM) holds the known part only at noise levels
t < hold_from · T: the first steps then sample from the condition alone, and the known part binds the rest. With
MDM's full hold, each step's x̂0 is drawn towards motions that go with the kept part, step after step, so on a
small model a condition it never saw next to that kept part (raised hands over walking legs) fades as the steps
add up (docs/results/editing/val_experiments.md). Holding later trades that harmonisation for following the condition.
``reconstruction`` (w_r, 0: off, as MDM) adds reconstruction guidance (Ho et al. 2022) to either mode: each held step's
x̂0 also moves by −(w_r √ᾱ_t / 2) ∇_{x_t} of its error on the known part, so the generated part moves with the
known one rather than only being placed next to it (``diffusion.guidance.reconstruction_guidance``; one backward
pass per step). A model trained with ``known_conditioning`` (in-painting-aware) is also given the clean known part
as an input.
``resample=U`` (a sampler option, ``diffusion.samplers``) adds RePaint's resampling to either mode.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields, replace
from typing import Any, Literal

import torch

from motiondiff.diffusion.guidance import overwrite_known, reconstruction_guidance

EditMode = Literal["overwrite", "repaint"]
EDIT_MODES = ("overwrite", "repaint")
SAMPLERS = ("ddim", "ddpm", "dpmpp")


@dataclass(frozen=True)
class SamplingOptions:
    """How an edit (in-betweening, body parts, a long motion's overlaps) samples: one definition for every caller.

    ``guidance=None``: the model's default when conditioned, unused when not. ``steps=None``: every step of the
    sampler. ``resample``: RePaint's repeats per step (1: none). ``hold_from``: the known part is held at noise
    levels t < hold_from · T (1: at every step, MDM; 0.3: over the last 30% of the chain). ``reconstruction``: the
    weight w_r of reconstruction guidance over the held steps (0: none, MDM)."""

    mode: EditMode = "overwrite"
    guidance: float | None = None
    sampler: str = "ddim"
    steps: int | None = 50
    eta: float = 0.0
    resample: int = 1
    hold_from: float = 1.0
    reconstruction: float = 0.0

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
        if self.sampler == "dpmpp" and self.resample != 1:
            raise error(f"sampler dpmpp has no RePaint resampling (resample={self.resample}); use sampler=ddim for it")
        hold = self.hold_from
        if isinstance(hold, bool) or not isinstance(hold, int | float) or not 0 < hold <= 1:
            raise error(
                f"hold_from is the share of the chain the known part is held over, in (0, 1] (1: every step, "
                f"MDM), got {self.hold_from}"
            )
        weight = self.reconstruction
        if isinstance(weight, bool) or not isinstance(weight, int | float) or not 0 <= weight < float("inf"):
            raise error(
                f"reconstruction is the weight of reconstruction guidance, a number >= 0 (0: off, MDM), got {weight}"
            )
        guidance = None
        if conditioned:
            guidance = module.default_guidance if self.guidance is None else float(self.guidance)
            if guidance < 0:
                raise error(f"guidance must be >= 0, got {guidance}")
        return replace(
            self, guidance=guidance, eta=float(self.eta), resample=int(self.resample), hold_from=float(self.hold_from),
            reconstruction=float(weight),
        )  # fmt: skip

    def as_dict(self) -> dict:
        return asdict(self)

    def inpaint_kwargs(self) -> dict:
        """Keyword arguments of ``inpaint`` (guidance only when there is one)."""
        kwargs = asdict(self)
        if kwargs["guidance"] is None:
            del kwargs["guidance"]
        return kwargs

    def sample_kwargs(self) -> dict:
        """Keyword arguments of ``module.sample`` for a window with nothing to hold (no mode, hold or guide)."""
        kwargs = self.inpaint_kwargs()
        del kwargs["mode"], kwargs["hold_from"], kwargs["reconstruction"]
        return kwargs


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
