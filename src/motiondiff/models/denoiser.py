"""MDM denoiser G(x_t, t, c): frame projection + time/condition token + a swappable backbone + output projection.

It knows nothing about noise schedules: it maps a noisy sequence to a prediction (x0, ε or v, as the diffusion code
decides) of the same shape.

With ``known_input=True`` the network also reads the clean known part of an edit (in-betweening frames, a kept body
part) per frame: ``known_proj([keep ⊙ x_known, keep])`` is added to the frame tokens. Sampling-time in-painting alone
(MDM's overwrite) only shows the known part through x_t, which at high noise carries almost none of it, so a small
model generates a middle that ignores the pose it must meet; seeing the clean known part fixes that. The projection
starts at zero, so a trained model fine-tuned with it starts from its own predictions.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import torch
from torch import Tensor, nn

from motiondiff.models.backbones import build_backbone
from motiondiff.models.conditioning import build_condition
from motiondiff.models.embeddings import TimestepEmbedder

# Network sizes as data, so configs and benchmarks can pick or edit them. "paper" = MDM appendix C (17.88 M params).
# Mirrors conf/model/*.yaml (what train.py uses); tests/unit/models/test_models.py checks they agree.
PRESETS: dict[str, dict[str, Any]] = {
    "paper": dict(d_model=512, num_layers=8, num_heads=4, ff_size=1024, dropout=0.1, activation="gelu"),
    "cpu": dict(d_model=128, num_layers=4, num_heads=4, ff_size=256, dropout=0.1, activation="gelu"),
}


class MDMDenoiser(nn.Module):
    def __init__(
        self, feature_dim: int, d_model: int, backbone: nn.Module, condition: nn.Module, known_input: bool = False
    ):
        super().__init__()
        if getattr(condition, "d_model", d_model) is None:  # NoCondition() built without a size takes ours
            condition.d_model = d_model
        for part, name in ((backbone, "backbone"), (condition, "condition")):
            if getattr(part, "d_model", d_model) != d_model:
                raise ValueError(f"{name} has d_model={part.d_model} but the denoiser has d_model={d_model}")
        self.feature_dim, self.d_model = feature_dim, d_model
        self.input_proj = nn.Linear(feature_dim, d_model)
        self.timestep_embedder = TimestepEmbedder(d_model)
        self.condition = condition
        self.backbone = backbone
        self.output_proj = nn.Linear(d_model, feature_dim)
        self.known_input = bool(known_input)
        if self.known_input:
            self.known_proj = nn.Linear(2 * feature_dim, d_model)
            nn.init.zeros_(self.known_proj.weight)
            nn.init.zeros_(self.known_proj.bias)

    def forward(
        self,
        x: Tensor,
        t: Tensor,
        cond: Tensor | None = None,
        mask: Tensor | None = None,
        drop_cond: Tensor | None = None,
        known: Tensor | None = None,
        keep: Tensor | None = None,
    ) -> Tensor:
        """x (B, N, D) noisy motion, t (B,) long steps, cond (B, cond_dim) text features | (B,) action ids | None,
        mask (B, N) bool True = valid frame, drop_cond (B,) bool True = use ∅. Returns (B, N, D).
        known (B, N, D) clean features and keep (B, N, D) bool where they are known: only for ``known_input``
        models (None: nothing known)."""
        if x.ndim != 3 or x.shape[-1] != self.feature_dim:
            raise ValueError(f"x must be (B, N, {self.feature_dim}), got {tuple(x.shape)}")
        batch, frames = x.shape[:2]
        if t.ndim == 0:
            t = t.expand(batch)
        if t.shape != (batch,):
            raise ValueError(f"t must be ({batch},) time steps, got {tuple(t.shape)}")
        if mask is not None and mask.shape != (batch, frames):
            raise ValueError(f"mask must be ({batch}, {frames}) bool, got {tuple(mask.shape)}")
        token = self.timestep_embedder(t) + self.condition(cond, drop_cond, batch_size=batch, device=x.device)
        h = self.input_proj(x)
        if self.known_input:
            h = h + self._known_tokens(known, keep, x)
        elif known is not None:
            raise ValueError("this denoiser was built without known_input: it cannot read a known part")
        h = self.backbone(h, token, mask)
        return self.output_proj(h)

    def _known_tokens(self, known: Tensor | None, keep: Tensor | None, x: Tensor) -> Tensor:
        if known is None:  # nothing known: the projection of all zeros is its bias
            return self.known_proj.bias
        if keep is None or known.shape != x.shape or keep.shape != x.shape:
            raise ValueError(f"known and keep must both be {tuple(x.shape)}, got {tuple(known.shape)} and "
                             f"{None if keep is None else tuple(keep.shape)}")  # fmt: skip
        keep = keep.to(x.dtype)
        return self.known_proj(torch.cat([known.to(x.dtype) * keep, keep], dim=-1))

    @classmethod
    def from_config(
        cls,
        feature_dim: int,
        *,
        preset: str | Mapping[str, Any] = "cpu",
        backbone: str = "trans_enc",
        condition: str = "text",
        cond_dim: int | None = None,
        num_actions: int | None = None,
        known_input: bool = False,
        **overrides: Any,
    ) -> MDMDenoiser:
        """Build from a preset name (or dict) plus overrides, e.g. from_config(263, preset="paper", cond_dim=512)."""
        if isinstance(preset, str):
            if preset not in PRESETS:
                raise ValueError(f"unknown preset {preset!r}; known: {', '.join(PRESETS)}")
            preset = PRESETS[preset]
        arch = {**preset, **overrides}
        d_model = arch["d_model"]
        return cls(
            feature_dim,
            d_model,
            backbone=build_backbone(backbone, **arch),
            condition=build_condition(condition, d_model, cond_dim=cond_dim, num_actions=num_actions),
            known_input=known_input,
        )


def build_denoiser(feature_dim: int, **kwargs: Any) -> MDMDenoiser:
    """Alias of MDMDenoiser.from_config for config `_target_`s."""
    return MDMDenoiser.from_config(feature_dim, **kwargs)


def count_parameters(module: nn.Module, trainable_only: bool = True) -> int:
    return sum(p.numel() for p in module.parameters() if p.requires_grad or not trainable_only)
