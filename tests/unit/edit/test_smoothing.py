"""vvMDM temporal smoothing: the Gaussian filter against a hand-computed example, and the smoothness metric rising
when jittery motion is smoothed."""

from __future__ import annotations

import numpy as np
import pytest

from motiondiff.data.datamodules import embedded_data_root
from motiondiff.data.formats.prepared import load_split
from motiondiff.edit.smoothing import smooth_joints, smoothness_of_joints
from motiondiff.geometry.skeleton import SMPL22
from motiondiff.metrics import smoothness


def test_an_impulse_becomes_the_normalised_gaussian():
    """σ = 1 frame, kernel |k| ≤ 4: w_k = e^{−k²/2} / Σ e^{−k'²/2},
    Σ = 1 + 2(e^−½ + e^−2 + e^−4.5 + e^−8) = 2.5066208."""
    x = np.zeros((11, 1, 3))
    x[5, 0] = [1.0, -2.0, 0.0]
    out = smooth_joints(x, 1.0)
    # w_0 = 1/2.5066208 = 0.39894347, w_1 = e^−½/2.5066208 = 0.24197145, w_2 = 0.05399113, w_3 = 0.00443186, ...
    by_hand = np.array([0.0, 0.00013383, 0.00443186, 0.05399113, 0.24197145, 0.39894347, 0.24197145, 0.05399113,
                        0.00443186, 0.00013383, 0.0])  # fmt: skip
    np.testing.assert_allclose(out[:, 0, 0], by_hand, atol=1e-8)
    np.testing.assert_allclose(out[:, 0, 1], -2 * by_hand, atol=2e-8)  # each coordinate on its own
    assert out.sum(0)[0, 0] == pytest.approx(1.0)  # an average: nothing is lost


def test_ends_repeat_and_off_means_untouched():
    still = np.tile(np.array([[0.3, 1.0, -0.2]]), (20, 2, 1)).astype(np.float32)
    out = smooth_joints(still, 3.0)
    assert out.dtype == np.float32 and np.allclose(out, still)  # a still pose does not sag towards 0 at the ends
    batch = np.random.default_rng(0).standard_normal((2, 15, 4, 3))
    assert np.array_equal(smooth_joints(batch, None), batch) and np.array_equal(smooth_joints(batch, 0), batch)
    np.testing.assert_allclose(smooth_joints(batch, 1.0)[1], smooth_joints(batch[1], 1.0))  # over time, per motion
    with pytest.raises(ValueError, match="sigma must be >= 0"):
        smooth_joints(batch, -1)


def test_smoothing_jittery_motion_raises_the_smoothness_metric():
    clip = load_split(embedded_data_root(), "val").clips()[0].joints.astype(np.float64)
    noisy = clip + 0.01 * np.random.default_rng(0).standard_normal(clip.shape)  # 1 cm jitter
    smoothed = smooth_joints(noisy, 1.5)
    before, after = smoothness_of_joints(noisy, SMPL22), smoothness_of_joints(smoothed, SMPL22)
    assert after > before and after > smoothness_of_joints(noisy, SMPL22) + 0.01
    flat = lambda j: j.reshape(len(j), -1)  # noqa: E731 - the same metric on the joints themselves
    assert smoothness(flat(smoothed)) > smoothness(flat(noisy))
    assert np.abs(smooth_joints(clip, 1.5) - clip).max() < 0.05  # a clean clip moves little
    assert smoothness_of_joints(clip[:3], SMPL22) is None  # too short to measure


def test_smoothed_features_keep_their_rows_and_lower_the_joint_acceleration():
    """evaluate.py's smooth_sigma: features of a real clip with frame-to-frame jitter added to the joints, smoothed
    through the joints and re-encoded, keep their row count and width and lose most of the added acceleration."""
    from motiondiff.data.representations.hml_features import features_from_joints, joints_from_features
    from motiondiff.edit.smoothing import smooth_features

    data = load_split(embedded_data_root(), "train")
    joints = data.arrays["joints"][data.clip_slice(0)][:60].astype(np.float64)
    jitter = np.random.default_rng(0).normal(0, 0.02, joints.shape)
    feats = features_from_joints(joints + jitter, SMPL22)
    smoothed = smooth_features(feats, 1.5)
    assert smoothed.shape == feats.shape and smoothed.dtype == feats.dtype
    assert np.array_equal(smooth_features(feats, None), feats) and np.array_equal(smooth_features(feats, 0), feats)

    def accel(f):
        return np.linalg.norm(np.diff(joints_from_features(f), n=2, axis=0), axis=-1).mean()

    assert accel(smoothed) < 0.3 * accel(feats)
