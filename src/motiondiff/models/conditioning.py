"""Condition embedders: a raw condition -> (B, d) vector that is added to the time-step embedding.

Every embedder returns zeros for the rows where `drop_cond` is True. That zero vector is the "∅" condition of
classifier-free guidance: training drops ~10% of conditions, sampling mixes G(x, t, ∅) and G(x, t, c).
(MDM zeroes the raw CLIP feature *before* its Linear, so its ∅ is the Linear's bias; here ∅ is exactly zero, which
makes it the same token as the unconditional model's.)

Text features are precomputed by a frozen encoder (motiondiff.text) and cached, so only the Linear lives here.
"""

from __future__ import annotations

import torch
from torch import Tensor, nn


def _batch_size(cond: Tensor | None, drop_cond: Tensor | None, batch_size: int | None) -> int:
    for source in (
        batch_size,
        None if cond is None else cond.shape[0],
        None if drop_cond is None else drop_cond.shape[0],
    ):
        if source is not None:
            return int(source)
    raise ValueError("cannot infer the batch size: pass cond, drop_cond or batch_size")


def _check_drop(drop_cond: Tensor | None, batch: int) -> None:
    if drop_cond is not None and (drop_cond.dtype != torch.bool or drop_cond.shape != (batch,)):
        raise ValueError(f"drop_cond must be a ({batch},) bool tensor, got {tuple(drop_cond.shape)} {drop_cond.dtype}")


def _drop(emb: Tensor, drop_cond: Tensor | None) -> Tensor:
    # torch.where, not multiplication: a NaN/inf in a dropped condition must not leak into the output.
    if drop_cond is None:
        return emb
    return torch.where(drop_cond.to(emb.device).unsqueeze(-1), torch.zeros((), dtype=emb.dtype, device=emb.device), emb)


class ConditionEmbedder(nn.Module):
    """Base class. `forward(cond, drop_cond=None, *, batch_size=None, device=None) -> (B, d_model)`.

    Subclasses with a real condition implement `_check(cond, batch)` and `_embed(cond, drop_cond)`; the batch size,
    the drop mask and the all-∅ batch (no cond at all, e.g. the unconditional half of CFG) are handled here once.
    """

    d_model: int | None
    kind: str = "base"
    expects: str = ""  # what cond must be, for messages

    def _null(self, batch: int, device: torch.device | str | None) -> Tensor:
        if self.d_model is None:
            raise ValueError(f"{type(self).__name__} has no d_model; give it one or pass it to a denoiser")
        return torch.zeros(batch, self.d_model, device=device)

    def forward(
        self,
        cond: Tensor | None,
        drop_cond: Tensor | None = None,
        *,
        batch_size: int | None = None,
        device: torch.device | str | None = None,
    ) -> Tensor:
        batch = _batch_size(cond, drop_cond, batch_size)
        _check_drop(drop_cond, batch)
        if cond is None:
            if drop_cond is not None and bool(drop_cond.all()):
                param = next(self.parameters(), None)
                return self._null(batch, device if device is not None else getattr(param, "device", None))
            raise ValueError(f"{self.kind} condition needs cond = {self.expects}; for ∅ pass drop_cond all True")
        self._check(cond, batch)
        return _drop(self._embed(cond, drop_cond), drop_cond)

    def _check(self, cond: Tensor, batch: int) -> None:
        raise NotImplementedError

    def _embed(self, cond: Tensor, drop_cond: Tensor | None) -> Tensor:
        raise NotImplementedError


class TextCondition(ConditionEmbedder):
    """Precomputed text-encoder feature (B, cond_dim) float -> Linear -> (B, d)."""

    kind = "text"
    expects = "(B, cond_dim) text features"

    def __init__(self, cond_dim: int, d_model: int):
        super().__init__()
        self.cond_dim, self.d_model = cond_dim, d_model
        self.proj = nn.Linear(cond_dim, d_model)

    def _check(self, cond: Tensor, batch: int) -> None:
        if cond.ndim != 2 or cond.shape != (batch, self.cond_dim) or not cond.is_floating_point():
            raise ValueError(
                f"text condition expects ({batch}, {self.cond_dim}) float features, got {tuple(cond.shape)} {cond.dtype}; is cond_dim the text encoder's dim?"
            )

    def _embed(self, cond: Tensor, drop_cond: Tensor | None) -> Tensor:
        return self.proj(cond.to(self.proj.weight.dtype))


class ActionCondition(ConditionEmbedder):
    """Action class index (B,) long -> learned (B, d) embedding, one vector per class (MDM: d params per class)."""

    kind = "action"
    expects = "(B,) class indices"

    def __init__(self, num_actions: int, d_model: int):
        super().__init__()
        if num_actions < 1:
            raise ValueError(f"num_actions must be >= 1, got {num_actions}")
        self.num_actions, self.d_model = num_actions, d_model
        self.embedding = nn.Embedding(num_actions, d_model)

    def _check(self, cond: Tensor, batch: int) -> None:
        if cond.shape != (batch,) or cond.is_floating_point() or cond.dtype == torch.bool:
            raise ValueError(
                f"action condition expects ({batch},) integer class indices, got {tuple(cond.shape)} {cond.dtype}"
            )

    def _embed(self, cond: Tensor, drop_cond: Tensor | None) -> Tensor:
        idx = cond.long() if drop_cond is None else cond.long().masked_fill(drop_cond.to(cond.device), 0)
        if bool(((idx < 0) | (idx >= self.num_actions)).any()):
            raise ValueError(f"action index out of range [0, {self.num_actions}): {idx.tolist()}")
        return self.embedding(idx)


class NoCondition(ConditionEmbedder):
    """Unconditional model: always the ∅ (zero) vector, no parameters. d_model is filled in by the denoiser."""

    kind = "none"

    def __init__(self, d_model: int | None = None):
        super().__init__()
        self.d_model = d_model

    def forward(
        self,
        cond: Tensor | None = None,
        drop_cond: Tensor | None = None,
        *,
        batch_size: int | None = None,
        device: torch.device | str | None = None,
    ) -> Tensor:
        batch = _batch_size(cond, drop_cond, batch_size)
        return self._null(batch, device)


CONDITION_KINDS = ("text", "action", "none")


def build_condition(
    kind: str, d_model: int, cond_dim: int | None = None, num_actions: int | None = None
) -> ConditionEmbedder:
    """Factory used by configs: kind "text" needs cond_dim (the text encoder's dim), "action" needs num_actions."""
    if kind == "text":
        if not cond_dim:
            raise ValueError("condition 'text' needs cond_dim = the text encoder's feature size (512 CLIP, 384 MiniLM)")
        return TextCondition(cond_dim, d_model)
    if kind == "action":
        if not num_actions:
            raise ValueError("condition 'action' needs num_actions = the dataset's number of action classes")
        return ActionCondition(num_actions, d_model)
    if kind == "none":
        return NoCondition(d_model)
    raise ValueError(f"unknown condition kind {kind!r}; known: {', '.join(CONDITION_KINDS)}")
