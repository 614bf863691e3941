"""SMPL parameter export (motiondiff.export.smpl_export, export=smpl).

Acceptance: forward kinematics of the written file on the SMPL kinematic tree with the rest pose the file records,
computed here the way the SMPL body model does it (Rodrigues rotations chained as 4x4 transforms over the rest
joints, `smplx.lbs.batch_rigid_transform`), gives back the exported joints to <= 2 cm (max over frames and joints)
for every real clip of the embedded val split, and for the released text model's output after cleanup=bones (its
raw joints stretch their bones, which no fixed skeleton follows; their fit is held to the best one can do). Also:
SMPL's layout and conventions, a rotation representation's own rotations written as they are, and one clear error
for a skeleton that is not SMPL's."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from motiondiff.data.datamodules import embedded_data_root
from motiondiff.data.formats.prepared import load_split
from motiondiff.data.representations import get_representation
from motiondiff.data.representations.clip import ClipMotion
from motiondiff.edit.rigid_bones import bone_length_range
from motiondiff.export import export_smpl, export_smpl_from_features, smpl_joints
from motiondiff.export.outputs import export_features, parse_formats
from motiondiff.export.smpl_export import SMPL_NEUTRAL_PELVIS, SmplLayoutError
from motiondiff.geometry.kinematics import forward_kinematics
from motiondiff.geometry.rotations import qangle
from motiondiff.geometry.skeleton import KIT21, SMPL22, SMPL24
from motiondiff.pipelines import MotionOutput, MotionPipeline
from motiondiff.runtime.errors import UsageError

TOL = 0.02  # metres: the acceptance criterion (max over frames and joints)
KEYS = {"poses", "trans", "mocap_framerate", "gender", "betas", "global_orient", "body_pose", "transl",
        "rest_offsets", "rest_joints", "parents", "joint_names", "up_axis"}  # fmt: skip


@pytest.fixture(scope="module")
def val_clips():
    return load_split(embedded_data_root(), "val").clips()


def load(path) -> dict:
    with np.load(path) as f:  # no allow_pickle: every array is plain numbers or text
        return {k: f[k] for k in f.files}


def smpl_model_fk(data: dict) -> np.ndarray:
    """Joints (F, 24, 3) as the SMPL model poses its skeleton: each joint's 4x4 transform is its parent's times
    [Rodrigues(pose_j) | J_j - J_parent], the root's [R_0 | J_0]; posed joints are the transforms' translations plus
    `trans`. Independent of motiondiff.geometry.kinematics (matrices, absolute rest joints, no quaternions)."""
    poses, rest, parents = data["poses"], data["rest_joints"], data["parents"]
    frames = len(poses)
    rot = Rotation.from_rotvec(poses.reshape(-1, 3)).as_matrix().reshape(frames, 24, 3, 3)
    transforms = np.zeros((frames, 24, 4, 4))
    for j in range(24):
        local = np.zeros((frames, 4, 4))
        local[:, :3, :3], local[:, 3, 3] = rot[:, j], 1.0
        local[:, :3, 3] = rest[j] - (rest[parents[j]] if parents[j] >= 0 else 0.0)
        transforms[:, j] = local if parents[j] < 0 else transforms[:, parents[j]] @ local
    return transforms[:, :, :3, 3] + data["trans"][:, None]


def fk_error(path, joints: np.ndarray) -> np.ndarray:
    data = load(path)
    return np.linalg.norm(smpl_model_fk(data)[:, : joints.shape[1]] - joints, axis=-1)


# ---- layout and conventions -----------------------------------------------------------------------------------------
def test_layout_and_smpl_conventions(val_clips, tmp_path):
    joints = val_clips[0].joints
    n = len(joints)
    report = export_smpl(tmp_path / "clip_smpl.npz", joints, SMPL22, 20)
    data = load(report.path)
    assert set(data) == KEYS and report.method == "ik" and report.frames == n
    assert data["poses"].shape == (n, 72) and data["trans"].shape == (n, 3) and data["body_pose"].shape == (n, 69)
    assert str(data["gender"]) == "neutral" and float(data["mocap_framerate"]) == 20.0 and str(data["up_axis"]) == "y"
    assert data["betas"].shape == (10,) and not data["betas"].any()
    np.testing.assert_array_equal(data["global_orient"], data["poses"][:, :3])
    np.testing.assert_array_equal(data["body_pose"], data["poses"][:, 3:])
    np.testing.assert_array_equal(data["transl"], data["trans"])
    assert data["parents"].tolist() == list(SMPL24.parents) and data["joint_names"].tolist() == list(SMPL24.joint_names)
    assert not data["poses"][:, 66:].any()  # SMPL-22 has no hands: SMPL joints 22 and 23 stay at the rest pose
    # the pelvis is at trans + SMPL's rest pelvis J_0, as an SMPL body with zero shape puts it
    np.testing.assert_allclose(data["rest_offsets"][0], SMPL_NEUTRAL_PELVIS)
    np.testing.assert_allclose(data["trans"] + data["rest_joints"][0], joints[:, 0], atol=1e-9)
    # the rotations are relative to SMPL's rest pose: every bone points the way the SMPL template's does, exactly
    # where a joint has one child; the hips and collars keep the data's arrangement around pelvis and chest, turned
    # to fit the template's (the Bandai hips sit 39 degrees off SMPL's seen from the pelvis)
    rest, template = data["rest_offsets"], SMPL24.offsets
    cos = (rest * template).sum(-1) / np.maximum(
        np.linalg.norm(rest, axis=-1) * np.linalg.norm(template, axis=-1), 1e-12
    )
    branching = [c for c in range(1, 24) if len(SMPL24.children[SMPL24.parents[c]]) > 1]
    single = [c for c in range(1, 22) if c not in branching]
    print(
        f"\nrest bones vs the SMPL template: cosines {np.round(cos[branching], 3)} (branching), {cos[single].min():.6f}"
    )
    assert cos[single].min() > 1 - 1e-9 and cos[branching].min() > 0.7
    # the zero pose puts the joints at the recorded rest joints
    zero = dict(data, poses=np.zeros((1, 72)), trans=np.zeros((1, 3)))
    np.testing.assert_allclose(smpl_model_fk(zero)[0], data["rest_joints"], atol=1e-12)
    np.testing.assert_allclose(smpl_joints(data), smpl_model_fk(data), atol=1e-9)  # the library's FK agrees


def test_rotations_are_written_as_given(tmp_path):
    """A rotation representation on the SMPL-24 rig (HumanAct12/UESTC) writes the model's own rotations: the
    poses are its axis-angles exactly, the rig's FK comes back, no IK."""
    frames = 12
    rotations = Rotation.random(frames * 24, random_state=3).as_quat()[:, [3, 0, 1, 2]].reshape(frames, 24, 4)
    root = np.random.default_rng(3).normal(size=(frames, 3)) + [0.0, 0.9, 0.0]
    translations = np.repeat(SMPL24.offsets[None], frames, axis=0)
    translations[:, 0] = root
    joints = forward_kinematics(rotations, translations, SMPL24.parents)[0]
    clip = ClipMotion(joints=joints[:, :22].astype(np.float32), rotations=rotations, root=root, rig=SMPL24)
    rep = get_representation("rp6jr", SMPL22, SMPL24)
    report = export_smpl_from_features(tmp_path / "rot_smpl.npz", rep, rep.encode(clip), 30)
    data = load(report.path)
    assert report.method == "rotations" and report.max_error < 1e-5
    written = Rotation.from_rotvec(data["poses"].reshape(-1, 3)).as_quat()[:, [3, 0, 1, 2]].reshape(frames, 24, 4)
    assert qangle(written, rotations).max() < 1e-5  # float32 features: 6D columns to 1e-7
    assert fk_error(report.path, joints).max() < 1e-5


