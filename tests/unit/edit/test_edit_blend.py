"""Boundary blending (edit.blend) against its formulas: hand-computed offsets, kept frames untouched, idempotent;
and in-betweening uses it."""

from __future__ import annotations

import math

import numpy as np
import pytest
from fixtures.tiny_models import tiny_datamodule, tiny_module

from motiondiff.edit.api import inbetween
from motiondiff.edit.blend import blend_boundaries, blend_weights
from motiondiff.edit.inputs import dataset_motions
from motiondiff.edit.masks import EditError


def _kept(n: int, prefix: int, suffix: int) -> np.ndarray:
    kept = np.zeros(n, dtype=bool)
    kept[:prefix] = True
    kept[n - suffix :] = True
    return kept


def test_weights_start_at_one_and_fade_with_a_cosine():
    expected = [1.0, 0.5 * (1 + math.cos(math.pi / 4)), 0.5, 0.5 * (1 + math.cos(3 * math.pi / 4))]
    assert blend_weights(4).tolist() == pytest.approx(expected)


def test_hand_computed_offsets_on_a_small_gap():
    """N = 10, frames 0-1 and 8-9 kept, D = 1, blend 2: n = min(2, 6 // 2) = 2, w = (1, 0.5)."""
    x = np.array([0.0, 1.0, 5, 5, 5, 5, 5, 5, 10.0, 12.0])[:, None]
    out = blend_boundaries(x, _kept(10, 2, 2), frames=2).ravel()
    # start: target 2·1 − 0 = 2, offset 2 − 5 = −3 → frames 2, 3 get −3, −1.5
    # end: target 2·10 − 12 = 8, offset 8 − 5 = 3 → frames 7, 6 get +3, +1.5
    assert out.tolist() == pytest.approx([0.0, 1.0, 2.0, 3.5, 5.0, 5.0, 6.5, 8.0, 10.0, 12.0])


def test_a_single_kept_frame_is_held_and_a_short_gap_caps_the_blend():
    x = np.array([4.0, 1, 1, 1, 1, 1])[:, None]
    out = blend_boundaries(x, _kept(6, 1, 0), frames=100).ravel()  # n = 5 // 2 = 2 frames
    assert out.tolist() == pytest.approx([4.0, 4.0, 2.5, 1.0, 1.0, 1.0])


def test_kept_frames_untouched_first_frame_continues_the_kept_motion_and_idempotent():
    rng = np.random.default_rng(0)
    n, d = 40, 5
    ramp = np.linspace(0, 1, n)[:, None] * rng.normal(size=(1, d))
    kept = _kept(n, 10, 10)
    x = np.where(kept[:, None], ramp, ramp + rng.normal(size=(n, d)))  # the model's motion off the kept one
    out = blend_boundaries(x, kept, frames=6)
    np.testing.assert_array_equal(out[kept], x[kept])
    np.testing.assert_allclose(out[10], 2 * ramp[9] - ramp[8])
    np.testing.assert_allclose(out[29], 2 * ramp[30] - ramp[31])
    np.testing.assert_array_equal(out[16:24], x[16:24])  # beyond the 6 blended frames of either side
    np.testing.assert_allclose(blend_boundaries(out, kept, frames=6), out)


def test_linear_so_normalising_first_gives_the_same_result():
    rng = np.random.default_rng(1)
    x, kept = rng.normal(size=(30, 4)), _kept(30, 7, 7)
    mean, std = rng.normal(size=4), rng.uniform(0.5, 2.0, size=4)
    direct = blend_boundaries(x, kept, 5)
    via_normalised = blend_boundaries((x - mean) / std, kept, 5) * std + mean
    np.testing.assert_allclose(via_normalised, direct, atol=1e-12)


def test_zero_frames_or_nothing_kept_change_nothing_and_bad_input_is_named():
    x = np.random.default_rng(2).normal(size=(12, 3))
    np.testing.assert_array_equal(blend_boundaries(x, _kept(12, 3, 3), 0), x)
    np.testing.assert_array_equal(blend_boundaries(x, np.zeros(12, dtype=bool), 4), x)
    with pytest.raises(ValueError, match="whole number of frames"):
        blend_boundaries(x, _kept(12, 3, 3), -1)
    with pytest.raises(ValueError, match="kept_frames has 5 frames"):
        blend_boundaries(x, np.ones(5, dtype=bool), 2)


@pytest.fixture(scope="module")
def module():
    return tiny_module(tiny_datamodule()).eval()


def test_inbetween_blends_its_boundaries_and_keeps_the_input(module):
    motion = dataset_motions(module, "test")[0]
    kept = _kept(motion.num_frames, 10, 10)
    plain = inbetween(module, motion, prefix=10, suffix=10, steps=5, seed=0, boundary_blend=0, close_root=False)
    blended = inbetween(module, motion, prefix=10, suffix=10, steps=5, seed=0, boundary_blend=8, close_root=False)
    np.testing.assert_array_equal(blended.features[0][kept], motion.features[kept])
    np.testing.assert_allclose(blended.features[0], blend_boundaries(plain.features[0], kept, 8), atol=1e-5)
    assert blended.settings["boundary_blend"] == 8 and plain.settings["boundary_blend"] == 0
    with pytest.raises(EditError, match="boundary_blend is a whole number"):
        inbetween(module, motion, steps=5, boundary_blend=1.5)
