"""Denoiser backbones, all with one interface so a config can swap them (`backbone=trans_enc`).

MDM's backbone ablation (paper Table 1/8): trans_enc (default), trans_dec (token via cross-attention; `input_token`
for "+ input token"), gru (token concatenated to every frame) and unet (1-D convolutions over time).

forward(h: (B, N, d) frame embeddings, token: (B, d) time + condition token, mask: (B, N) bool, True = valid frame)
-> (B, N, d). Padded frames' outputs may be anything but must not influence valid frames.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol, runtime_checkable

from torch import Tensor, nn

from motiondiff.models.backbones.gru import GRUBackbone
from motiondiff.models.backbones.trans_dec import TransDecBackbone
from motiondiff.models.backbones.trans_enc import TransEncBackbone
from motiondiff.models.backbones.unet import UNetBackbone


@runtime_checkable
class Backbone(Protocol):
    d_model: int

    def __call__(self, h: Tensor, token: Tensor, mask: Tensor | None = None) -> Tensor: ...


# name -> constructor taking keyword arguments (d_model, num_layers, ...). New backbones register here.
BACKBONES: dict[str, Callable[..., nn.Module]] = {
    "trans_enc": TransEncBackbone,
    "trans_dec": TransDecBackbone,
    "gru": GRUBackbone,
    "unet": UNetBackbone,
}


def build_backbone(name: str, **kwargs) -> nn.Module:
    if name not in BACKBONES:
        raise ValueError(f"unknown backbone {name!r}; known: {', '.join(sorted(BACKBONES))}")
    return BACKBONES[name](**kwargs)


__all__ = [
    "BACKBONES",
    "Backbone",
    "GRUBackbone",
    "TransDecBackbone",
    "TransEncBackbone",
    "UNetBackbone",
    "build_backbone",
]
