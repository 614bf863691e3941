"""Editing masks: frames kept for in-betweening, feature dims kept for body-part editing (from the model's own
representation: SMPL-22 dims for hml263, the rig's joints for the rig representations)."""

from __future__ import annotations

import numpy as np
import pytest

from motiondiff.data.datamodules import embedded_data_root
from motiondiff.data.formats.prepared import load_split
from motiondiff.data.representations import get_representation
from motiondiff.data.representations.hml_features import feature_slices
from motiondiff.edit.masks import (
    EditError,
    frame_keep,
    frames_from_fraction,
    frames_from_seconds,
    resolve_joints,
    to_frames,
)
from motiondiff.geometry.skeleton import SMPL22


@pytest.fixture(scope="module")
def rig():
    return load_split(embedded_data_root(), "test").rig()


def test_frame_counts_from_frames_fractions_and_seconds():
    assert to_frames(7, 80) == 7  # an int is frames
    assert to_frames(0.25, 80) == 20 and to_frames(1.0, 80) == 80  # a float <= 1 is a fraction
    assert to_frames(None, 79) == 20  # default: a quarter, rounded
    assert frames_from_seconds(1.5, 20.0) == 30 and frames_from_fraction(0.5, 41) == 20
    with pytest.raises(EditError, match="prefix_s"):
        to_frames(2.5, 80)  # a float above 1 is neither: say how to give seconds
    for bad in (-1, "a", True):
        with pytest.raises(EditError):
            to_frames(bad, 80)
    with pytest.raises(EditError):
        frames_from_seconds(-1.0, 20.0)


def test_frame_keep_marks_prefix_and_suffix():
    keep = frame_keep(10, 2, 3)
    assert keep.tolist() == [True, True, False, False, False, False, False, True, True, True]
    assert frame_keep(8).tolist() == [True, True, False, False, False, False, True, True]  # 25% each
    assert frame_keep(6, 0, 2).tolist() == [False, False, False, False, True, True]
    with pytest.raises(EditError, match="nothing to generate"):
        frame_keep(10, 5, 5)


def test_resolve_joints_presets_names_indices_and_errors():
    assert resolve_joints(SMPL22, "lower_body") == SMPL22.parts["lower_body"]
    assert 0 in resolve_joints(SMPL22, "lower_body")  # the root (trajectory) goes with the legs, as in MDM
    assert resolve_joints(SMPL22, ["l_wrist", 21, "l_collar"]) == (13, 20, 21)
    assert resolve_joints(SMPL22, "head") == (12, 15)  # a preset wins over the joint of the same name
    assert resolve_joints(SMPL22, ["left_arm", "right_arm"]) == SMPL22.parts["arms"]
    with pytest.raises(EditError, match="lower_body.*upper_body") as err:
        resolve_joints(SMPL22, "lower_bdy")
    assert "left_arm" in str(err.value)  # one message naming every preset
    with pytest.raises(EditError, match="out of range"):
        resolve_joints(SMPL22, [22])
    with pytest.raises(EditError):
        resolve_joints(SMPL22, [])


def test_hml263_lower_body_mask_keeps_trajectory_legs_and_contacts():
    rep = get_representation("hml263", SMPL22)
    sl = feature_slices(22)
    keep = rep.part_keep(resolve_joints(SMPL22, "lower_body"))
    assert keep.shape == (263,) and keep[:4].all()  # root rotation/linear velocity and height
    assert keep[sl["contacts"]].all()  # the foot-contact channels belong to the feet
    ric = keep[sl["ric"]].reshape(21, 3)  # joints 1..21
    assert ric[[j - 1 for j in SMPL22.parts["legs"]]].all() and not ric[[j - 1 for j in SMPL22.parts["arms"]]].any()
    vel = keep[sl["local_vel"]].reshape(22, 3)
    assert vel[0].all() and not vel[SMPL22.index("head")].any()
    upper = rep.part_keep(resolve_joints(SMPL22, "upper_body"))
    assert not upper[:4].any() and not (upper & keep).any() and (upper | keep).all()  # the two halves partition


def test_rig_masks_come_from_the_rig(rig):
    """rp6jr on the Bandai rig: lower_body = the rig's Hips (position + global rotation) and leg joints."""
    rep = get_representation("rp6jr", SMPL22, rig)
    joints = resolve_joints(rep.skeleton, "lower_body")
    assert [rep.skeleton.joint_names[j] for j in joints][:2] == ["Hips", "UpperLeg_L"]
    keep = rep.part_keep(joints)
    assert keep.shape == (rep.dim,) and keep[:9].all()  # root position (3) + root rotation (6)
    spine = rep.skeleton.index("Spine")
    assert not keep[3 + 6 * spine : 3 + 6 * (spine + 1)].any()
    assert keep.sum() == 3 + 6 * len(joints)
    jp = get_representation("jp", SMPL22, rig)
    assert jp.part_keep(joints).sum() == 3 * len(joints)
    hml = get_representation("hml263", SMPL22).part_keep(resolve_joints(SMPL22, "lower_body"))
    assert hml.shape != keep.shape  # a mask belongs to one representation


def test_rig_unknown_part_lists_the_rig_presets(rig):
    with pytest.raises(EditError, match="lower_body") as err:
        resolve_joints(rig, ["Hips", "tail"])
    assert "UpperLeg_L" in str(err.value) and np.all(resolve_joints(rig, "root") == (0,))
