"""GuidedMotion's motion VAE (paper §3.3, after MLD): a transformer encoder reads Q learnable query tokens together
with the motion and returns a Gaussian latent z ∈ R^{Q×D'}; a transformer decoder reads z with one query token per
output frame and returns the motion. Both stacks have long skip connections (U-Net style: the output half of the
layers concatenates the matching input-half activation and projects it back), which the paper keeps from MLD.
GuidedMotion trains three independent VAEs with Q = 2 (motion level), 4 (action level) and 8 (specific level).
"""

from __future__ import annotations

from dataclasses import asdict, replace
from typing import Any

import torch
from torch import Tensor, nn

from motiondiff.models.backbones.encoder_layer import TransformerSize
from motiondiff.models.embeddings import SinusoidalPositionalEncoding

LEVEL_TOKENS = {"motion": 2, "action": 4, "specific": 8}
VAE_SIZE = TransformerSize(num_layers=9)  # MotionVAE's default sizes (MLD's 9 layers: 4 in, 1 middle, 4 out)


class SkipTransformer(nn.Module):
    """num_layers (odd) encoder layers: (L−1)/2 in, one middle, (L−1)/2 out; out layer k gets Linear([x, skip_k])."""

    def __init__(self, d_model: int, num_layers: int, num_heads: int, ff_size: int, dropout: float):
        super().__init__()
        if num_layers < 1 or num_layers % 2 == 0:
            raise ValueError(f"a skip transformer needs an odd number of layers (in, middle, out), got {num_layers}")

        layer = TransformerSize(d_model, num_layers, num_heads, ff_size, dropout).layer
        half = num_layers // 2
        self.input_layers = nn.ModuleList(layer() for _ in range(half))
        self.middle = layer()
        self.output_layers = nn.ModuleList(layer() for _ in range(half))
        self.skip_projections = nn.ModuleList(nn.Linear(2 * d_model, d_model) for _ in range(half))
        self.norm = nn.LayerNorm(d_model)

    def forward(self, x: Tensor, padding: Tensor | None = None) -> Tensor:
        skips = []
        for layer in self.input_layers:
            x = layer(x, src_key_padding_mask=padding)
            skips.append(x)
        x = self.middle(x, src_key_padding_mask=padding)
        for layer, project in zip(self.output_layers, self.skip_projections, strict=True):
            x = layer(project(torch.cat([x, skips.pop()], dim=-1)), src_key_padding_mask=padding)
        return self.norm(x)


class MotionVAE(nn.Module):
    """features (B, N, D) with a valid-frame mask (B, N) <-> latent (B, Q, latent_dim)."""

    def __init__(
        self, feature_dim: int, latent_tokens: int = 4, latent_dim: int = 256, *, max_frames: int = 196, **size: Any
    ):
        """``size``: TransformerSize's fields (d_model, num_layers, ...), each VAE_SIZE's where not given."""
        super().__init__()
        if latent_tokens < 1:
            raise ValueError(f"latent_tokens (Q) must be >= 1, got {latent_tokens}")
        size = replace(VAE_SIZE, **size)
        d_model = size.d_model
        self.feature_dim, self.latent_tokens, self.latent_dim = feature_dim, latent_tokens, latent_dim
        self.max_frames = max_frames
        self.motion_in = nn.Linear(feature_dim, d_model)
        self.queries = nn.Parameter(torch.randn(latent_tokens, d_model) * 0.02)  # Q learnable query tokens
        self.positions = SinusoidalPositionalEncoding(d_model, max_len=max_frames + latent_tokens, dropout=size.dropout)
        self.encoder = SkipTransformer(**asdict(size))
        self.to_gaussian = nn.Linear(d_model, 2 * latent_dim)  # mean and log-variance per token
        self.latent_in = nn.Linear(latent_dim, d_model)
        self.decoder = SkipTransformer(**asdict(size))
        self.motion_out = nn.Linear(d_model, feature_dim)

    def _padding(self, mask: Tensor) -> Tensor:
        """Key padding for [Q tokens, N frames]: the tokens are always valid."""
        tokens = torch.zeros(mask.shape[0], self.latent_tokens, dtype=torch.bool, device=mask.device)
        return torch.cat([tokens, ~mask], dim=1)

    def encode(self, features: Tensor, mask: Tensor) -> tuple[Tensor, Tensor]:
        """(mean, log-variance), each (B, Q, latent_dim)."""
        b, n, _ = features.shape
        if n > self.max_frames:
            raise ValueError(f"{n} frames is more than this VAE's max_frames={self.max_frames}")
        x = torch.cat([self.queries.expand(b, -1, -1), self.motion_in(features)], dim=1)
        x = self.encoder(self.positions(x), self._padding(mask))
        mean, log_var = self.to_gaussian(x[:, : self.latent_tokens]).chunk(2, dim=-1)
        return mean, log_var.clamp(-30.0, 20.0)

    def decode(self, z: Tensor, mask: Tensor) -> Tensor:
        """Features (B, N, D) for N = mask.shape[1] frames; padded frames are zero."""
        b, n = mask.shape
        frames = torch.zeros(b, n, self.latent_in.out_features, device=z.device, dtype=z.dtype)
        x = self.positions(torch.cat([self.latent_in(z), frames], dim=1))  # one positional query per output frame
        x = self.decoder(x, self._padding(mask))
        return self.motion_out(x[:, self.latent_tokens :]) * mask[..., None]

    def forward(self, features: Tensor, mask: Tensor, generator: torch.Generator | None = None):
        """(reconstruction, mean, log_var); z is sampled with the reparameterisation trick."""
        mean, log_var = self.encode(features, mask)
        noise = torch.randn(mean.shape, generator=generator, device=mean.device, dtype=mean.dtype)
        z = mean + (0.5 * log_var).exp() * noise
        return self.decode(z, mask), mean, log_var


def kl_divergence(mean: Tensor, log_var: Tensor) -> Tensor:
    """KL(N(mean, exp(log_var)) || N(0, I)) per sample, summed over tokens and dims."""
    return 0.5 * (mean.pow(2) + log_var.exp() - 1.0 - log_var).flatten(1).sum(-1)


def vae_loss(recon: Tensor, target: Tensor, mask: Tensor, mean: Tensor, log_var: Tensor, kl_weight: float = 1e-4):
    """(total, reconstruction, kl): masked mean squared feature error + kl_weight · mean KL per sample."""
    err = (recon - target).pow(2).mean(-1)
    reconstruction = (err * mask).sum() / mask.sum().clamp(min=1)
    kl = kl_divergence(mean, log_var).mean()
    return reconstruction + kl_weight * kl, reconstruction, kl
