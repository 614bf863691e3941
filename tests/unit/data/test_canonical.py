"""Rigid turns about y per representation: decode(turn(f)) = turn(decode(f)), placements read the way the training
clips were canonicalised, and hml features (which carry no placement) are placed by the decoder's own root."""

from __future__ import annotations

import numpy as np
import pytest

from motiondiff.data.datamodules import embedded_data_root
from motiondiff.data.formats.prepared import load_split
from motiondiff.data.representations import ROTATION_REPRESENTATIONS, get_representation
from motiondiff.edit.canonical import (
    carries_placement,
    facing_yaw,
    from_canonical,
    inverse_placement,
    placement,
    rigid_yaw_translate,
    to_canonical,
    turn_points,
    yaw_matrix,
)
from motiondiff.geometry.skeleton import SMPL22

PLACED = ("jp", *ROTATION_REPRESENTATIONS)
TOL = 1e-5  # metres
YAW = np.array([0.7, -2.4])
OFFSET = np.array([[1.5, 0.0, -0.3], [-4.0, 0.0, 2.2]])


@pytest.fixture(scope="module")
def val():
    split = load_split(embedded_data_root(), "val")
    return split.rig(), split.clips()


def features_of(rep, clips, frames: int = 40, noise: float = 0.02) -> np.ndarray:
    """Two real clips' features (2, frames, D), plus a little noise so that they look generated (not quite valid
    rotations), which the turn must handle exactly too."""
    rng = np.random.default_rng(0)
    feats = np.stack([rep.encode(c)[:frames] for c in clips[:2]]).astype(np.float64)
    return feats + noise * rng.standard_normal(feats.shape)


@pytest.mark.parametrize("name", PLACED)
def test_decode_of_turned_features_is_the_turned_decoding(val, name):
    rig, clips = val
    rep = get_representation(name, SMPL22, rig)
    feats = features_of(rep, clips)
    turned = rigid_yaw_translate(rep, feats, YAW, OFFSET)
    err = np.abs(rep.decode_numpy(turned) - turn_points(rep.decode_numpy(feats), YAW, OFFSET)).max()
    assert err <= TOL, f"{name}: {err:.2e} m"


def test_jp_without_a_rig_turns_too(val):
    _, clips = val
    rep = get_representation("jp", SMPL22)
    feats = features_of(rep, clips)
    turned = rigid_yaw_translate(rep, feats, YAW, OFFSET)
    assert np.abs(rep.decode_numpy(turned) - turn_points(rep.decode_numpy(feats), YAW, OFFSET)).max() <= TOL


@pytest.mark.parametrize("name", ["jp", "rp6jr", "rpqjr"])
def test_training_clips_start_canonical_by_the_same_rule(val, name):
    """placement() reads frame 0 of every real clip as (0, origin): the rule the dataset canonicalised with."""
    rig, clips = val
    rep = get_representation(name, SMPL22, rig)
    for clip in clips:
        yaw, offset = placement(rep, rep.encode(clip), 0)
        assert abs(np.angle(np.exp(1j * yaw))) < 1e-3 and np.abs(offset).max() < 1e-4


@pytest.mark.parametrize("name", PLACED)
def test_to_canonical_puts_the_frame_at_the_origin_facing_forward(val, name):
    rig, clips = val
    rep = get_representation(name, SMPL22, rig)
    world = rigid_yaw_translate(rep, features_of(rep, clips), YAW, OFFSET)
    s = 12
    yaw, offset = placement(rep, world, s)
    canon = to_canonical(rep, world[:, s:], yaw, offset)
    yaw0, offset0 = placement(rep, canon, 0)
    assert np.abs(np.angle(np.exp(1j * yaw0))).max() < 1e-6 and np.abs(offset0).max() < 1e-6
    back = from_canonical(rep, canon, yaw, offset)
    assert np.abs(rep.decode_numpy(back) - rep.decode_numpy(world[:, s:])).max() <= TOL


def test_hml_features_carry_no_placement_and_are_placed_by_their_root(val):
    _, clips = val
    rep = get_representation("hml263", SMPL22)
    feats = features_of(rep, clips, noise=0.0)
    assert not carries_placement(rep) and carries_placement(get_representation("jp", SMPL22))
    with pytest.raises(ValueError, match="carry no global position"):
        rigid_yaw_translate(rep, feats, YAW, OFFSET)
    assert np.array_equal(to_canonical(rep, feats, YAW, OFFSET), feats)
    # decoding from row s on gives the same motion, rigidly moved to the decoder's root at frame s
    s = 17
    yaw, offset = placement(rep, feats, s)
    whole, tail = rep.decode_numpy(feats), rep.decode_numpy(feats[:, s:])
    assert np.abs(whole[:, s:] - turn_points(tail, yaw, offset)).max() <= TOL
    assert np.abs(offset[:, 1]).max() == 0 and np.abs(offset - whole[:, s, 0] * [1, 0, 1]).max() <= TOL


def test_facing_yaw_of_a_hand_made_pose():
    """Hips and shoulders along x, right at -x: the body faces +Z (yaw 0); turned by R_y(θ) it faces yaw θ."""
    joints = np.zeros((22, 3))
    r_hip, l_hip, r_sdr, l_sdr = SMPL22.face_joints
    joints[[r_hip, l_hip, r_sdr, l_sdr]] = [[-0.1, 0.9, 0], [0.1, 0.9, 0], [-0.2, 1.4, 0], [0.2, 1.4, 0]]
    # +Z is "forward" when left is +x: across = right - left = -x, up x (-x) = +z
    assert facing_yaw(joints, SMPL22) == pytest.approx(0.0)
    for theta in (0.5, np.pi / 2, -2.0):
        assert facing_yaw(joints @ yaw_matrix(theta).T, SMPL22) == pytest.approx(theta)


def test_yaw_matrix_and_inverse_placement():
    assert np.allclose(yaw_matrix(np.pi / 2) @ [0, 0, 1], [1, 0, 0])  # +Z turns towards +X
    pts = np.random.default_rng(1).standard_normal((2, 5, 3))
    moved = turn_points(pts, YAW, OFFSET)
    assert np.allclose(turn_points(moved, *inverse_placement(YAW, OFFSET)), pts)
    assert np.allclose(moved[:, :, 1], pts[:, :, 1] + OFFSET[:, None, 1])  # heights only shift by offset_y
