"""SMPL parameter files as motion input (motiondiff.data.formats.smpl_params): joints of AMASS-layout files through a
body model (a synthetic one of the real model's layout), this project's own export=smpl files without one, meshes by
linear blend skinning, and one clear message for what cannot be read."""

from __future__ import annotations

import numpy as np
import pytest
from fixtures.synthetic_smpl import smpl_rest_joints, write_synthetic_smpl
from scipy.spatial.transform import Rotation

from motiondiff.data.datamodules import embedded_data_root
from motiondiff.data.formats.prepared import load_split
from motiondiff.data.formats.smpl_params import (
    SmplParamsError,
    is_smpl_params,
    load_smpl_body,
    read_smpl_params,
)
from motiondiff.export import export_smpl
from motiondiff.geometry.skeleton import SMPL22, SMPL24

FRAMES = 12


def smpl_fk(poses: np.ndarray, trans: np.ndarray, rest: np.ndarray) -> np.ndarray:
    """Joints (N, J, 3) the way the SMPL model computes them: 4x4 transforms [R_j | J_j - J_parent] chained from
    the root, Rodrigues rotations, the translation added to everything (`smplx.lbs.batch_rigid_transform`)."""
    parents, count = SMPL24.parents, len(rest)
    out = np.zeros((len(poses), count, 3))
    for n, pose in enumerate(poses):
        world = [None] * count
        for j in range(count):
            local = np.eye(4)
            local[:3, :3] = Rotation.from_rotvec(pose[3 * j : 3 * j + 3]).as_matrix()
            local[:3, 3] = rest[j] - (rest[parents[j]] if parents[j] >= 0 else 0.0)
            world[j] = local if parents[j] < 0 else world[parents[j]] @ local
            out[n, j] = world[j][:3, 3] + trans[n]
    return out


def amass_file(path, poses, trans, betas, fps=60.0, layout="poses"):
    arrays = {"trans": trans, "betas": betas, "gender": np.array("neutral"), "mocap_framerate": np.array(fps)}
    if layout == "poses":
        arrays["poses"] = poses
    else:
        arrays.update(root_orient=poses[:, :3], pose_body=poses[:, 3:66])  # AMASS SMPL-X
    np.savez(path, **arrays)
    return path


@pytest.fixture
def motion_arrays():
    rng = np.random.default_rng(1)
    poses = np.zeros((FRAMES, 156))  # SMPL+H: 52 joints, the first 22 the body
    poses[:, :66] = rng.normal(scale=0.3, size=(FRAMES, 66))
    return poses, rng.normal(scale=0.5, size=(FRAMES, 3)), rng.normal(size=16)


@pytest.mark.parametrize("layout", ["poses", "smplx"])
def test_amass_joints_through_a_body_model_match_smpl_fk(tmp_path, motion_arrays, layout):
    poses, trans, betas = motion_arrays
    body = load_smpl_body(write_synthetic_smpl(tmp_path / "model.npz"))
    motion = read_smpl_params(amass_file(tmp_path / "clip.npz", poses, trans, betas, layout=layout), body)
    expected = smpl_fk(poses[:, :66], trans, body.rest_joints(betas)[:22])
    assert motion.joint_names == list(SMPL22.joint_names) and motion.frame_time == pytest.approx(1 / 60)
    np.testing.assert_allclose(motion.positions(), expected, atol=1e-9)
    assert not np.allclose(body.rest_joints(betas), smpl_rest_joints())  # the shape mattered


def test_an_export_smpl_file_reads_back_without_a_model(tmp_path):
    clip = load_split(embedded_data_root(), "val").clips()[0].joints.astype(np.float64)
    export_smpl(tmp_path / "clip_smpl.npz", clip, SMPL22, 20.0)
    motion = read_smpl_params(tmp_path / "clip_smpl.npz")
    np.testing.assert_allclose(motion.positions(), clip, atol=1e-6)
    assert motion.frame_time == pytest.approx(0.05)


def test_mesh_vertices_follow_their_joints(tmp_path, motion_arrays):
    poses, trans, betas = motion_arrays
    body = load_smpl_body(write_synthetic_smpl(tmp_path / "model.npz"))
    rest = np.tile([1.0, 0.0, 0.0, 0.0], (1, 24, 1))
    np.testing.assert_allclose(body.vertices(rest, np.zeros((1, 3)), betas)[0], body.shaped(betas), atol=1e-12)
    # a turned root only: the whole mesh turns about the pelvis and moves by trans
    turn = Rotation.from_rotvec([0.0, 0.7, 0.2])
    rotations = rest.copy()
    rotations[0, 0] = turn.as_quat()[[3, 0, 1, 2]]
    shift = np.array([[0.3, 0.1, -0.2]])
    body_no_correctives = load_smpl_body(write_synthetic_smpl(tmp_path / "m2.npz"))
    object.__setattr__(body_no_correctives, "posedirs", None)
    pelvis = body_no_correctives.rest_joints(betas)[0]
    expected = turn.apply(body_no_correctives.shaped(betas) - pelvis) + pelvis + shift
    np.testing.assert_allclose(body_no_correctives.vertices(rotations, shift, betas)[0], expected, atol=1e-12)
    assert body.vertices(np.repeat(rest, FRAMES, axis=0), trans, betas).shape == (FRAMES, 24 * 6, 3)


def test_what_cannot_be_read_names_the_fix(tmp_path, motion_arrays):
    poses, trans, betas = motion_arrays
    clip = amass_file(tmp_path / "clip.npz", poses, trans, betas)
    with pytest.raises(SmplParamsError, match=r"not the skeleton; .*licence-restricted .*smpl_model=") as caught:
        read_smpl_params(clip)
    assert "\n" not in str(caught.value)
    with pytest.raises(SmplParamsError, match=r"\.pkl holds chumpy objects: convert it"):
        load_smpl_body(tmp_path / "SMPL_NEUTRAL.pkl")
    np.savez(tmp_path / "half.npz", v_template=np.zeros((5, 3)))
    with pytest.raises(SmplParamsError, match="lacks shapedirs, J_regressor, kintree_table"):
        load_smpl_body(tmp_path / "half.npz")
    np.savez(tmp_path / "nofps.npz", poses=poses, trans=trans)
    with pytest.raises(SmplParamsError, match="no positive frame rate"):
        read_smpl_params(tmp_path / "nofps.npz", load_smpl_body(write_synthetic_smpl(tmp_path / "model.npz")))
    np.savez(tmp_path / "short.npz", poses=poses[:, :30], trans=trans, mocap_framerate=30.0)
    with pytest.raises(SmplParamsError, match="at least the 22 body joints"):
        read_smpl_params(tmp_path / "short.npz")
    assert is_smpl_params(["poses", "trans", "betas"]) and not is_smpl_params(["joints"])
