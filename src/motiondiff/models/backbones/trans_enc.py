"""MDM's default backbone: the time/condition token is prepended to the frames and a Transformer encoder reads both."""

from __future__ import annotations

from typing import Any

import torch
from torch import Tensor, nn

from motiondiff.models.backbones.encoder_layer import FastDropoutEncoderLayer
from motiondiff.models.backbones.transformer import TransformerBackbone


class TransEncBackbone(TransformerBackbone):
    """[token, frames] + sinusoidal positions -> nn.TransformerEncoder -> frames (the token's output is dropped).

    Post-norm layers as in MDM (PyTorch defaults). batch_first=True lets PyTorch use its fused inference fast path;
    training drops out with a cheaper mask (``FastDropoutEncoderLayer``, the same parameters).
    """

    def build(self, layer_args: dict[str, Any], num_layers: int) -> None:
        # No nested tensors: they are a prototype API (warns on every padded eval call); the fused fast path stays.
        self.encoder = nn.TransformerEncoder(
            FastDropoutEncoderLayer(**layer_args), num_layers=num_layers, enable_nested_tensor=False
        )

    def forward(self, h: Tensor, token: Tensor, mask: Tensor | None = None) -> Tensor:
        seq = self.pos_encoding(torch.cat([token.unsqueeze(1), h], dim=1))  # positions cover the token too (MDM)
        pad = None
        if mask is not None and not bool(mask.all()):  # no mask at all keeps the cheaper unmasked attention
            keep = torch.cat([mask.new_ones(mask.shape[0], 1), mask.to(torch.bool)], dim=1)
            pad = ~keep  # True = ignore this key
        return self.encoder(seq, src_key_padding_mask=pad)[:, 1:]
