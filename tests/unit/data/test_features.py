"""HumanML3D features against the official sample 012314 (../shared/reference/humanml3d) and self-consistency."""

from __future__ import annotations

import numpy as np
import pytest

from motiondiff.data.representations.hml_features import (
    canonicalize_joints,
    feature_dim,
    feature_slices,
    features_from_canonical,
    features_from_joints,
    joints_from_features,
)
from motiondiff.geometry.rotations import qrot
from motiondiff.geometry.skeleton import KIT21, SMPL22, SMPL22_BONE_LENGTHS


@pytest.fixture(scope="module")
def official(shared):
    root = shared("reference", "humanml3d")
    return np.load(root / "new_joints" / "012314.npy"), np.load(root / "new_joint_vecs" / "012314.npy")


def test_dims():
    assert feature_dim(22) == 263 and feature_dim(21) == 251
    sl = feature_slices(22)
    assert sl["ric"] == slice(4, 67) and sl["rot6d"] == slice(67, 193)
    assert sl["local_vel"] == slice(193, 259) and sl["contacts"] == slice(259, 263)


def test_decode_matches_official_joints(official):
    joints, vecs = official
    out = joints_from_features(vecs)
    assert out.dtype == np.float32 and out.shape == (170, 22, 3)
    print(f"\njoints_from_features vs new_joints: max |error| {np.abs(out - joints).max():.2e} m")
    assert np.abs(out - joints).max() <= 1e-5


def test_encode_matches_official_features(official):
    joints, vecs = official
    feats = features_from_joints(joints)
    assert feats.dtype == np.float32 and feats.shape == (169, 263)
    for name, sl in feature_slices(22).items():
        print(f"\n{name:<13} rows 0-88 {np.abs(feats[:89, sl] - vecs[:89, sl]).max():.1e}  "
              f"rows 0-168 {np.abs(feats[:, sl] - vecs[:169, sl]).max():.1e}", end="")  # fmt: skip
        # Rows 0-88 are unaffected by the official input's extra last frame (see PROCEDURE.md).
        assert np.abs(feats[:89, sl] - vecs[:89, sl]).max() <= 1e-4, name
        assert np.abs(feats[:, sl] - vecs[:169, sl]).max() <= 2e-2, name
    np.testing.assert_array_equal(feats[:, 259:], vecs[:169, 259:])


def test_canonical_official_joints_are_a_fixed_point(official):
    joints, _ = official
    assert np.abs(canonicalize_joints(joints) - joints).max() < 1e-4


def test_round_trip_on_transformed_motion(official):
    """Any placement/heading/scale of a motion gives canonical joints that decode back from their features."""
    joints, _ = official
    yaw = np.array([np.cos(0.6), 0.0, np.sin(0.6), 0.0])  # rotate ~69 degrees about y
    moved = qrot(np.broadcast_to(yaw, joints.shape[:-1] + (4,)), joints.astype(np.float64)) * 1.3 + [
        2.0,
        0.5,
        -1.0,
    ]
    canon = canonicalize_joints(moved)
    # Uniform skeleton: every bone has the HumanML3D target length, the floor is at 0, frame-0 root at the origin.
    parents = np.array(SMPL22.parents)
    lengths = np.linalg.norm(canon[:, 1:] - canon[:, parents[1:]], axis=-1)
    np.testing.assert_allclose(lengths, np.broadcast_to(SMPL22_BONE_LENGTHS[1:], lengths.shape), atol=1e-6)
    assert abs(canon[..., 1].min()) < 1e-9 and np.abs(canon[0, 0, [0, 2]]).max() < 1e-9
    # Heading and placement are normalised away, so the result matches the untransformed motion.
    assert np.abs(canon - canonicalize_joints(joints)).max() < 1e-3
    feats = features_from_canonical(canon)
    decoded = joints_from_features(feats)
    assert np.abs(decoded - canon[:-1]).max() < 1e-5


def test_decode_batched(official):
    _, vecs = official
    batch = np.stack([vecs[:100], vecs[50:150]])
    out = joints_from_features(batch)
    assert out.shape == (2, 100, 22, 3)
    np.testing.assert_allclose(out[0], joints_from_features(vecs[:100]), atol=1e-6)


def test_kit_width_round_trip():
    rng = np.random.default_rng(0)
    # A KIT-like skeleton: rest pose from the raw offsets (unit bones, in metres for the test), random smooth sway.
    rest = np.zeros((21, 3))
    for j, p in enumerate(KIT21.parents):
        if p >= 0:
            rest[j] = rest[p] + KIT21.raw_offsets[j] * 0.2
    rest[:, 1] -= rest[:, 1].min()
    t = np.linspace(0, 2 * np.pi, 60)[:, None, None]
    joints = rest[None] + 0.02 * np.sin(t + rng.uniform(0, 6, (1, 21, 3))) + np.array([0, 0, 1.0]) * t / 5
    feats = features_from_joints(joints, KIT21)
    assert feats.shape == (59, 251)
    decoded = joints_from_features(feats)
    assert decoded.shape == (59, 21, 3)
    assert np.abs(decoded - canonicalize_joints(joints, KIT21)[:-1]).max() < 1e-5


@pytest.mark.parametrize(
    "bad, match",
    [
        (np.zeros((10, 21, 3)), r"\(frames, 22, 3\)"),
        (np.zeros((1, 22, 3)), "at least 2 frames"),
        (np.full((5, 22, 3), np.nan), "NaN"),
    ],
)
def test_bad_joints(bad, match):
    with pytest.raises(ValueError, match=match):
        features_from_joints(bad)


def test_bad_feature_width():
    with pytest.raises(ValueError, match="263"):
        joints_from_features(np.zeros((10, 100)))
