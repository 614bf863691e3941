"""GuidedMotion's noise schedule is the paper's: β "scaled linearly" from 8.5e-4 to 0.012 over T = 1000 (MLD's
scaled_linear, β = linspace(√start, √end, T)²), not a plain linear ramp between the same end points."""

from __future__ import annotations

import math

import pytest
import torch
from hydra import compose, initialize_config_dir

from motiondiff.cli.common import REPO_DIR, register_resolvers
from motiondiff.diffusion.schedules import make_betas

register_resolvers()


def test_the_latent_preset_uses_scaled_linear():
    with initialize_config_dir(config_dir=str(REPO_DIR / "conf"), version_base="1.3"):
        cfg = compose("train_latent")
    d = cfg.diffusion
    assert (d.schedule, d.steps, d.beta_start, d.beta_end, d.prediction) == (
        "scaled_linear",
        1000,
        8.5e-4,
        0.012,
        "eps",
    )


def test_scaled_linear_by_hand():
    betas = make_betas("scaled_linear", 1000, beta_start=8.5e-4, beta_end=0.012)
    mid = (math.sqrt(8.5e-4) + (math.sqrt(0.012) - math.sqrt(8.5e-4)) * 500 / 999) ** 2  # β_500 from the formula
    assert betas[500].item() == pytest.approx(mid, rel=1e-12)
    alpha_bar = torch.cumprod(1 - betas, 0)
    assert alpha_bar[500].item() == pytest.approx(0.2763, abs=1e-4)  # a plain linear ramp gives 0.1608
    assert alpha_bar[-1].item() == pytest.approx(0.00466, abs=1e-5)
