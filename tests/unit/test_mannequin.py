"""The mannequin (motiondiff.geometry.mannequin): closed, outward-wound pieces bound to joints of the skeleton on
SMPL-22, KIT-21 and a Bandai-style rig whose root stands on the ground; posed from joints, every vertex stays on its
capsule around the posed joints; the rigid binding an armature applies (each vertex moved by its owner joint's
world transform) puts every vertex on the same capsules."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from motiondiff.data.datamodules import embedded_data_root
from motiondiff.data.formats.prepared import load_split
from motiondiff.geometry.inverse_kinematics import fit_rest_offsets
from motiondiff.geometry.kinematics import forward_kinematics
from motiondiff.geometry.mannequin import build_mannequin
from motiondiff.geometry.rotations import qrot
from motiondiff.geometry.skeleton import KIT21, SMPL22, Skeleton

BANDAI_NAMES = ("joint_Root", "Hips", "Spine", "Chest", "Neck", "Head", "Shoulder_L", "UpperArm_L", "LowerArm_L",
                "Hand_L", "Shoulder_R", "UpperArm_R", "LowerArm_R", "Hand_R", "UpperLeg_L", "LowerLeg_L", "Foot_L",
                "Toes_L", "UpperLeg_R", "LowerLeg_R", "Foot_R", "Toes_R")  # fmt: skip
BANDAI_PARENTS = (-1, 0, 1, 2, 3, 4, 3, 6, 7, 8, 3, 10, 11, 12, 1, 14, 15, 16, 1, 18, 19, 20)
BANDAI_OFFSETS = np.array(
    [[0, 0, 0], [0, 0.94, 0], [0, 0.1, 0], [0, 0.15, 0], [0, 0.2, 0], [0, 0.1, 0.02], [0.05, 0.15, 0],
     [0.1, 0, 0], [0.25, 0, 0], [0.22, 0, 0], [-0.05, 0.15, 0], [-0.1, 0, 0], [-0.25, 0, 0], [-0.22, 0, 0],
     [0.1, -0.05, 0], [0, -0.4, 0], [0, -0.4, 0], [0, -0.05, 0.12], [-0.1, -0.05, 0], [0, -0.4, 0], [0, -0.4, 0],
     [0, -0.05, 0.12]]
)  # fmt: skip
BANDAI = Skeleton.infer("bandai", BANDAI_NAMES, BANDAI_PARENTS, BANDAI_OFFSETS)
SKELETONS = {"smpl22": SMPL22, "kit21": KIT21.with_offsets(KIT21.offsets * 0.3), "bandai": BANDAI}


@pytest.fixture(scope="module")
def clip():
    return load_split(embedded_data_root(), "val").clips()[0].joints.astype(np.float64)  # SMPL-22, 20 fps


def end_points(mannequin, joints: np.ndarray, end: int) -> np.ndarray:
    """(N, P, 3) end point `end` (0: A, 1: B) of every piece, by the documented rule."""
    at = joints[:, mannequin.joint[:, end]]
    toward = mannequin.toward[:, end]
    bone = at - joints[:, np.maximum(toward, 0)]
    unit = bone / np.maximum(np.linalg.norm(bone, axis=-1, keepdims=True), 1e-12)
    return at + np.where((toward >= 0)[:, None], mannequin.reach[:, end, None] * unit, 0.0)


def assert_on_capsules(mannequin, joints: np.ndarray, vertices: np.ndarray) -> None:
    """Each vertex at its rest distance from its piece's end point, and as far along the posed axis as at rest."""
    radius = np.hypot(mannequin.along, np.linalg.norm(mannequin.ring, axis=-1))
    ends = np.stack([end_points(mannequin, joints, e) for e in (0, 1)])  # (2, N, P, 3)
    end = ends[mannequin.t.astype(int), :, mannequin.piece].transpose(1, 0, 2)  # (N, V, 3)
    axis = joints[:, mannequin.axis_to] - joints[:, mannequin.axis_from]
    axis = (axis / np.linalg.norm(axis, axis=-1, keepdims=True))[:, mannequin.piece]
    offset = vertices - end
    np.testing.assert_allclose(np.linalg.norm(offset, axis=-1), np.broadcast_to(radius, offset.shape[:2]), atol=1e-9)
    np.testing.assert_allclose((offset * axis).sum(-1), np.broadcast_to(mannequin.along, offset.shape[:2]),
                               atol=1e-9)  # fmt: skip


