"""Class-balanced training order (`dataset.datamodule.balance`): rare action labels are drawn more often, the order
still depends on (seed, epoch) alone so a resumed run rebuilds it, and bad weights are refused."""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest

from motiondiff.data.resumable import EpochShuffleSampler, balance_weights


def test_balance_zero_keeps_the_plain_permutation():
    assert balance_weights([0, 0, 1], 0.0) is None
    assert list(EpochShuffleSampler(30, seed=2, weights=None)) == list(EpochShuffleSampler(30, seed=2))


def test_power_one_makes_every_label_equally_likely_and_half_is_in_between():
    labels = [0] * 90 + [1] * 10
    for power, rare_share in ((1.0, 0.5), (0.5, 10 * 10**-0.5 / (90 * 90**-0.5 + 10 * 10**-0.5)), (0.0, 0.1)):
        w = balance_weights(labels, power)
        w = np.ones(len(labels)) if w is None else w
        assert w[90:].sum() / w.sum() == pytest.approx(rare_share)
    draws = Counter()
    sampler = EpochShuffleSampler(100, seed=0, weights=balance_weights(labels, 1.0))
    for epoch in range(20):
        sampler.set_epoch(epoch)
        draws.update(labels[i] for _, i in sampler)
    assert 0.45 < draws[1] / sum(draws.values()) < 0.55  # 10% of the clips, half of the draws


def test_unlabelled_clips_form_one_group():
    w = balance_weights([-1, -1, 3], 1.0)
    assert w.tolist() == [0.5, 0.5, 1.0]


def test_weighted_order_is_fixed_by_seed_and_epoch_and_resumes():
    w = balance_weights([0] * 15 + [1] * 5, 0.5)
    a, b = EpochShuffleSampler(20, seed=3, weights=w), EpochShuffleSampler(20, seed=3, weights=w)
    a.set_epoch(4), b.set_epoch(4)
    full = list(a)
    assert full == list(b) and len(full) == 20
    b.resume(4, 7)
    assert list(b) == full[7:]


@pytest.mark.parametrize("weights", [np.ones(3), np.array([1.0, -1.0, 1.0, 1.0]), np.zeros(4), np.full(4, np.nan)])
def test_bad_weights_are_refused(weights):
    with pytest.raises(ValueError, match="sampling weights"):
        EpochShuffleSampler(4, weights=weights)


def test_negative_balance_is_refused():
    with pytest.raises(ValueError, match="balance must be >= 0"):
        balance_weights([0, 1], -0.5)
