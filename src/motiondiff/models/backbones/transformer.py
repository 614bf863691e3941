"""What MDM's two Transformer backbones (trans_enc, trans_dec) share: their sizes, the heads check and the positions."""

from __future__ import annotations

from typing import Any

from torch import nn

from motiondiff.models.embeddings import SinusoidalPositionalEncoding


class TransformerBackbone(nn.Module):
    """Checks the sizes, keeps d_model, adds sinusoidal positions; a subclass builds its layer stack in ``build``.

    ``build(layer_args, num_layers, **options)`` gets the keyword arguments of one PyTorch Transformer layer
    (batch_first=True) and the backbone's own options (trans_dec: ``input_token``).
    """

    def __init__(
        self,
        d_model: int,
        num_layers: int,
        num_heads: int,
        ff_size: int,
        dropout: float = 0.1,
        activation: str = "gelu",
        max_len: int = 5000,
        **options: Any,
    ):
        super().__init__()
        if d_model % num_heads:
            raise ValueError(f"d_model={d_model} must be divisible by num_heads={num_heads}")
        self.d_model = d_model
        self.pos_encoding = SinusoidalPositionalEncoding(d_model, max_len=max_len, dropout=dropout)
        layer_args = dict(d_model=d_model, nhead=num_heads, dim_feedforward=ff_size, dropout=dropout,
                          activation=activation, batch_first=True)  # fmt: skip
        self.build(layer_args, num_layers, **options)

    def build(self, layer_args: dict[str, Any], num_layers: int) -> None:
        raise NotImplementedError
