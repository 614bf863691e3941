"""The per-noise-level prediction errors of issue 43's ε account (motiondiff.eval.prediction_error)."""

import math

import pytest
import torch
from fixtures.tiny_models import tiny_datamodule, tiny_module

from motiondiff.eval.prediction_error import noise_floor, prediction_errors

T_VALUES = (999, 500, 20)


class Oracle(torch.nn.Module):
    """A denoiser that knows the answer: the clean clips themselves."""

    def __init__(self, x0):
        super().__init__()
        self.x0 = x0

    def forward(self, x_t, t, **kwargs):
        return self.x0


@pytest.fixture(scope="module")
def clips():
    dm = tiny_datamodule(max_frames=24)
    val = dm.dataset("val")
    items = [val[i]["motion"][:24] for i in range(len(val)) if len(val[i]["motion"]) >= 24][:4]
    return torch.stack([torch.as_tensor(c) for c in items]).float(), dm


@pytest.mark.parametrize("prediction", ["x0", "eps", "v"])
def test_the_two_errors_are_tied_by_the_schedule_whatever_the_network_predicts(clips, prediction):
    x0, dm = clips
    module = tiny_module(dm, ("condition=none", f"diffusion={prediction}")).eval()
    abar = module.diffusion.alphas_cumprod
    for t, rms_x0, rms_eps in prediction_errors(module, x0, T_VALUES, noises=2):
        assert rms_x0 == pytest.approx(rms_eps * math.sqrt((1 - float(abar[t])) / float(abar[t])), rel=1e-3)
    assert prediction_errors(module, x0, T_VALUES) == prediction_errors(module, x0, T_VALUES)  # seeded


def test_a_network_that_returns_the_clean_motion_has_no_error(clips):
    x0, dm = clips
    module = tiny_module(dm, ("condition=none", "diffusion=x0")).eval()
    module.denoiser = Oracle(x0)
    for _, rms_x0, rms_eps in prediction_errors(module, x0, T_VALUES):
        assert rms_x0 == 0.0 and rms_eps < 1e-3


def test_the_noise_floor_is_what_projecting_white_noise_onto_a_subspace_leaves():
    generator = torch.Generator().manual_seed(0)
    basis, _ = torch.linalg.qr(torch.randn(263, 128, generator=generator, dtype=torch.float64))
    eps = torch.randn(20000, 263, generator=generator, dtype=torch.float64)
    residual = eps - eps @ basis @ basis.T  # the best ε̂ in the 128-dim span: ε's own projection
    assert float(residual.pow(2).mean().sqrt()) == pytest.approx(noise_floor(263, 128), rel=0.01)
    assert noise_floor(263, 128) == pytest.approx(0.716, abs=5e-4)
    assert noise_floor(66, 128) == 0.0
    with pytest.raises(ValueError, match="feature_dim must be > 0"):
        noise_floor(0, 10)
