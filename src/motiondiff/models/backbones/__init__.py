"""Denoiser backbones, all with one interface so a config can swap them (`backbone=trans_enc`).

forward(h: (B, N, d) frame embeddings, token: (B, d) time + condition token, mask: (B, N) bool, True = valid frame)
-> (B, N, d). Padded frames' outputs may be anything but must not influence valid frames.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol, runtime_checkable

from torch import Tensor, nn

from motiondiff.models.backbones.trans_enc import TransEncBackbone


@runtime_checkable
class Backbone(Protocol):
    d_model: int

    def __call__(self, h: Tensor, token: Tensor, mask: Tensor | None = None) -> Tensor: ...


# name -> constructor taking keyword arguments (d_model, num_layers, ...). New backbones register here.
BACKBONES: dict[str, Callable[..., nn.Module]] = {
    "trans_enc": TransEncBackbone,
}


def build_backbone(name: str, **kwargs) -> nn.Module:
    if name not in BACKBONES:
        raise ValueError(f"unknown backbone {name!r}; known: {', '.join(sorted(BACKBONES))}")
    return BACKBONES[name](**kwargs)


__all__ = ["BACKBONES", "Backbone", "TransEncBackbone", "build_backbone"]
