"""num_samples is bounded and sampled SAMPLE_BATCH at a time: the batches give the motions one batch gives (same seed,
deterministic sampler, CPU), and an edit of many samples runs in batches too."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from fixtures.tiny_models import tiny_datamodule, tiny_module

from motiondiff.lit.generation import MAX_NUM_SAMPLES, SAMPLE_BATCH, check_num_samples, generate_features
from motiondiff.runtime.errors import UsageError


@pytest.fixture(scope="module")
def module():
    return tiny_module(tiny_datamodule(max_frames=24), ["condition=none", "model.dropout=0.0"]).eval()


@pytest.mark.parametrize("value", [0, -3, MAX_NUM_SAMPLES + 1, 100000, 2.5, True, "many"])
def test_num_samples_out_of_bounds_is_one_line(value):
    with pytest.raises(UsageError, match=rf"num_samples={value!r}: must be a whole number from 1 to"):
        check_num_samples(value)


def test_num_samples_in_bounds():
    assert check_num_samples(1) == 1 and check_num_samples(MAX_NUM_SAMPLES) == MAX_NUM_SAMPLES


@pytest.mark.parametrize("sampler", ["ddim", "dpmpp"])
def test_batches_give_the_motions_of_one_batch(module, sampler):
    n = SAMPLE_BATCH + 6  # one whole batch and a short one
    lengths = torch.full((n,), 16)

    def run(batch_size):
        gen = torch.Generator().manual_seed(7)
        feats = generate_features(module, [None] * n, lengths, batch_size=batch_size, generator=gen, sampler=sampler,
                                  steps=3, eta=0.0)  # fmt: skip
        return np.stack(feats)

    batched, whole = run(SAMPLE_BATCH), run(n)
    assert batched.shape == whole.shape == (n, 16, module.representation.dim)
    np.testing.assert_allclose(batched, whole, atol=1e-4, rtol=1e-4)
    assert np.abs(batched[0] - batched[-1]).max() > 1e-3  # different motions, not one repeated
