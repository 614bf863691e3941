"""The training order of an epoch and each item's random window and caption depend only on (seed, epoch, index),
so a resume can rebuild the rest of an epoch; and the saved random state round-trips through weights_only loading."""

from __future__ import annotations

import io
import random

import numpy as np
import torch

from motiondiff.data.datasets import MotionDataset, MotionRecord
from motiondiff.data.resumable import EpochShuffleSampler
from motiondiff.lit.resume import random_state, set_random_state


def test_each_epoch_is_a_permutation_fixed_by_seed_and_epoch():
    a, b = EpochShuffleSampler(50, seed=3), EpochShuffleSampler(50, seed=3)
    first = list(a)
    assert sorted(i for _, i in first) == list(range(50)) and {e for e, _ in first} == {0}
    b.set_epoch(1)
    assert [i for _, i in b] != [i for _, i in first]  # a new order each epoch
    a.set_epoch(1)
    assert list(a) == list(b)
    assert list(EpochShuffleSampler(50, seed=4)) != first


def test_resume_yields_the_rest_of_the_epoch_once():
    sampler = EpochShuffleSampler(20, seed=0)
    sampler.set_epoch(2)
    full = list(sampler)
    sampler.resume(2, 8)
    assert list(sampler) == full[8:]
    assert list(sampler) == full  # the skip applies to one iteration only


def _dataset():
    rng = np.random.default_rng(0)
    records = [MotionRecord(id=f"c{i}", motion=rng.normal(size=(60, 4)).astype(np.float32), texts=["a", "b", "c"])
               for i in range(5)]  # fmt: skip
    return MotionDataset(records, np.zeros(4), np.ones(4), max_frames=20, train=True, seed=7)


def test_an_items_window_and_caption_depend_only_on_epoch_and_index():
    ds = _dataset()
    item = ds[(3, 2)]
    ds[(3, 1)], ds[(4, 2)]  # other draws in between change nothing
    again = ds[(3, 2)]
    assert item["start"] == again["start"] and item["text"] == again["text"]
    torch.testing.assert_close(item["motion"], again["motion"])
    starts = {ds[(e, 2)]["start"] for e in range(30)}
    assert len(starts) > 5  # still random across epochs


def test_random_state_round_trips_through_a_weights_only_checkpoint():
    torch.manual_seed(1), np.random.seed(1), random.seed(1)  # noqa: NPY002
    buffer = io.BytesIO()
    torch.save({"state": random_state()}, buffer)
    expected = (torch.rand(3), np.random.rand(3), random.random())  # noqa: NPY002
    buffer.seek(0)
    set_random_state(torch.load(buffer, weights_only=True)["state"])
    got = (torch.rand(3), np.random.rand(3), random.random())  # noqa: NPY002
    torch.testing.assert_close(got[0], expected[0])
    assert np.array_equal(got[1], expected[1]) and got[2] == expected[2]
