"""Up-axis detection (motiondiff.data.formats.up_axis) on real motion turned to every up axis: the embedded test
clips' joints, and the project's own BVH export of a clip turned as Blender turns a file (a change of basis); files
that cannot be decided warn and are read as Y-up; `BVHMotion.rotated`; the loading API's `up_axis=`."""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest

from motiondiff.data.datamodules import embedded_data_root
from motiondiff.data.formats.bvh import motion_from_arrays, read_bvh, write_bvh
from motiondiff.data.formats.joint_map import JointMap
from motiondiff.data.formats.prepared import load_split
from motiondiff.data.formats.up_axis import (
    AXES,
    UpAxisWarning,
    bvh_up_axis,
    detect_up_axis,
    parse_up_axis,
    rotation_to_y_up,
)
from motiondiff.export import export_bvh
from motiondiff.geometry.rotations import axis_angle_to_quat, matrix_to_quat, qmul, qrot
from motiondiff.geometry.skeleton import SMPL22

HEAD, FEET = SMPL22.index("head"), [7, 8, 10, 11]
TURNED = ("+y", "+z", "-z", "+x")  # the cases the acceptance names; the loop below runs every axis
CLIP_ID = "dataset-1_walk_active_001"


@pytest.fixture(scope="module")
def test_split():
    return load_split(embedded_data_root(), "test")


@pytest.fixture(scope="module")
def clip_joints(test_split):
    i = [str(c) for c in test_split.arrays["ids"]].index(CLIP_ID)
    return test_split.arrays["joints"][test_split.clip_slice(i)].astype(np.float64)


def in_file_axes(joints: np.ndarray, axis: str) -> np.ndarray:
    """Y-up joints as a file whose up is `axis` holds them (the inverse of rotation_to_y_up)."""
    return joints @ rotation_to_y_up(axis)


@pytest.fixture(scope="module")
def exported(clip_joints, tmp_path_factory):
    """The project's own BVH export of the clip (IK, SMPL-22, metres, Y-up), read back."""
    path = export_bvh(tmp_path_factory.mktemp("up") / "walk.bvh", clip_joints, SMPL22, fps=20.0).path
    return read_bvh(path)


def _map(motion):
    return JointMap.infer(motion.joint_names, motion.parents, offsets=motion.offsets)


def test_rotations_to_y_up_are_proper_and_take_each_axis_up():
    for axis in AXES:
        r = rotation_to_y_up(axis)
        assert np.allclose(r @ r.T, np.eye(3)) and np.isclose(np.linalg.det(r), 1.0)
        head = np.zeros(3)
        head["xyz".index(axis[1])] = 1.0 if axis[0] == "+" else -1.0
        assert np.allclose(r @ head, [0, 1, 0])
    assert np.allclose(rotation_to_y_up("+z") @ [0, -1, 0], [0, 0, 1])  # Blender's -Y forward becomes +Z


@pytest.mark.parametrize("axis", TURNED)
def test_every_real_test_clip_turned_to_an_axis_is_detected(test_split, axis):
    for i in range(test_split.num_clips):
        joints = test_split.arrays["joints"][test_split.clip_slice(i)]
        up = detect_up_axis(in_file_axes(joints, axis), HEAD, FEET)
        assert (up.axis, up.decided, up.how) == (axis, True, "motion") and up.share > 0.9


def test_the_other_axes_and_forcing():
    rng = np.random.default_rng(0)
    joints = load_split(embedded_data_root(), "val").arrays["joints"][:200].astype(np.float64)
    for axis in AXES:
        assert detect_up_axis(in_file_axes(joints, axis) + rng.normal(size=3), HEAD, FEET).axis == axis
    forced = detect_up_axis(joints, HEAD, FEET, up_axis="-z")
    assert (forced.axis, forced.how) == ("-z", "forced")
    assert [parse_up_axis(v) for v in ("auto", "y", "Z", "+x", "-y")] == [None, "+y", "+z", "+x", "-y"]
    with pytest.raises(ValueError, match="up_axis='up' is not an axis; choose auto"):
        parse_up_axis("up")


@pytest.mark.parametrize("axis", TURNED)
def test_the_projects_bvh_export_turned_like_blender(exported, axis):
    """A change of basis (offsets, End Sites and rotations turned), in centimetres at 24 fps as Blender writes: the
    motion and the standing rest pose both give the axis."""
    motion = exported.rotated(rotation_to_y_up(axis).T).scaled(100).resample(24)
    up = bvh_up_axis(motion, _map(motion))
    assert (up.axis, up.how, up.motion_axis, up.rest_axis) == (axis, "motion and rest pose", axis, axis)
    back = motion.rotated(up.matrix).scaled(0.01).positions()
    assert np.abs(back - exported.resample(24).positions()).max() < 1e-6


