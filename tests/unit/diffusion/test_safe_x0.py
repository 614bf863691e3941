"""Safe x̂0 (diffusion.thresholding): a no-op inside the data's range, always inside it after, and it stops a small
error in an ε model's first DDIM-50 step (ᾱ ≈ 2.4e-9 on the cosine schedule) from changing the sampled motion."""

from __future__ import annotations

import pytest
import torch

from motiondiff.diffusion.process import GaussianDiffusion
from motiondiff.diffusion.samplers import ddim_sample, select_timesteps
from motiondiff.diffusion.schedules import make_betas
from motiondiff.diffusion.thresholding import make_threshold

D, B = 64, 256
MU = torch.linspace(-1, 1, D)


@pytest.mark.parametrize("rule", ["static", "dynamic"])
def test_inside_the_range_nothing_changes_and_outside_it_comes_back(rule):
    low, high = MU - 3, MU + 3
    fn = make_threshold(rule, low, high)
    inside = MU + 2 * torch.rand(B, 10, D) - 1
    torch.testing.assert_close(fn(inside), inside)
    wild = MU + 200 * torch.randn(B, 10, D)
    out = fn(wild)
    assert bool(((out >= low - 1e-5) & (out <= high + 1e-5)).all())
    if rule == "dynamic":  # the shape is kept: rescaled, not piled onto the bounds
        assert float(((out - low).abs() < 1e-4).float().mean()) < 0.05


def test_unknown_rule_is_refused():
    assert make_threshold("none", MU, MU) is None and make_threshold(None, MU, MU) is None
    with pytest.raises(ValueError, match="static or dynamic"):
        make_threshold("imagen", MU, MU)


def _sample_change(rule: str | None) -> float:
    """RMS change of DDIM-50 samples when ε̂ is 1% off at the first step, for unit-variance Gaussian data with the
    exact ε model (its x̂0 is the posterior mean) and the range of 20,000 draws of that data."""
    torch.manual_seed(0)
    data = MU + torch.randn(20000, D)
    proc = GaussianDiffusion(make_betas("cosine", 1000), prediction="eps")
    alpha_bar = proc.alphas_cumprod.float()
    first = select_timesteps(1000, 50)[-1]

    def model(error: float):
        def fn(x, t):
            a = alpha_bar[t[0]]
            x0 = MU + (a.sqrt() / (a + 1 - a)) * (x - a.sqrt() * MU)
            eps = (x - a.sqrt() * x0) / (1 - a).sqrt()
            return eps * (1 + error) if int(t[0]) == first else eps

        return fn

    clip = make_threshold(rule, data.min(0).values, data.max(0).values)
    noise = torch.randn(B, D)
    exact = ddim_sample(proc, model(0.0), (B, D), noise=noise, clip_x0=clip)
    off = ddim_sample(proc, model(0.01), (B, D), noise=noise, clip_x0=clip)
    return float((off - exact).pow(2).mean().sqrt())


def test_a_one_percent_error_at_the_first_step_no_longer_changes_the_motion():
    unsafe, static, dynamic = _sample_change(None), _sample_change("static"), _sample_change("dynamic")
    assert unsafe > 3.0  # the first step multiplies the error by about 630 (measured 6.1 RMS)
    assert static < unsafe / 25 and dynamic < unsafe / 60  # measured 0.12 and 0.050


def test_padding_does_not_shrink_the_motion():
    low, high = MU - 3, MU + 3
    x0 = MU + 2 * torch.rand(2, 10, D) - 1
    x0[:, 8:] = 500.0  # padded frames, never constrained by a loss
    mask = torch.arange(10)[None] < torch.tensor([8, 8])[:, None]
    out = make_threshold("dynamic", low, high, mask=mask)(x0)
    torch.testing.assert_close(out[:, :8], x0[:, :8])