# ---- acceptance ---------------------------------------------------------------------------------------------------
def test_real_clips_reproduced_within_2cm(val_clips, tmp_path):
    errors = []
    for i, clip in enumerate(val_clips):
        report = export_smpl(tmp_path / f"clip{i}_smpl.npz", clip.joints, SMPL22, 20)
        err = fk_error(report.path, clip.joints)
        assert abs(err.max() - report.max_error) < 1e-6  # the report tells the truth about the file
        errors.append(err)
    worst, mean = max(e.max() for e in errors), float(np.mean(np.concatenate([e.ravel() for e in errors])))
    print(f"\nSMPL FK of {len(val_clips)} real val clips: max {worst:.1e} m, mean {mean:.1e} m")
    assert worst <= TOL


def test_released_text_model_output_reproduced_within_2cm_after_bone_cleanup(tmp_path):
    # sample.py's defaults (DDIM-50). The model's joints stretch their bones (a wrist bone by up to 8 cm over these
    # walks), which no file with one set of bone lengths can follow: the fit of the raw joints stays within 0.7 cm of
    # that bound (a quarter of the largest length change). After cleanup=bones the joints lie on one skeleton, and
    # the file reproduces them.
    out = MotionPipeline.from_pretrained("text")("a person walks forward", seconds=4, num_samples=2, seed=0)
    raw = out.save(tmp_path / "raw", formats=["smpl"])
    bounds = [bone_length_range(j, SMPL22).max() / 4 for j in out.joints]
    raw_errors = [fk_error(row["exports"]["smpl"], j).max() for row, j in zip(raw, out.joints, strict=True)]
    cleaned = out.cleaned("bones")
    rows = cleaned.save(tmp_path / "rigid", formats=["smpl"])
    errors = [fk_error(row["exports"]["smpl"], joints) for row, joints in zip(rows, cleaned.joints, strict=True)]
    worst, mean = max(e.max() for e in errors), float(np.mean(errors))
    print(
        f"\nSMPL FK of the released text model's walks: raw joints max {100 * max(raw_errors):.3f} cm (bound "
        f"{100 * max(bounds):.3f} cm); after cleanup=bones max {100 * worst:.1e} cm, mean {100 * mean:.1e} cm"
    )
    assert all(b - 1e-6 <= e <= b + 0.007 for e, b in zip(raw_errors, bounds, strict=True))
    assert worst <= 1e-4 <= TOL  # float32 joints
    assert max(c["bones"]["max_move_m"] for c in cleaned.info["cleanup"]) <= max(bounds) + 0.007
    assert rows[0]["exports"]["smpl"].endswith("_smpl.npz") and rows[0]["exports"]["smpl_method"] == "ik"
    assert abs(raw[0]["exports"]["smpl_max_error_m"] - raw_errors[0]) < 1e-6


