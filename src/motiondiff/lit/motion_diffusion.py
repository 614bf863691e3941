"""The model of MDM / vvMDM as a plain torch module: a denoiser with a Gaussian diffusion, sampled with guidance.

It owns what a checkpoint must carry to generate motion without the dataset: the denoiser, the diffusion settings, the
feature Mean/Std, the action names and the text encoder's name. Text conditions are looked up in a table of
pre-computed caption features (`set_text_table`). Sampling needs nothing more, so loading a model for generation does
not import Lightning (about 5 s of CPU at every start); `lit.diffusion.MotionDiffusionModule` adds the training steps.
"""

from __future__ import annotations

import numpy as np
import torch

from motiondiff.data.representations.spec import representation_from_spec
from motiondiff.diffusion import GaussianDiffusion, ddim_sample, ddpm_sample, dpmpp_sample, guided_model_fn, make_betas
from motiondiff.diffusion.samplers import SPACINGS
from motiondiff.diffusion.thresholding import make_threshold
from motiondiff.lit.geometric_losses import GeometricLoss
from motiondiff.lit.known_masks import random_known_keep
from motiondiff.models.backbones import build_backbone
from motiondiff.models.conditioning import build_condition
from motiondiff.models.denoiser import MDMDenoiser

# The samplers ``sample`` knows and each one's default steps (None: every step of the chain). "auto" (or None) in
# ``sample`` and the pipelines is the model's own default (``default_sampler``).
SAMPLER_STEPS = {"ddim": 50, "ddpm": None, "dpmpp": 7}


class HyperParameters(dict):
    """The constructor's arguments, read as attributes too (``hparams.feature_dim``), as Lightning's hparams are."""

    def __getattr__(self, name: str):
        try:
            return self[name]
        except KeyError:
            raise AttributeError(name) from None


