"""Foot-skate cleanup (motiondiff.edit.foot_cleanup, cleanup=feet): the sliding measure on a motion whose answer is
known, and on the released text model's walks: sliding goes down, joints off the legs and every bone length stay,
and kept frames or kept joints are returned exactly."""

from __future__ import annotations

import numpy as np
import pytest

from motiondiff.edit.foot_cleanup import clean_foot_skate, detect_contacts, foot_sliding
from motiondiff.geometry.skeleton import SMPL22
from motiondiff.pipelines import MotionPipeline

FPS = 20.0
LEGS = sorted(SMPL22.part("legs"))
OFF_LEGS = [j for j in range(22) if j not in LEGS]


@pytest.fixture(scope="module")
def walks():
    # sample.py's defaults (DDIM-50); the generated feet jitter by up to 40 cm between frames and glide
    out = MotionPipeline.from_pretrained("text")("a person walks forward", seconds=4, num_samples=4, seed=0)
    return out.joints


def bone_lengths(joints: np.ndarray) -> np.ndarray:
    parents = np.array(SMPL22.parents)
    return np.linalg.norm(joints[:, 1:] - joints[:, parents[1:]], axis=-1)


def test_sliding_and_contacts_of_a_known_motion():
    """Left ankle and toe: planted but sliding at 10 cm/s for 10 frames, a fast swing 25 cm up, planted still for
    10 frames; the right foot stays still on the ground throughout."""
    joints = np.zeros((30, 22, 3))
    x = np.concatenate([0.005 * np.arange(10), np.linspace(0.1, 0.9, 10), np.full(10, 1.0)])
    y = np.concatenate([np.zeros(10), 0.25 * np.sin(np.linspace(0.3, np.pi - 0.3, 10)), np.zeros(10)])
    for joint, height, ahead in ((7, 0.08, 0.0), (10, 0.02, 0.14)):
        joints[:, joint] = np.stack([x + ahead, y + height, np.zeros(30)], axis=-1)
    joints[:, [8, 11]] = [[-0.2, 0.08, 0.0], [-0.2, 0.02, 0.14]]
    contacts = detect_contacts(joints, SMPL22, FPS)  # columns: left ankle, left toe, right ankle, right toe
    assert contacts[:8, :2].all() and not contacts[12:18, :2].any() and contacts[22:, :2].all()
    assert contacts[:, 2:].all()
    known = np.zeros((30, 4), dtype=bool)
    known[:10], known[20:] = True, True
    # 4 joints x 18 frame pairs in contact; the left ankle's and toe's first 9 slide 0.5 cm a frame (10 cm/s)
    assert foot_sliding(joints, SMPL22, FPS, known) == pytest.approx(10.0 * 18 / 72)


def test_cleanup_of_generated_walks_reduces_sliding_and_moves_only_the_legs(walks):
    before, after = [], []
    for joints in walks:
        result = clean_foot_skate(joints, SMPL22, FPS)
        before.append(result.sliding_before_cm_s)
        after.append(result.sliding_after_cm_s)
        # contacts are found (real walks: about half the foot-frames; the released model's walks include quick
        # dashes, whose feet are down in a few percent of the frames)
        assert result.contacts.any()
        np.testing.assert_array_equal(result.joints[:, OFF_LEGS], joints[:, OFF_LEGS])
        assert np.abs(bone_lengths(result.joints) - bone_lengths(joints.astype(np.float64))).max() < 1e-6
        assert result.frames_changed > 0
    print(f"\nfoot sliding of {len(walks)} generated walks: {np.mean(before):.1f} -> {np.mean(after):.1f} cm/s")
    assert np.mean(after) < 0.5 * np.mean(before)
    assert all(a < b for a, b in zip(after, before, strict=True))


def test_kept_frames_and_kept_joints_are_returned_exactly(walks):
    joints = walks[0]
    frames = np.zeros(len(joints), dtype=bool)
    frames[:20], frames[-20:] = True, True  # an in-between's kept start and end
    result = clean_foot_skate(joints, SMPL22, FPS, keep=frames)
    np.testing.assert_array_equal(result.joints[frames], joints[frames])
    assert not np.array_equal(result.joints[~frames], joints[~frames])  # the generated middle is cleaned
    free = np.zeros_like(result.contacts)
    free[~frames] = result.contacts[~frames]
    assert foot_sliding(result.joints, SMPL22, FPS, free) < foot_sliding(joints, SMPL22, FPS, free)
    # body parts kept from the input: the kept left leg does not move, the generated right leg is cleaned
    points = np.zeros(joints.shape[:2], dtype=bool)
    points[:, list(SMPL22.part("left_leg"))] = True
    result = clean_foot_skate(joints, SMPL22, FPS, keep=points)
    np.testing.assert_array_equal(
        result.joints[:, list(SMPL22.part("left_leg"))], joints[:, list(SMPL22.part("left_leg"))]
    )
    assert not np.array_equal(
        result.joints[:, list(SMPL22.part("right_leg"))], joints[:, list(SMPL22.part("right_leg"))]
    )


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match=r"joints must have shape \(frames >= 1, 22, 3\)"):
        clean_foot_skate(np.zeros((10, 21, 3)), SMPL22, FPS)
    with pytest.raises(ValueError, match="keep must be kept frames"):
        clean_foot_skate(np.zeros((10, 22, 3)), SMPL22, FPS, keep=np.zeros(9, dtype=bool))
    short = clean_foot_skate(np.ones((2, 22, 3)), SMPL22, FPS)  # too short to tell contacts: returned as it is
    np.testing.assert_array_equal(short.joints, np.ones((2, 22, 3)))