# ---- refusals -----------------------------------------------------------------------------------------------------
def test_a_skeleton_that_is_not_smpl_gets_one_clear_error(tmp_path):
    frames = 5
    rotations = Rotation.random(frames * 21, random_state=0).as_quat()[:, [3, 0, 1, 2]].reshape(frames, 21, 4)
    kit = forward_kinematics(rotations, np.repeat(KIT21.offsets[None], frames, axis=0), KIT21.parents)[0]
    message = r"export=smpl needs a motion on SMPL-22 .* or SMPL-24 .*; this one is on 'kit21' \(21 joints\)"
    with pytest.raises(SmplLayoutError, match=message) as caught:
        export_smpl(tmp_path / "kit_smpl.npz", kit, KIT21, 12.5)
    assert isinstance(caught.value, UsageError) and "\n" not in str(caught.value)
    rep = get_representation("kit251", KIT21)
    feats = np.zeros((frames, rep.dim))
    with pytest.raises(UsageError, match=message):
        export_features(tmp_path / "kit", rep, feats, 12.5, ["bvh", "smpl"])
    output = MotionOutput([kit], [feats], [None], 12.5, KIT21, rep)
    with pytest.raises(UsageError, match=message):
        output.save(tmp_path / "saved", formats=["mp4", "smpl"])
    assert list(tmp_path.rglob("*")) == []  # refused before anything was written
    assert "smpl" in parse_formats("mp4,smpl")
