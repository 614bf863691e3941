"""torch_rotations and the torch FK against their numpy twins (rotations.py, kinematics.py), orthonormality of the
6D decoding, and finite gradients at the singular points (zero rotation, 180-degree turns)."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from scipy.spatial.transform import Rotation

from motiondiff.geometry import rotations as R
from motiondiff.geometry import torch_rotations as T
from motiondiff.geometry.kinematics import forward_kinematics, forward_kinematics_torch

TOL = 1e-6


@pytest.fixture(scope="module")
def rots():
    """Random rotations plus the hard cases: identity, tiny angles, exact 180-degree turns about axes and a diagonal."""
    rand = Rotation.random(500, random_state=0)
    special = Rotation.from_rotvec(
        [[0, 0, 0], [1e-9, 0, 0], [0, 1e-5, 2e-5], [np.pi, 0, 0], [0, np.pi, 0], [0, 0, np.pi]]
        + [list(np.pi * np.array([1.0, 1.0, 0.0]) / np.sqrt(2))]
    )
    return Rotation.concatenate([rand, special])


def t64(x) -> torch.Tensor:
    return torch.as_tensor(np.asarray(x), dtype=torch.float64)


def same_up_to_sign(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.minimum(np.abs(a - b).max(-1), np.abs(a + b).max(-1)).max())


def test_quat_matrix_both_ways(rots):
    q = rots.as_quat()[:, [3, 0, 1, 2]]
    m = rots.as_matrix()
    assert np.abs(T.quat_to_matrix(t64(q)).numpy() - R.quat_to_matrix(q)).max() <= TOL
    back = T.matrix_to_quat(t64(m)).numpy()
    assert same_up_to_sign(back, R.matrix_to_quat(m)) <= TOL
    assert (back[:, 0] >= 0).all()
    assert np.abs(T.quat_to_matrix(t64(back)).numpy() - m).max() <= TOL  # exact also at 180 degrees


def test_quaternion_algebra(rots):
    q = rots.as_quat()[:, [3, 0, 1, 2]]
    p = np.roll(q, 1, axis=0)
    v = np.random.default_rng(0).normal(size=(len(q), 3))
    assert np.abs(T.qmul(t64(q), t64(p)).numpy() - R.qmul(q, p)).max() <= TOL
    assert np.abs(T.qrot(t64(q), t64(v)).numpy() - R.qrot(q, v)).max() <= TOL
    assert np.abs(T.qinv(t64(q)).numpy() - R.qinv(q)).max() <= TOL
    # broadcasting one rotation over many vectors
    assert T.qrot(t64(q[:1]), t64(v)).shape == (len(v), 3)


def test_sixd(rots):
    m = rots.as_matrix()
    d6 = R.matrix_to_6d(m)
    assert np.abs(T.matrix_to_6d(t64(m)).numpy() - d6).max() <= TOL
    noisy = d6 + np.random.default_rng(1).normal(scale=0.3, size=d6.shape)  # what a network outputs
    got = T.sixd_to_matrix(t64(noisy)).numpy()
    assert np.abs(got - R.sixd_to_matrix(noisy)).max() <= TOL
    assert np.abs(got @ np.swapaxes(got, -1, -2) - np.eye(3)).max() <= TOL
    assert np.abs(np.linalg.det(got) - 1).max() <= TOL
    assert np.abs(T.sixd_to_matrix(t64(d6)).numpy() - m).max() <= TOL


def test_axis_angle(rots):
    v = rots.as_rotvec()
    m = rots.as_matrix()
    assert np.abs(T.axis_angle_to_matrix(t64(v)).numpy() - m).max() <= TOL
    back = T.matrix_to_axis_angle(t64(m)).numpy()
    # at exactly 180 degrees v and -v are the same rotation: compare the matrices there
    assert np.abs(T.axis_angle_to_matrix(t64(back)).numpy() - m).max() <= TOL
    regular = np.linalg.norm(v, axis=-1) < np.pi - 1e-3
    assert np.abs(back[regular] - v[regular]).max() <= TOL
    q = T.axis_angle_to_quat(t64(v)).numpy()
    assert same_up_to_sign(q, rots.as_quat()[:, [3, 0, 1, 2]]) <= TOL


@pytest.mark.parametrize("order", ["XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX"])
def test_euler_matches_numpy(order):
    angles = np.random.default_rng(2).uniform(-np.pi, np.pi, size=(300, 3))
    want = R.euler_to_matrix(angles, order, degrees=False)
    assert np.abs(T.euler_to_matrix(t64(angles), order).numpy() - want).max() <= TOL
    back = R.matrix_to_euler(want, order, degrees=False)  # the encoder's direction, then decode again
    assert np.abs(T.euler_to_matrix(t64(back), order).numpy() - want).max() <= TOL
    with pytest.raises(ValueError, match="three of X, Y, Z"):
        T.euler_to_matrix(t64(angles), "XYW")


def test_torch_fk_matches_numpy_fk():
    rng = np.random.default_rng(3)
    parents = (-1, 0, 1, 2, 1, 4, 0, 6)
    q = Rotation.random(5 * 8, random_state=4).as_quat()[:, [3, 0, 1, 2]].reshape(5, 8, 4)
    trans = rng.normal(size=(5, 8, 3))
    pos, world = forward_kinematics(q, trans, parents)
    got_pos, got_world = forward_kinematics_torch(T.quat_to_matrix(t64(q)), t64(trans), parents)
    assert np.abs(got_pos.numpy() - pos).max() <= TOL
    assert np.abs(got_world.numpy() - R.quat_to_matrix(world)).max() <= TOL
    # shared offsets (J, 3) broadcast over frames
    got_pos2, _ = forward_kinematics_torch(T.quat_to_matrix(t64(q)), t64(trans[0]), parents)
    assert got_pos2.shape == (5, 8, 3)


def test_float32_stays_float32():
    x = torch.randn(4, 6)
    assert T.sixd_to_matrix(x).dtype == torch.float32
    assert T.matrix_to_quat(T.sixd_to_matrix(x)).dtype == torch.float32
    assert T.euler_to_matrix(torch.randn(4, 3), "XYZ").dtype == torch.float32


@pytest.mark.parametrize(
    "fn, x",
    [
        (T.axis_angle_to_matrix, torch.zeros(2, 3)),  # zero rotation
        (T.axis_angle_to_quat, torch.zeros(2, 3)),
        (T.quat_to_axis_angle, torch.tensor([[1.0, 0, 0, 0], [0.0, 1, 0, 0]])),  # identity and 180 degrees
        (T.matrix_to_quat, torch.stack([torch.eye(3), torch.diag(torch.tensor([1.0, -1, -1]))])),
        (T.sixd_to_matrix, torch.tensor([[1.0, 0, 0, 0, 1, 0]])),
        (lambda a: T.euler_to_matrix(a, "XYZ"), torch.tensor([[0.0, np.pi / 2, 0.0]])),  # gimbal lock
    ],
)
def test_gradients_are_finite_at_singular_points(fn, x):
    x = x.double().requires_grad_(True)
    out = fn(x)
    (out * torch.linspace(0.5, 1.5, out.numel(), dtype=out.dtype).reshape(out.shape)).sum().backward()
    assert torch.isfinite(x.grad).all()
