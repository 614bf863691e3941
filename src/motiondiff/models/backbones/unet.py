"""MDM's U-Net baseline (paper Sec. 4.1, Table 1): a 1-D U-Net over time with the features as channels.

MDM adapts the image-diffusion U-Net to motion by replacing 2-D convolutions with 1-D ones along time, so the
joint/feature axis becomes the channels ("due to the irregular behavior of the joint axis"); it reports FID 1.137 and
23.47 M parameters, but not the exact layout. This one is a plain DDPM-style layout: `blocks_per_level` residual conv
blocks per resolution, `levels` stride-2 down-samplings (widths d * channel_mults[i]) with skip connections, nearest
up-sampling, and the time + condition token injected into every block as FiLM (res_block.py).

Variable lengths: N is padded up to a multiple of 2**levels and cropped back. Padded positions are zeroed before every
convolution (the down-sampled mask is the max-pooled one) and GroupNorm statistics count valid positions only
(masked_norm.py). A padded clip therefore gives, on its valid frames, what it gives alone: its outputs depend neither
on the values of the padded frames nor on how many there are (up to float rounding).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import torch
import torch.nn.functional as F
from torch import Tensor, nn

from motiondiff.models.backbones.masked_norm import MaskedGroupNorm
from motiondiff.models.backbones.res_block import ResBlock1d, make_activation


class UNetBackbone(nn.Module):
    """(B, N, d) frames -> 1-D U-Net on (B, d, N) -> (B, N, d); padded outputs are zeros.

    num_layers, num_heads and ff_size are accepted so every backbone takes the model preset, and ignored.
    """

    def __init__(
        self,
        d_model: int,
        num_layers: int | None = None,
        num_heads: int | None = None,
        ff_size: int | None = None,
        dropout: float = 0.1,
        activation: str = "gelu",
        levels: int = 2,
        channel_mults: Sequence[int] = (1, 2),
        blocks_per_level: int = 2,
        num_groups: int = 32,
    ):
        super().__init__()
        del num_layers, num_heads, ff_size  # transformer settings
        channel_mults = [int(m) for m in channel_mults]
        if levels < 1 or len(channel_mults) != levels:
            raise ValueError(f"channel_mults needs one width multiplier per level: levels={levels}, {channel_mults}")
        if blocks_per_level < 1:
            raise ValueError(f"blocks_per_level must be >= 1, got {blocks_per_level}")
        self.d_model, self.levels = d_model, levels
        widths = [d_model] + [d_model * m for m in channel_mults]  # resolution r has widths[r] channels

        def blocks(c_in: int, c_out: int) -> nn.ModuleList:
            return nn.ModuleList(
                ResBlock1d(c, c_out, d_model, math.gcd(num_groups, c_out), dropout, activation)
                for c in [c_in] + [c_out] * (blocks_per_level - 1)
            )

        self.down = nn.ModuleList(blocks(widths[r], widths[r]) for r in range(levels))
        self.downsample = nn.ModuleList(
            nn.Conv1d(widths[r], widths[r + 1], kernel_size=3, stride=2, padding=1) for r in range(levels)
        )
        self.mid = blocks(widths[levels], widths[levels])
        self.upsample = nn.ModuleList(
            nn.Conv1d(widths[r + 1], widths[r], kernel_size=3, padding=1) for r in range(levels)
        )
        self.up = nn.ModuleList(blocks(2 * widths[r], widths[r]) for r in range(levels))  # input: [upsampled, skip]
        self.out_norm = MaskedGroupNorm(math.gcd(num_groups, d_model), d_model)
        self.out_act = make_activation(activation)

    def forward(self, h: Tensor, token: Tensor, mask: Tensor | None = None) -> Tensor:
        batch, frames, _ = h.shape
        extra = -frames % (2**self.levels)
        valid = torch.ones(batch, frames, dtype=torch.bool, device=h.device) if mask is None else mask.to(torch.bool)
        m = F.pad(valid.to(h.dtype).unsqueeze(1), (0, extra))  # (B, 1, L); the internal padding is invalid too
        x = F.pad(h.transpose(1, 2), (0, extra)) * m
        skips: list[tuple[Tensor, Tensor]] = []
        for blocks, down in zip(self.down, self.downsample, strict=True):
            for block in blocks:
                x = block(x, token, m)
            skips.append((x, m))
            x = down(x)  # x is zero at padded positions already
            m = F.max_pool1d(m, 2)  # a coarse position is valid if either of its two frames is
            x = x * m
        for block in self.mid:
            x = block(x, token, m)
        for blocks, up in zip(reversed(self.up), reversed(self.upsample), strict=True):
            skip, m = skips.pop()
            x = up(F.interpolate(x, scale_factor=2, mode="nearest") * m)
            x = torch.cat([x, skip], dim=1) * m
            for block in blocks:
                x = block(x, token, m)
        x = self.out_act(self.out_norm(x, m)) * m
        return x[..., :frames].transpose(1, 2)
