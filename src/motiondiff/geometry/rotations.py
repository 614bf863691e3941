"""Rotation math in one place (numpy, float64 inside, any leading batch shape).

Conventions used everywhere in motiondiff:
- quaternions are (w, x, y, z), Hamilton product, rotating column vectors: v' = q v q*;
- rotation matrices act on column vectors: v' = R @ v;
- Euler angles follow BVH: the channel order "ZXY" means R = Rz(a0) @ Rx(a1) @ Ry(a2) (intrinsic),
  angles in degrees unless stated otherwise. Euler conversions go through scipy's Rotation.
- 6D rotations are the first two columns of the matrix, ordered (R00, R10, R20, R01, R11, R21).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from motiondiff.geometry.quaternion_algebra import hamilton, matrix_entries

_EPS = 1e-12


def qnormalize(q: np.ndarray) -> np.ndarray:
    return q / np.maximum(np.linalg.norm(q, axis=-1, keepdims=True), _EPS)


def qmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product a * b (apply b first, then a)."""
    return np.stack(hamilton(np.moveaxis(a, -1, 0), np.moveaxis(b, -1, 0)), axis=-1)


def qinv(q: np.ndarray) -> np.ndarray:
    """Inverse of a unit quaternion (its conjugate)."""
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def qrot(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate vectors v (..., 3) by unit quaternions q (..., 4)."""
    w = q[..., :1]
    u = q[..., 1:]
    uv = np.cross(u, v)
    return v + 2.0 * (w * uv + np.cross(u, uv))


def qbetween(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Shortest-arc rotation taking direction u to direction v (the inputs need not be unit length)."""
    axis = np.cross(u, v)
    w = np.sqrt((u**2).sum(-1) * (v**2).sum(-1)) + (u * v).sum(-1)
    return qnormalize(np.concatenate([w[..., None], axis], axis=-1))


def qfix(q: np.ndarray, axis: int = 0) -> np.ndarray:
    """Make a quaternion sequence continuous along `axis` (q and -q are the same rotation; QuaterNet's fix)."""
    q = np.moveaxis(np.array(q, dtype=np.float64, copy=True), axis, 0)
    flip = (q[1:] * q[:-1]).sum(-1) < 0
    sign = np.where(np.cumsum(flip, axis=0) % 2 == 1, -1.0, 1.0)
    q[1:] *= sign[..., None]
    return np.moveaxis(q, 0, axis)


def qslerp(q0: np.ndarray, q1: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Spherical interpolation between unit quaternions; t broadcasts against q0[..., 0]."""
    t = np.asarray(t, dtype=np.float64)[..., None]
    dot = (q0 * q1).sum(-1, keepdims=True)
    q1 = np.where(dot < 0, -q1, q1)  # take the short way round
    dot = np.abs(dot)
    theta = np.arccos(np.clip(dot, -1.0, 1.0))
    sin_theta = np.sin(theta)
    near = sin_theta < 1e-6  # nearly identical: fall back to normalised lerp
    safe = np.where(near, 1.0, sin_theta)
    w0 = np.where(near, 1.0 - t, np.sin((1.0 - t) * theta) / safe)
    w1 = np.where(near, t, np.sin(t * theta) / safe)
    return qnormalize(w0 * q0 + w1 * q1)


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    q = qnormalize(q)
    return np.stack(matrix_entries(np.moveaxis(q, -1, 0)), axis=-1).reshape(q.shape[:-1] + (3, 3))


def matrix_to_quat(m: np.ndarray) -> np.ndarray:
    shape = m.shape[:-2]
    xyzw = Rotation.from_matrix(m.reshape(-1, 3, 3)).as_quat()
    return xyzw[:, [3, 0, 1, 2]].reshape(shape + (4,))


def quat_to_rotvec(q: np.ndarray) -> np.ndarray:
    """Quaternions (..., 4) -> axis-angle vectors (..., 3) (axis times angle in radians, angle in [0, pi]; SMPL's
    pose parameters)."""
    shape = q.shape[:-1]
    xyzw = np.asarray(q, dtype=np.float64).reshape(-1, 4)[:, [1, 2, 3, 0]]
    return Rotation.from_quat(xyzw).as_rotvec().reshape(shape + (3,))


def rotvec_to_quat(v: np.ndarray) -> np.ndarray:
    """Axis-angle vectors (..., 3) -> quaternions (..., 4) (w, x, y, z)."""
    shape = v.shape[:-1]
    xyzw = Rotation.from_rotvec(np.asarray(v, dtype=np.float64).reshape(-1, 3)).as_quat()
    return xyzw[:, [3, 0, 1, 2]].reshape(shape + (4,))


def _check_order(order: str) -> str:
    order = order.upper()
    if len(order) != 3 or set(order) - set("XYZ"):
        raise ValueError(f"Euler order must be three of X, Y, Z (e.g. 'ZXY'), got {order!r}")
    return order


def euler_to_matrix(angles: np.ndarray, order: str, degrees: bool = True) -> np.ndarray:
    """Intrinsic Euler angles (..., 3) in `order` -> rotation matrices (..., 3, 3)."""
    order = _check_order(order)
    shape = angles.shape[:-1]
    rot = Rotation.from_euler(order, angles.reshape(-1, 3), degrees=degrees)
    return rot.as_matrix().reshape(shape + (3, 3))


def matrix_to_euler(m: np.ndarray, order: str, degrees: bool = True) -> np.ndarray:
    """Rotation matrices (..., 3, 3) -> intrinsic Euler angles (..., 3) in `order`."""
    import warnings

    order = _check_order(order)
    shape = m.shape[:-2]
    with warnings.catch_warnings():
        # At gimbal lock scipy picks one of the equivalent solutions and warns; the matrix is still exact.
        warnings.simplefilter("ignore", UserWarning)
        eul = Rotation.from_matrix(m.reshape(-1, 3, 3)).as_euler(order, degrees=degrees)
    return eul.reshape(shape + (3,))


def matrix_to_6d(m: np.ndarray) -> np.ndarray:
    """First two columns, ordered (R00, R10, R20, R01, R11, R21)."""
    return np.concatenate([m[..., :, 0], m[..., :, 1]], axis=-1)


def sixd_to_matrix(d6: np.ndarray) -> np.ndarray:
    """Gram-Schmidt on the two stored columns (Zhou et al. 2019)."""
    a1, a2 = d6[..., :3], d6[..., 3:]
    b1 = a1 / np.maximum(np.linalg.norm(a1, axis=-1, keepdims=True), _EPS)
    b2 = a2 - (b1 * a2).sum(-1, keepdims=True) * b1
    b2 = b2 / np.maximum(np.linalg.norm(b2, axis=-1, keepdims=True), _EPS)
    b3 = np.cross(b1, b2)
    return np.stack([b1, b2, b3], axis=-1)


def quat_to_6d(q: np.ndarray) -> np.ndarray:
    return matrix_to_6d(quat_to_matrix(q))


# ---- helpers for inverse kinematics --------------------------------------------------------------------------
def axis_angle_to_quat(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rotation by `angle` radians (...) about unit `axis` (..., 3): q = (cos(angle/2), sin(angle/2) axis)."""
    half = 0.5 * np.asarray(angle, dtype=np.float64)[..., None]
    return np.concatenate([np.cos(half), np.sin(half) * axis], axis=-1)


def any_perpendicular(u: np.ndarray) -> np.ndarray:
    """A unit vector perpendicular to u (..., 3): u crossed with the basis axis least aligned with it."""
    basis = np.eye(3)[np.argmin(np.abs(u), axis=-1)]
    return qnormalize(np.cross(u, basis))


def qswing(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Shortest-arc rotation taking direction u to direction v, like `qbetween`, but also defined for opposite
    directions (where every half turn about an axis perpendicular to u is shortest; this picks
    `any_perpendicular(u)`). Unnormalised q = (|u||v| + u.v, u x v) has norm 2|u||v|cos(theta/2), which only
    vanishes for opposite vectors."""
    axis = np.cross(u, v)
    scale = np.sqrt((u**2).sum(-1) * (v**2).sum(-1))
    q = np.concatenate([(scale + (u * v).sum(-1))[..., None], axis], axis=-1)
    opposite = np.linalg.norm(q, axis=-1) <= 1e-12 * np.maximum(scale, _EPS)
    half_turn = np.concatenate([np.zeros(u.shape[:-1] + (1,)), any_perpendicular(u)], axis=-1)
    return qnormalize(np.where(opposite[..., None], half_turn, q))


def qtwist_angle(q: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Angle (radians, in [-pi, pi)) of the twist of q about unit `axis` in the swing-twist split q = swing * twist,
    twist = normalise(w, (xyz . axis) axis): 2 atan2(xyz . axis, w), the same for q and -q."""
    angle = 2.0 * np.arctan2((q[..., 1:] * axis).sum(-1), q[..., 0])
    return (angle + np.pi) % (2.0 * np.pi) - np.pi


def qangle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle (radians, [0, pi]) of the rotation taking quaternion a to b: with d = a^-1 b, 2 atan2(|d_xyz|, |d_w|)
    (accurate for tiny angles and float32 inputs, where 2 acos(|<a, b>|) loses half the digits)."""
    d = qmul(qinv(a), b)
    return 2.0 * np.arctan2(np.linalg.norm(d[..., 1:], axis=-1), np.abs(d[..., 0]))


def kabsch(source: np.ndarray, target: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """Best-fit rotation matrices R (..., 3, 3) minimising sum_k w_k |R s_k - t_k|^2 for vectors (..., K, 3).

    With H = sum_k w_k s_k t_k^T = U S V^T (SVD), R = V diag(1, 1, d) U^T, d = sign det(V U^T) so R is a rotation
    and not a reflection (Kabsch 1976). Unique when the sources span a plane; exact when the targets are rotated
    sources."""
    w = np.ones(source.shape[:-1]) if weights is None else np.broadcast_to(weights, source.shape[:-1])
    h = np.einsum("...k,...ki,...kj->...ij", w, source, target)
    u, _, vt = np.linalg.svd(h)
    v, ut = np.swapaxes(vt, -1, -2), np.swapaxes(u, -1, -2)
    d = np.sign(np.linalg.det(v @ ut))
    d = np.where(d == 0, 1.0, d)
    fix = np.broadcast_to(np.eye(3), h.shape).copy()
    fix[..., 2, 2] = d
    return v @ fix @ ut
