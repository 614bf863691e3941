"""Residual 1-D conv block of the U-Net backbone, with the time + condition token injected as FiLM.

As in DDPM-style U-Nets (Ho et al.; Dhariwal & Nichol's scale-shift norm), the token z_tk gives every block a
per-channel scale and shift after its second normalisation. Padded positions are zeroed before each convolution, and
normalisation statistics skip them, so their values never reach a valid position.
"""

from __future__ import annotations

from torch import Tensor, nn

from motiondiff.models.backbones.masked_norm import MaskedGroupNorm

ACTIVATIONS = {"gelu": nn.GELU, "silu": nn.SiLU, "relu": nn.ReLU}


def make_activation(name: str) -> nn.Module:
    if name not in ACTIVATIONS:
        raise ValueError(f"unknown activation {name!r}; known: {', '.join(ACTIVATIONS)}")
    return ACTIVATIONS[name]()


class ResBlock1d(nn.Module):
    """x -> norm, act, conv3 -> norm * (1 + scale) + shift, act, dropout, conv3 -> + skip(x); (B, C, L) layout."""

    def __init__(
        self, c_in: int, c_out: int, d_token: int, groups: int, dropout: float = 0.0, activation: str = "gelu"
    ):
        super().__init__()
        self.norm1 = MaskedGroupNorm(groups, c_in)
        self.conv1 = nn.Conv1d(c_in, c_out, kernel_size=3, padding=1)
        self.token_proj = nn.Sequential(make_activation(activation), nn.Linear(d_token, 2 * c_out))
        self.norm2 = MaskedGroupNorm(groups, c_out)
        self.conv2 = nn.Conv1d(c_out, c_out, kernel_size=3, padding=1)
        self.act = make_activation(activation)
        self.dropout = nn.Dropout(dropout)
        self.skip = nn.Conv1d(c_in, c_out, kernel_size=1) if c_in != c_out else nn.Identity()

    def forward(self, x: Tensor, token: Tensor, mask: Tensor) -> Tensor:
        """x (B, C_in, L), token (B, d), mask (B, 1, L) float -> (B, C_out, L), zero at padded positions."""
        y = self.conv1(self.act(self.norm1(x, mask)) * mask)
        scale, shift = self.token_proj(token).unsqueeze(-1).chunk(2, dim=1)
        y = self.norm2(y, mask) * (1 + scale) + shift
        y = self.conv2(self.dropout(self.act(y)) * mask)
        return (self.skip(x * mask) + y) * mask
