"""Diffusion in-painting's options: how an edit holds the known part of a motion while the rest is generated.

The sampling itself (``overwrite``: MDM's x̂0 replacement; ``repaint``: RePaint's re-noised known part) lives in
``lit.inpainting`` and runs through the one generation chain (``lit.generation.generate_features`` with known frames);
``inpaint``, ``renoise_known`` and ``EDIT_MODES`` are re-exported here for the callers that hold a batch themselves.

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

from motiondiff.lit.inpainting import EDIT_MODES, EditMode, inpaint, renoise_known

__all__ = ["EDIT_MODES", "SAMPLERS", "EditMode", "SamplingOptions", "inpaint", "renoise_known"]
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
        """Keyword arguments of ``inpaint`` and of ``generate_features`` with known frames (guidance only when there is
        one)."""
        kwargs = asdict(self)
        if kwargs["guidance"] is None:
            del kwargs["guidance"]
        return kwargs

    def sample_kwargs(self) -> dict:
        """Keyword arguments of ``module.sample`` for a window with nothing to hold (no mode, hold or guide)."""
        kwargs = self.inpaint_kwargs()
        del kwargs["mode"], kwargs["hold_from"], kwargs["reconstruction"]
        return kwargs