class MotionDiffusion(torch.nn.Module):
    """The model: its denoiser, diffusion, normalisation and condition; ``hparams`` are the constructor's arguments
    (what a checkpoint or release stores to rebuild it)."""

    def __init__(
        self,
        feature_dim: int,
        model: dict,
        backbone: dict,
        condition: dict,
        diffusion: dict,
        optim: dict,
        mean: list[float],
        std: list[float],
        max_frames: int,
        fps: float,
        num_joints: int,
        action_names: list[str] | None = None,
        text_encoder: dict | None = None,
        dataset: str = "",
        representation: dict | None = None,
        loss: dict | None = None,
        known_conditioning: dict | None = None,
        x0_range: list[list[float]] | None = None,
    ):
        super().__init__()
        self._hparams = HyperParameters({k: v for k, v in locals().items() if k not in ("self", "__class__")})
        self.condition_kind = condition["kind"]
        self.cond_drop_prob = float(condition.get("drop_prob", 0.1))
        # Text-feature noise in training (condition.text_noise): each caption's prepared features (centred, unit mean
        # norm) get isotropic Gaussian noise of expected norm text_noise, so nearby wordings of one caption share its
        # motion (the nearest caption of another action is about 0.5 away, two of one action about 1.2).
        self.text_noise = float(condition.get("text_noise") or 0.0)
        cond_dim = text_encoder["dim"] if self.condition_kind == "text" else None
        self.denoiser = MDMDenoiser(
            feature_dim=feature_dim,
            d_model=model["d_model"],
            backbone=build_backbone(backbone["name"], **_backbone_kwargs(model, backbone)),
            condition=build_condition(
                self.condition_kind,
                model["d_model"],
                cond_dim=cond_dim,
                num_actions=len(action_names or []) or None,
            ),
            known_input=bool(known_conditioning),
        )
        self.diffusion = GaussianDiffusion(
            make_betas(diffusion["schedule"], diffusion["steps"]),
            prediction=diffusion["prediction"],
            weighting=diffusion.get("weighting"),  # None: the prediction type's default (abar_t for v)
        )
        # Input perturbation (Ning et al. 2023, DDPM-IP): x_t is built with noise ε + γ·ξ while the loss keeps ε, so
        # the denoiser learns inputs that do not match its own noise exactly, as its sampled x_t never do.
        self.input_perturbation = float(diffusion.get("input_perturbation") or 0.0)
        # How features decode to joints (None: HumanML3D features, as checkpoints from before representations).
        self.representation = representation_from_spec(representation, feature_dim)
        lambdas = {k: float(v) for k, v in (loss or {}).items() if k.startswith("lambda_")}
        threshold, reduction = (loss or {}).get("contact_threshold"), (loss or {}).get("reduction") or "mean"
        lambdas["time_weighting"] = (loss or {}).get("time_weighting") or "none"
        self.geometric = (GeometricLoss(self.representation, **lambdas, contact_threshold=threshold,
                                        reduction=reduction) if lambdas else None)  # fmt: skip
        if self.geometric is not None and not self.geometric.active:
            self.geometric = None
        # Safe x̂0 (guided-diffusion's clip_denoised, with the training data's per-feature range in place of images'
        # [-1, 1]): an ε model's x̂0 = (x_t − √(1−ᾱ) ε̂)/√ᾱ multiplies any error in ε̂ by 1/√ᾱ, about 2e4 at the last
        # step of the cosine schedule, and DDIM's first step carries it into x_t. diffusion.clip_x0: none | static |
        # dynamic (motiondiff.diffusion.thresholding); none by default, chosen on val (docs/results/safe_x0).
        self.register_buffer("x0_low", torch.tensor(x0_range[0] if x0_range else [], dtype=torch.float32),
                             persistent=False)  # fmt: skip
        self.register_buffer("x0_high", torch.tensor(x0_range[1] if x0_range else [], dtype=torch.float32),
                             persistent=False)  # fmt: skip
        self.clip_rule = None
        self.set_clip_rule(diffusion.get("clip_x0") if x0_range is not None else None)  # a bad rule fails here
        self.timestep_spacing = None
        self.set_timestep_spacing(diffusion.get("timestep_spacing"))
        self.register_buffer("mean", torch.tensor(mean, dtype=torch.float32))
        self.register_buffer("std", torch.tensor(std, dtype=torch.float32))
        # Caption features of the training data; rebuilt from the text cache at setup, not stored in checkpoints.
        self.register_buffer("text_table", torch.zeros(0, cond_dim or 0), persistent=False)
        self.text_index: dict[str, int] = {}
        # Sentence features of captions share one dominant direction (cosine 0.7-0.8 between "raises both hands"
        # and "raises the right hand"); centring them on the training captions and rescaling to unit mean norm makes
        # the differences between captions what the condition projection sees. Stored, so prompts get the same map.
        self.center_text = bool(condition.get("center_text", True))
        self.register_buffer("text_center", torch.zeros(cond_dim or 0))
        self.register_buffer("text_scale", torch.ones(()))
        # In-painting-aware training (see models/denoiser.py and lit/known_masks.py): how often a sample is shown a
        # known part, and the dims of each body part it may be shown.
        self.known_conditioning = dict(known_conditioning or {})
        if self.known_conditioning:
            skeleton = self.representation.skeleton
            parts = [self.representation.part_keep(joints) for joints in skeleton.parts.values()]
            self.register_buffer("part_masks", torch.tensor(np.array(parts), dtype=torch.bool), persistent=False)

    @property
    def hparams(self) -> HyperParameters:
        return self._hparams

    @property
    def device(self) -> torch.device:
        return self.mean.device

    # ---- conditions ---------------------------------------------------------------------------------------------
    def set_text_table(self, table: torch.Tensor, index: dict[str, int]) -> None:
        """Features (K, C) of every training caption and caption -> row; fixes the centring on first use."""
        table = table.to(self.device, torch.float32)
        if self.center_text and not bool(self.text_center.any()):
            self.text_center = table.mean(0)
            self.text_scale = (table - self.text_center).norm(dim=1).mean().clamp_min(1e-6)
        self.text_table = self.prepare_text(table)
        self.text_index = dict(index)

    def prepare_text(self, features: torch.Tensor) -> torch.Tensor:
        """Encoder features -> what the condition projection receives (same map for captions and prompts)."""
        return (features.to(self.text_center) - self.text_center) / self.text_scale

    def batch_condition(self, batch: dict):
        """The raw condition of a training batch: caption features by table lookup, action ids, or None."""
        if self.condition_kind == "text":
            try:
                rows = [self.text_index[t] for t in batch["text"]]
            except KeyError as err:
                raise RuntimeError(f"caption {err} has no pre-computed feature: call set_text_table first") from None
            return self.text_table[torch.tensor(rows, device=self.device)]
        if self.condition_kind == "action":
            return batch["action"]
        return None

    # ---- training -----------------------------------------------------------------------------------------------
    def _loss(
        self, batch: dict, drop_prob: float, perturb: bool = True
    ) -> tuple[torch.Tensor, dict[str, torch.Tensor]]:
        """Total loss and its parts: the diffusion loss, plus MDM's geometric terms when `loss` enables them.
        ``perturb``: apply the input perturbation (training only; validation measures the plain loss)."""
        x0, mask = batch["motion"], batch["mask"]
        b = x0.shape[0]
        t = torch.randint(0, self.diffusion.num_steps, (b,), device=x0.device)
        noise = torch.randn_like(x0)
        gamma = self.input_perturbation if perturb else 0.0
        perturbed = noise + gamma * torch.randn_like(x0) if gamma else noise
        x_t = self.diffusion.q_sample(x0, t, perturbed)
        drop = torch.rand(b, device=x0.device) < drop_prob
        known = {}
        if self.known_conditioning:
            keep = random_known_keep(
                mask, self.part_masks, float(self.known_conditioning.get("prob", 0.5)),
                float(self.known_conditioning.get("frame_share", 0.5)),
            )  # fmt: skip
            known = {"known": x0, "keep": keep}
        cond = self.batch_condition(batch)
        if perturb and self.text_noise and self.condition_kind == "text":
            cond = cond + torch.randn_like(cond) * (self.text_noise / cond.shape[-1] ** 0.5)
        out = self.denoiser(x_t, t, cond=cond, mask=mask, drop_cond=drop, **known)
        loss = self.diffusion.loss(out, x0, noise, t, mask=mask)
        parts = {"diffusion": loss.detach()}
        if self.geometric is not None:
            x0_hat = self.diffusion.to_x0(out.float(), x_t.float(), t)
            weighted = self.geometric.time_weighting == "alpha_bar"
            alpha_bar = self.diffusion.alpha_bar(t) if weighted else None
            geo, terms = self.geometric(x0_hat, x0, mask, self.mean, self.std, alpha_bar=alpha_bar)
            loss = loss + geo
            parts.update(terms)
        return loss, parts

    # ---- sampling -----------------------------------------------------------------------------------------------
    @torch.inference_mode()
    def sample(
        self,
        cond,
        lengths: torch.Tensor,
        guidance: float = 2.5,
        sampler: str = "ddim",
        steps: int | None = 50,
        eta: float = 0.0,
        generator: torch.Generator | None = None,
        progress: bool = False,
        x0_hook=None,
        xt_hook=None,
        resample: int = 1,
        x0_guide=None,
        known: torch.Tensor | None = None,
        keep: torch.Tensor | None = None,
    ) -> torch.Tensor:
        """Generate normalised features (B, max(lengths), D); frames past each length are padding. ``sampler``: one of
        ``SAMPLER_STEPS`` or "auto" (`default_sampler`) (``steps=None``: its default; ``eta`` is DDIM's only). ``resample``:
        RePaint's repeats per step for editing; ``x0_hook``, ``xt_hook``, ``x0_guide``: see ``diffusion.samplers``.
        ``known``/``keep`` (B, N, D): the clean known part of an edit, read by models trained with
        ``known_conditioning`` (ignored by others)."""
        self.eval()
        sampler = self.resolve_sampler(sampler)
        b, n = len(lengths), int(lengths.max())
        mask = torch.arange(n, device=self.device)[None] < lengths.to(self.device)[:, None]
        extra = {}
        if self.denoiser.known_input and known is not None:
            extra = {"known": known.to(self.device, torch.float32), "keep": keep.to(self.device).expand(known.shape)}
        if cond is None:  # unconditioned: the model's ∅ condition (what guidance uses as its unconditional half)
            drop = torch.ones(b, dtype=torch.bool, device=self.device)

            def fn(x, t):
                return self.denoiser(x, t, cond=None, mask=mask, drop_cond=drop, **extra)
        else:
            fn = guided_model_fn(self.denoiser, cond, guidance, mask=mask, **extra)
        shape = (b, n, self.hparams.feature_dim)
        clip = make_threshold(self.clip_rule, self.x0_low, self.x0_high, mask=mask)
        options = dict(generator=generator, x0_hook=x0_hook, xt_hook=xt_hook, x0_guide=x0_guide, progress=progress,
                       resample=resample, device=self.device, clip_x0=clip)  # fmt: skip
        if self.timestep_spacing is not None:  # else each sampler's own (DDIM, DDPM: uniform; DPM-Solver++: logsnr)
            options["spacing"] = self.timestep_spacing
        if sampler == "ddim":
            return ddim_sample(self.diffusion, fn, shape, steps=steps or self.default_steps("ddim"), eta=eta, **options)
        if sampler == "ddpm":
            return ddpm_sample(self.diffusion, fn, shape, steps=steps, **options)
        if sampler == "dpmpp":  # DPM-Solver++(2M); eta is unused (the solver is deterministic)
            return dpmpp_sample(self.diffusion, fn, shape, steps=steps or self.default_steps("dpmpp"), **options)
        raise ValueError(f"unknown sampler {sampler!r}; choose one of {', '.join(SAMPLER_STEPS)}")

    def set_clip_rule(self, rule: str | None) -> None:
        """Sample with another safe-x̂0 rule (none | static | dynamic) than the one the model was trained with."""
        if make_threshold(rule, self.x0_low, self.x0_high) is not None and not self.x0_low.numel():
            raise ValueError("this model has no x0 range (trained before safe x̂0): only clip_x0=none is possible")
        self.clip_rule = rule

    def set_timestep_spacing(self, spacing: str | None) -> None:
        """Sample on other steps than each sampler's own (None): uniform | leading (the official MDM code's DDIM
        respacing, which never visits t = T−1) | logsnr (``diffusion.samplers.select_timesteps``)."""
        if spacing is not None and spacing not in SPACINGS:
            raise ValueError(f"unknown timestep spacing {spacing!r}; choose one of {', '.join(SPACINGS)} (or null)")
        self.timestep_spacing = spacing

    @property
    def default_guidance(self) -> float:
        return float(self.hparams.model.get("sample_guidance", 2.5))

    @property
    def default_sampler(self) -> str:
        """The sampler generation uses when none is named: ``model.sample_sampler`` where the model's recipe chose
        one on val (the action model keeps DDIM-50: DPM-Solver++-7 missed its FID), else DPM-Solver++ (7 steps)."""
        return str(self.hparams.model.get("sample_sampler", "dpmpp"))

    def default_steps(self, sampler: str) -> int | None:
        """The steps `sampler` runs when none are given: ``model.sample_steps`` for the model's own sampler where its
        recipe chose the pair on val, else the sampler's usual count (``SAMPLER_STEPS``; None: DDPM's whole chain)."""
        own = self.hparams.model.get("sample_steps")
        return int(own) if own and sampler == self.default_sampler else SAMPLER_STEPS[sampler]

    def resolve_sampler(self, name: str | None) -> str:
        """``name``, or the model's `default_sampler` for "auto"/None; an unknown name is refused."""
        name = self.default_sampler if name in (None, "auto") else name
        if name not in SAMPLER_STEPS:
            raise ValueError(f"unknown sampler {name!r}; choose auto or one of {', '.join(SAMPLER_STEPS)}")
        return name

    @property
    def default_smooth_sigma(self) -> float | None:
        """vvMDM temporal smoothing applied to this model's samples by default (Gaussian sigma in frames; None: off)."""
        sigma = self.hparams.model.get("sample_smooth_sigma")
        return float(sigma) if sigma else None

    def normalise(self, features: torch.Tensor) -> torch.Tensor:
        """De-normalised features -> what the denoiser works on (the inverse of ``denormalise``)."""
        return (features.to(self.mean) - self.mean) / self.std

    def denormalise(self, features: torch.Tensor) -> torch.Tensor:
        return features * self.std + self.mean

    def joints(self, features: torch.Tensor) -> torch.Tensor:
        """De-normalised features (..., N, D) -> joint positions (..., N, J, 3) of `self.representation.skeleton`."""
        return self.representation.decode(features.float())


def _backbone_kwargs(model: dict, backbone: dict) -> dict:
    size = {k: model[k] for k in ("d_model", "num_layers", "num_heads", "ff_size", "dropout", "activation")}
    return {**size, **{k: v for k, v in backbone.items() if k != "name"}}
