"""The motion VAE: shapes per level, padding never leaks, KL against its closed form, and it learns to reconstruct."""

from __future__ import annotations

import pytest
import torch

from motiondiff.models.vae import LEVEL_TOKENS, MotionVAE, SkipTransformer, kl_divergence, vae_loss

SMALL = {"d_model": 32, "num_layers": 3, "num_heads": 2, "ff_size": 64, "dropout": 0.0, "max_frames": 40}


@pytest.mark.parametrize("level", sorted(LEVEL_TOKENS))
def test_latent_has_q_tokens_per_level(level):
    q = LEVEL_TOKENS[level]
    vae = MotionVAE(feature_dim=12, latent_tokens=q, latent_dim=16, **SMALL).eval()
    x, mask = torch.randn(3, 20, 12), torch.ones(3, 20, dtype=torch.bool)
    mean, log_var = vae.encode(x, mask)
    assert mean.shape == log_var.shape == (3, q, 16)
    assert vae.decode(mean, mask).shape == (3, 20, 12)


def test_padding_does_not_change_the_latent_or_the_valid_frames():
    torch.manual_seed(0)
    vae = MotionVAE(feature_dim=6, latent_tokens=2, latent_dim=8, **SMALL).eval()
    x = torch.randn(1, 10, 6)
    short_mean, _ = vae.encode(x, torch.ones(1, 10, dtype=torch.bool))
    padded = torch.cat([x, 100 * torch.randn(1, 5, 6)], dim=1)
    mask = torch.arange(15)[None] < 10
    long_mean, _ = vae.encode(padded, mask)
    torch.testing.assert_close(long_mean, short_mean, atol=1e-5, rtol=1e-4)
    out = vae.decode(short_mean, mask)
    assert torch.equal(out[:, 10:], torch.zeros(1, 5, 6))
    torch.testing.assert_close(out[:, :10], vae.decode(short_mean, torch.ones(1, 10, dtype=torch.bool)), atol=1e-5,
                               rtol=1e-4)  # fmt: skip


def test_kl_matches_the_closed_form_by_hand():
    mean, log_var = torch.tensor([[[0.5, -1.0]]]), torch.tensor([[[0.0, 2.0]]])
    # 0.5 * sum(mu^2 + sigma^2 - 1 - log sigma^2)
    by_hand = 0.5 * ((0.25 + 1 - 1 - 0) + (1 + torch.e**2 - 1 - 2))
    assert kl_divergence(mean, log_var).item() == pytest.approx(by_hand, rel=1e-6)
    assert kl_divergence(torch.zeros(2, 3, 4), torch.zeros(2, 3, 4)).abs().max() == 0


def test_skip_transformer_needs_odd_layers():
    with pytest.raises(ValueError, match="odd number of layers"):
        SkipTransformer(16, 4, 2, 32, 0.0)


def test_a_few_steps_reduce_the_reconstruction_error():
    torch.manual_seed(0)
    vae = MotionVAE(feature_dim=6, latent_tokens=2, latent_dim=8, **SMALL)
    t = torch.linspace(0, 6.28, 30)
    x = torch.stack([torch.sin(t * k) for k in range(1, 7)], dim=-1)[None].repeat(4, 1, 1)
    mask = torch.ones(4, 30, dtype=torch.bool)
    opt = torch.optim.Adam(vae.parameters(), lr=1e-3)
    losses = []
    for _ in range(60):
        recon, mean, log_var = vae(x, mask, generator=torch.Generator().manual_seed(1))
        loss, rec, _ = vae_loss(recon, x, mask, mean, log_var)
        opt.zero_grad()
        loss.backward()
        opt.step()
        losses.append(rec.item())
    assert losses[-1] < 0.5 * losses[0]
