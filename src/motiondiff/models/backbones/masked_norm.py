"""GroupNorm whose statistics come from the valid frames only (for the 1-D U-Net backbone).

nn.GroupNorm averages over the whole time axis, so a clip's normalisation would depend on how much padding the batch
gave it. Counting only valid positions makes a padded clip normalise exactly as it would alone.
"""

from __future__ import annotations

import torch
from torch import Tensor, nn


class MaskedGroupNorm(nn.Module):
    """(B, C, L) features, (B, 1, L) float mask (1 = valid) -> group-normalised features; same parameters as GroupNorm."""

    def __init__(self, num_groups: int, num_channels: int, eps: float = 1e-5):
        super().__init__()
        if num_channels % num_groups:
            raise ValueError(f"num_channels={num_channels} must be divisible by num_groups={num_groups}")
        self.num_groups, self.eps = num_groups, eps
        self.weight = nn.Parameter(torch.ones(num_channels))
        self.bias = nn.Parameter(torch.zeros(num_channels))

    def forward(self, x: Tensor, mask: Tensor) -> Tensor:
        batch, channels, length = x.shape
        groups = self.num_groups
        dtype = torch.promote_types(x.dtype, torch.float32)  # statistics in >= float32 (bf16 sums are too coarse)
        m = mask.to(dtype).unsqueeze(1)  # (B, 1, 1, L)
        xg = x.to(dtype).reshape(batch, groups, channels // groups, length) * m
        count = (m.sum(dim=-1, keepdim=True) * (channels // groups)).clamp(min=1.0)  # (B, 1, 1, 1) valid values/group
        mean = xg.sum(dim=(2, 3), keepdim=True) / count
        centred = (xg - mean) * m
        var = centred.pow(2).sum(dim=(2, 3), keepdim=True) / count
        out = (centred * torch.rsqrt(var + self.eps)).reshape(batch, channels, length)
        return (out * self.weight[:, None].to(dtype) + self.bias[:, None].to(dtype)).to(x.dtype)
