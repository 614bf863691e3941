"""Training windows of random length (`window_min_frames`): lengths spread over [min, max_frames] for long clips,
short clips keep what they have, evaluation windows stay fixed, `first_window_share` of them are the clip's first
window, and a bad value is one clear error."""

from __future__ import annotations

import numpy as np
import pytest

from motiondiff.data.datasets import MotionDataset, MotionRecord


def _records(lengths):
    rng = np.random.default_rng(0)
    return [MotionRecord(id=f"c{i}", motion=rng.normal(size=(n, 4)).astype(np.float32), texts=["t"])
            for i, n in enumerate(lengths)]  # fmt: skip


def test_without_it_a_long_clip_is_always_seen_at_max_frames():
    ds = MotionDataset(_records([150]), np.zeros(4), np.ones(4), max_frames=120, train=True, seed=1)
    assert {ds[(e, 0)]["length"] for e in range(40)} == {120}


def test_long_clips_are_seen_at_every_length_between_the_bounds():
    ds = MotionDataset(_records([150, 30, 50]), np.zeros(4), np.ones(4), max_frames=120, train=True, seed=1,
                       window_min_frames=40)  # fmt: skip
    long = [ds[(e, 0)] for e in range(400)]
    lengths = np.array([it["length"] for it in long])
    assert lengths.min() == 40 and lengths.max() == 120 and len(set(lengths)) > 60
    assert abs(lengths.mean() - 80) < 5  # uniform in [40, 120]
    for it in long:  # the window lies inside the clip and holds its frames
        assert it["motion"].shape[0] == it["length"] and 0 <= it["start"] <= 150 - it["length"]
    assert {ds[(e, 1)]["length"] for e in range(40)} == {30}  # shorter than the minimum: the whole clip
    assert {ds[(e, 2)]["length"] for e in range(80)} == set(range(40, 51))


def test_evaluation_windows_do_not_change():
    ds = MotionDataset(_records([150]), np.zeros(4), np.ones(4), max_frames=120, train=False, window_min_frames=40)
    assert {(ds[0]["length"], ds[0]["start"]) for _ in range(10)} == {(120, 0)}


def test_a_non_positive_minimum_is_refused():
    with pytest.raises(ValueError, match="window_min_frames"):
        MotionDataset(_records([50]), np.zeros(4), np.ones(4), window_min_frames=0)


def test_a_share_of_windows_is_the_clips_first_and_the_rest_stay_random():
    ds = MotionDataset(_records([150]), np.zeros(4), np.ones(4), max_frames=120, train=True, seed=1,
                       window_min_frames=40, first_window_share=0.5)  # fmt: skip
    items = [ds[(e, 0)] for e in range(400)]
    first = [(it["length"], it["start"]) == (120, 0) for it in items]
    assert 0.42 < np.mean(first) < 0.58
    rest = [it for it, f in zip(items, first, strict=True) if not f]
    assert len({it["length"] for it in rest}) > 40 and len({it["start"] for it in rest}) > 20
    np.testing.assert_array_equal(ds.item_lengths(7), [ds[(7, 0)]["length"]])  # the bucketing sampler's lengths


def test_a_zero_share_draws_what_earlier_runs_drew():
    """A run resumed after the option appeared draws the windows it drew before: the length, then the start, from
    the item's own (seed, epoch, index) generator, and no other draw."""
    ds = MotionDataset(_records([150]), np.zeros(4), np.ones(4), max_frames=120, train=True, seed=2,
                       window_min_frames=40, first_window_share=0.0)  # fmt: skip
    for e in range(20):
        rng = np.random.default_rng((2, e, 0))
        n = int(rng.integers(40, 121))
        assert (ds[(e, 0)]["length"], ds[(e, 0)]["start"]) == (n, int(rng.integers(0, 150 - n + 1)))


def test_without_random_lengths_the_share_still_starts_windows_at_the_first_frame():
    ds = MotionDataset(_records([150]), np.zeros(4), np.ones(4), max_frames=120, train=True, seed=1,
                       first_window_share=1.0)  # fmt: skip
    assert {(ds[(e, 0)]["length"], ds[(e, 0)]["start"]) for e in range(30)} == {(120, 0)}
    np.testing.assert_array_equal(ds.item_lengths(3), [120])


@pytest.mark.parametrize("share", [-0.1, 1.5])
def test_a_share_outside_0_1_is_refused(share):
    with pytest.raises(ValueError, match="first_window_share"):
        MotionDataset(_records([50]), np.zeros(4), np.ones(4), window_min_frames=40, first_window_share=share)