def test_a_rig_whose_rest_pose_is_not_standing_is_decided_by_its_motion(test_split, tmp_path):
    """The Bandai rig lays its rest pose along x (head 0.5 m from the feet): no rest evidence, the motion decides."""
    a, i = test_split.arrays, [str(c) for c in test_split.arrays["ids"]].index(CLIP_ID)
    s = test_split.clip_slice(i)
    motion = motion_from_arrays([str(n) for n in a["native_joint_names"]], a["native_parents"],
                                a["native_offsets"][i] * 100, a["native_rotations"][s], a["native_root"][s] * 100,
                                fps=20.0)  # fmt: skip
    motion = read_bvh(write_bvh(tmp_path / "bandai.bvh", motion.rotated(rotation_to_y_up("-z").T)))
    up = bvh_up_axis(motion, _map(motion))
    assert (up.axis, up.how, up.rest_axis) == ("-z", "motion", None)


def test_a_tumbling_body_warns_and_is_read_as_y_up(clip_joints):
    """The head-over-feet direction turns a full circle about x over the clip: no axis has the head above."""
    n = len(clip_joints)
    turn = axis_angle_to_quat(np.tile([1.0, 0.0, 0.0], (n, 1)), np.linspace(0, 2 * np.pi, n, endpoint=False))
    centre = clip_joints.mean(axis=1, keepdims=True)
    tumbling = qrot(turn[:, None], clip_joints - centre) + centre
    with pytest.warns(UpAxisWarning, match=r"tumble\.npy: cannot tell the up axis.*up_axis=y\|z\|x"):
        up = detect_up_axis(tumbling, HEAD, FEET, source="tumble.npy")
    assert (up.axis, up.decided, up.how) == ("+y", False, "undecided")
    with pytest.warns(UpAxisWarning, match="at the same place in every frame"):
        detect_up_axis(np.zeros((10, 22, 3)), HEAD, FEET, source="flat.npy")


def test_motion_and_rest_pose_that_disagree_warn(exported):
    """Only the root turned to Z-up (the rest pose stays standing along y): the evidence contradicts itself."""
    r = rotation_to_y_up("+z").T
    rotations = exported.rotations.copy()
    rotations[:, 0] = qmul(np.broadcast_to(matrix_to_quat(r), rotations[:, 0].shape), rotations[:, 0])
    translations = exported.translations.copy()
    translations[:, 0] = translations[:, 0] @ r.T
    turned = replace(exported, rotations=rotations, translations=translations, source="root_only.bvh")
    with pytest.warns(UpAxisWarning, match=r"root_only\.bvh: .*along \+z but the rest pose stands along \+y"):
        up = bvh_up_axis(turned, _map(turned))
    assert (up.axis, up.decided, up.motion_axis, up.rest_axis) == ("+y", False, "+z", "+y")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert bvh_up_axis(turned, _map(turned), up_axis="z").axis == "+z"  # forcing it is silent


def test_rotated_is_a_change_of_basis(exported):
    r = rotation_to_y_up("-x")
    turned = exported.rotated(r)
    assert np.allclose(turned.positions(), exported.positions() @ r.T, atol=1e-9)
    assert np.allclose(turned.offsets, exported.offsets @ r.T)
    assert all(np.allclose(turned.end_sites[j], r @ v) for j, v in exported.end_sites.items())
    with pytest.raises(ValueError, match="3x3 rotation"):
        exported.rotated(np.diag([1.0, 1.0, -1.0]))


# ---- the loading API ---------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def model():
    from motiondiff.pipelines import MotionPipeline

    return MotionPipeline.from_pretrained("text").model


def test_load_input_motion_turns_joint_files_to_y_up(model, clip_joints, tmp_path):
    from motiondiff.edit import load_input_motion
    from motiondiff.edit.masks import EditError

    np.save(tmp_path / "y.npy", clip_joints)
    np.save(tmp_path / "z.npy", in_file_axes(clip_joints, "+z"))
    np.savez(tmp_path / "x.npz", joints=in_file_axes(clip_joints, "-x"))
    plain = load_input_motion(tmp_path / "y.npy", model)
    assert plain.up.axis == "+y" and plain.up.decided
    for name, axis in (("z.npy", "+z"), ("x.npz", "-x")):
        motion = load_input_motion(tmp_path / name, model)
        assert motion.up.axis == axis
        assert np.abs(motion.joints - plain.joints).max() < 1e-5
    forced = load_input_motion(tmp_path / "z.npy", model, up_axis="y")  # forced: read as it is (lying)
    assert forced.up.how == "forced" and np.abs(forced.joints - plain.joints).max() > 0.1
    with pytest.raises(EditError, match="up_axis='sideways' is not an axis"):
        load_input_motion(tmp_path / "y.npy", model, up_axis="sideways")
    np.savez(tmp_path / "two.npz", a=clip_joints, b=clip_joints)
    with pytest.raises(EditError, match="holds arrays a, b; name the joint positions 'joints'"):
        load_input_motion(tmp_path / "two.npz", model)