@pytest.mark.parametrize("name", sorted(SKELETONS))
def test_every_piece_is_a_closed_outward_surface_bound_to_a_joint(name):
    skeleton = SKELETONS[name]
    mannequin = build_mannequin(skeleton)
    vertices, faces = mannequin.rest_vertices(), mannequin.faces
    assert faces.min() == 0 and faces.max() == mannequin.num_vertices - 1
    weights = mannequin.weights
    assert weights.shape == (mannequin.num_vertices, skeleton.num_joints)
    np.testing.assert_array_equal(weights.sum(1), 1.0)  # every vertex on exactly one existing joint
    bound = set(mannequin.owners.tolist())
    ground_root = name == "bandai"  # its root stands on the ground: nothing hangs from it
    assert bound == set(range(1 if ground_root else 0, skeleton.num_joints))
    if ground_root:
        assert 0 not in mannequin.joint and 0 not in mannequin.axis_from
    for piece in range(len(mannequin.joint)):
        mine = faces[(mannequin.piece[faces] == piece).all(1)]
        edges = np.sort(np.concatenate([mine[:, [0, 1]], mine[:, [1, 2]], mine[:, [2, 0]]]), axis=1)
        _, counts = np.unique(edges, axis=0, return_counts=True)
        assert (counts == 2).all()  # closed: every edge joins two triangles of the piece
        v = vertices[mine]
        assert np.linalg.det(v).sum() / 6 > 0  # counter-clockwise from outside: positive enclosed volume
    assert len(faces) == sum((mannequin.piece[faces] == p).all(1).sum() for p in range(len(mannequin.joint)))


def test_the_body_is_around_the_skeleton_and_sized_by_it():
    small, large = (build_mannequin(SMPL22, SMPL22.offsets * k).rest_vertices() for k in (1.0, 2.0))
    np.testing.assert_allclose(large, 2 * small, atol=1e-12)  # proportions are fractions of the stature
    joints = build_mannequin(SMPL22).rest_positions()
    low, high = small.min(0), small.max(0)
    assert (low < joints.min(0)).all() and (high > joints.max(0)).all()
    assert (low > joints.min(0) - 0.25).all() and (high < joints.max(0) + 0.25).all()


def test_posed_from_joints_every_vertex_stays_on_its_capsule(clip):
    mannequin = build_mannequin(SMPL22, fit_rest_offsets(clip, SMPL22))
    vertices = mannequin.at(clip)
    assert vertices.shape == (len(clip), mannequin.num_vertices, 3)
    assert_on_capsules(mannequin, clip, vertices)
    shift = np.array([1.5, 0.0, -2.0])
    np.testing.assert_allclose(mannequin.at(clip + shift), vertices + shift, atol=1e-12)
    np.testing.assert_allclose(mannequin.at(mannequin.rest_positions()[None])[0], mannequin.rest_vertices())
    with pytest.raises(ValueError, match=r"joints must be finite with shape \(frames, 22, 3\)"):
        mannequin.at(clip[:, :21])


@pytest.mark.parametrize("name", sorted(SKELETONS))
def test_the_rigid_binding_of_an_armature_gives_the_same_capsules(name):
    skeleton = SKELETONS[name]
    mannequin = build_mannequin(skeleton)
    frames = 5
    rotations = Rotation.random(frames * skeleton.num_joints, random_state=3).as_quat()[:, [3, 0, 1, 2]]
    rotations = rotations.reshape(frames, skeleton.num_joints, 4)
    leaves = [j for j, kids in enumerate(skeleton.children) if not kids]
    rotations[:, leaves] = [1.0, 0.0, 0.0, 0.0]  # as IK and the BVH export leave them
    root = np.random.default_rng(3).normal(size=(frames, 3))
    translations = np.repeat(skeleton.offsets[None], frames, axis=0)
    translations[:, 0] = root
    joints, world = forward_kinematics(rotations, translations, skeleton.parents)
    rest, owner = mannequin.rest_positions(), mannequin.owners
    rigid = joints[:, owner] + qrot(world[:, owner], mannequin.rest_vertices() - rest[owner])  # linear blend, weight 1
    assert_on_capsules(mannequin, joints, rigid)
    np.testing.assert_allclose(mannequin.posed(rotations, root), rigid, atol=1e-12)
