"""Input perturbation (DDPM-IP): training builds x_t with noise ε + γ·ξ (variance 1 + γ²), the loss keeps ε, and
validation measures the plain loss."""

from __future__ import annotations

import pytest
import torch
from fixtures.tiny_models import tiny_datamodule, tiny_module


@pytest.fixture(scope="module")
def datamodule():
    return tiny_datamodule()


def _noise_seen(module, batch, perturb: bool) -> tuple[torch.Tensor, torch.Tensor]:
    """(noise x_t was built with, noise the loss received) for one call of the training loss."""
    seen = {}
    q_sample, loss = module.diffusion.q_sample, module.diffusion.loss

    def recording_q_sample(x0, t, noise):
        seen["input"] = noise
        return q_sample(x0, t, noise)

    def recording_loss(out, x0, noise, t, mask=None):
        seen["target"] = noise
        return loss(out, x0, noise, t, mask=mask)

    module.diffusion.q_sample, module.diffusion.loss = recording_q_sample, recording_loss
    try:
        module._loss(batch, 0.0, perturb=perturb)
    finally:
        module.diffusion.q_sample, module.diffusion.loss = q_sample, loss
    return seen["input"], seen["target"]


def test_the_input_noise_is_perturbed_and_the_target_is_not(datamodule):
    batch = next(iter(datamodule.train_dataloader()))
    module = tiny_module(datamodule, ["condition=none", "diffusion.input_perturbation=0.5"])
    assert module.input_perturbation == 0.5
    torch.manual_seed(0)
    given, target = _noise_seen(module, batch, perturb=True)
    extra = given - target
    assert extra.abs().max() > 0 and extra.std().item() == pytest.approx(0.5, rel=0.05)
    assert target.std().item() == pytest.approx(1.0, rel=0.05)
    given, target = _noise_seen(module, batch, perturb=False)  # validation: x_t from the loss's own noise
    assert torch.equal(given, target)


def test_off_by_default(datamodule):
    module = tiny_module(datamodule)
    assert module.input_perturbation == 0.0
    batch = next(iter(datamodule.train_dataloader()))
    given, target = _noise_seen(module, batch, perturb=True)
    assert torch.equal(given, target)
