"""Sinusoidal embeddings shared by the denoisers: frame positions and diffusion time steps (as MDM)."""

from __future__ import annotations

import math

import torch
from torch import Tensor, nn

from motiondiff.models.fast_dropout import FastDropout


def _check_even(d_model: int) -> None:
    if d_model <= 0 or d_model % 2:
        raise ValueError(f"d_model must be a positive even number for sin/cos pairs, got {d_model}")


def sinusoidal_features(positions: Tensor, d_model: int) -> Tensor:
    """(…) positions -> (…, d_model) with interleaved [sin, cos] pairs, the Transformer/MDM layout.

    Frequencies are 1 / 10000^(2i/d); element 2i is sin, 2i+1 is cos.
    """
    _check_even(d_model)
    i = torch.arange(0, d_model, 2, device=positions.device, dtype=torch.float32)
    freqs = torch.exp(i * (-math.log(10000.0) / d_model))
    angles = positions.to(torch.float32).unsqueeze(-1) * freqs
    return torch.stack([angles.sin(), angles.cos()], dim=-1).flatten(-2)


class SinusoidalPositionalEncoding(nn.Module):
    """Adds fixed sinusoidal positions to a batch-first (B, L, d) sequence, then dropout."""

    def __init__(self, d_model: int, max_len: int = 5000, dropout: float = 0.1):
        super().__init__()
        self.d_model = d_model
        self.max_len = max_len
        self.dropout = FastDropout(dropout)  # nn.Dropout with a cheaper mask (motiondiff.models.fast_dropout)
        # Not persistent: recomputed from (d_model, max_len), so checkpoints do not carry a 10 MB constant.
        pe = sinusoidal_features(torch.arange(max_len), d_model).unsqueeze(0)
        self.register_buffer("pe", pe, persistent=False)

    def forward(self, x: Tensor) -> Tensor:
        length = x.shape[1]
        if length > self.max_len:
            raise ValueError(
                f"sequence of {length} positions exceeds max_len={self.max_len} of the positional encoding"
            )
        return self.dropout(x + self.pe[:, :length].to(x.dtype))


class TimestepEmbedder(nn.Module):
    """Integer diffusion step t (B,) -> (B, d): sinusoidal features -> Linear -> SiLU -> Linear (MDM's time MLP)."""

    def __init__(self, d_model: int):
        super().__init__()
        _check_even(d_model)
        self.d_model = d_model
        self.mlp = nn.Sequential(nn.Linear(d_model, d_model), nn.SiLU(), nn.Linear(d_model, d_model))

    def forward(self, t: Tensor) -> Tensor:
        # Computed on the fly rather than read from a table, so any step count T works.
        feats = sinusoidal_features(t, self.d_model).to(self.mlp[0].weight.dtype)
        return self.mlp(feats)
