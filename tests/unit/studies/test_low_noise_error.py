"""studies.editing.low_noise_error: the denoiser's error on an almost clean input, next to the input's own error."""

from __future__ import annotations

import pytest
import torch
from fixtures.tiny_models import tiny_datamodule, tiny_module

from motiondiff.data.datamodules import embedded_data_root
from motiondiff.edit.inputs import dataset_motions
from motiondiff.studies.editing import low_noise_error


@pytest.fixture(scope="module")
def module_and_clips():
    module = tiny_module(tiny_datamodule(max_frames=80)).eval()
    return module, dataset_motions(module, "val", embedded_data_root())[:3]


class Identity(torch.nn.Module):
    """An x0-predicting 'denoiser' that returns its input: x̂0 = x_t."""

    def forward(self, x, t, **kwargs):
        return x


def test_identity_denoiser_scores_what_the_input_scores(module_and_clips):
    module, clips = module_and_clips
    trained = module.denoiser
    module.denoiser = Identity()
    try:
        low = low_noise_error(module, clips, t=20)
        high = low_noise_error(module, clips, t=400)
    finally:
        module.denoiser = trained
    assert low["x0_hat_mpjpe_m"] == pytest.approx(low["x_t_mpjpe_m"], abs=1e-7)
    assert 0 < low["x_t_mpjpe_m"] < high["x_t_mpjpe_m"]  # more noise, further from the clip


def test_untrained_denoiser_is_worse_than_the_input_at_low_noise(module_and_clips):
    module, clips = module_and_clips
    low = low_noise_error(module, clips, t=20)
    assert low["clips"] == 3 and low["x0_hat_mpjpe_m"] > 5 * low["x_t_mpjpe_m"]
