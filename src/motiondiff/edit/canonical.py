"""Where a motion stands on the ground, and the rigid turns about y that move it: the one place that knows how each
representation family carries its global placement.

A *placement* (yaw, offset) maps a motion in canonical placement (root at the x,z origin, facing +Z) to the world:

    p_world = R_y(yaw) p_canonical + offset,   R_y(θ) = [[cos θ, 0, sin θ], [0, 1, 0], [−sin θ, 0, cos θ]],

offset = (x, 0, z) (heights are never touched: every training clip already stands on y = 0).

- ``hml263`` / ``kit251``: features hold per-frame root velocities and root-relative positions, so they are the same
  wherever the motion stands; decoding always starts at the origin facing +Z. They carry no placement:
  ``to_canonical`` / ``from_canonical`` return them unchanged and ``rigid_yaw_translate`` refuses them.
- ``jp``: world joint positions; the turn is applied to every joint.
- ``rp*jr``: root world position and root global rotation (then local rotations, which a rigid turn leaves alone);
  the root position is turned and shifted, the root rotation left-multiplied by R_y(yaw), re-encoded per codec.

``placement(rep, features, frame)`` reads a frame's placement the way the training clips were canonicalised (facing
from the skeleton's hips and shoulders, ``data.representations.hml_features.ground_and_face``; for hml the decoder's own root
heading), so ``to_canonical`` puts that frame where every training clip starts.
"""

from __future__ import annotations

import numpy as np
import torch

from motiondiff.data.representations import HMLRepresentation, JointPositions, Representation, RotationRepresentation
from motiondiff.data.representations.hml import recover_root_torch
from motiondiff.geometry.rotations import matrix_to_quat, qmul
from motiondiff.geometry.skeleton import Skeleton

UP = np.array([0.0, 1.0, 0.0])


def carries_placement(rep: Representation) -> bool:
    """False for hml263/kit251, whose features are invariant to where the motion stands and which way it faces."""
    return not isinstance(rep, HMLRepresentation)


def yaw_matrix(yaw) -> np.ndarray:
    """R_y(yaw) (..., 3, 3) for yaw (...) in radians: turns +Z towards +X for yaw > 0."""
    yaw = np.asarray(yaw, dtype=np.float64)
    c, s, zero, one = np.cos(yaw), np.sin(yaw), np.zeros_like(yaw), np.ones_like(yaw)
    rows = [np.stack([c, zero, s], -1), np.stack([zero, one, zero], -1), np.stack([-s, zero, c], -1)]
    return np.stack(rows, axis=-2)


def turn_points(points: np.ndarray, yaw, offset) -> np.ndarray:
    """R_y(yaw) p + offset for points (..., N, [J,] 3); yaw (...) and offset (..., 3) are per motion (batch dims)."""
    points = np.asarray(points, dtype=np.float64)
    yaw, offset = np.asarray(yaw, dtype=np.float64), np.asarray(offset, dtype=np.float64)
    extra = points.ndim - 1 - yaw.ndim  # frame (and joint) axes the per-motion placement broadcasts over
    rot = yaw_matrix(yaw).reshape(yaw.shape + (1,) * extra + (3, 3))
    return np.einsum("...ij,...j->...i", rot, points) + offset.reshape(offset.shape[:-1] + (1,) * extra + (3,))


def inverse_placement(yaw, offset) -> tuple[np.ndarray, np.ndarray]:
    """(yaw', offset') with turn(turn(p, yaw, offset), yaw', offset') = p: yaw' = −yaw, offset' = −R_y(−yaw) offset."""
    yaw, offset = np.asarray(yaw, dtype=np.float64), np.asarray(offset, dtype=np.float64)
    return -yaw, -np.einsum("...ij,...j->...i", yaw_matrix(-yaw), offset)


def facing_yaw(frame_joints: np.ndarray, skeleton: Skeleton) -> np.ndarray:
    """Yaw (...) of the facing of joints (..., J, 3), the rule of ``ground_and_face``: across = (r_hip − l_hip) +
    (r_shoulder − l_shoulder), forward = up × across / |across|, yaw = atan2(forward_x, forward_z) (0 = facing +Z)."""
    if skeleton.face_joints is None:
        raise ValueError(
            f"skeleton {skeleton.name!r} has no hip/shoulder joints to tell which way it faces; long motions "
            "need them to place each segment where the training clips start"
        )
    r_hip, l_hip, r_sdr, l_sdr = skeleton.face_joints
    j = np.asarray(frame_joints, dtype=np.float64)
    across = (j[..., r_hip, :] - j[..., l_hip, :]) + (j[..., r_sdr, :] - j[..., l_sdr, :])
    forward = np.cross(UP, across)
    return np.arctan2(forward[..., 0], forward[..., 2])


def placement(rep: Representation, features: np.ndarray, frame: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(yaw (...), offset (..., 3)) of frame ``frame`` of de-normalised features (..., N, D): what ``to_canonical``
    undoes, so that this frame starts the canonical motion at the origin facing +Z."""
    feats = np.asarray(features, dtype=np.float64)
    if isinstance(rep, HMLRepresentation):
        # the decoder's root at `frame`: rotation quaternion (cos a, 0, sin a, 0) is applied inverted, a turn of −2a
        if frame == 0:  # where decoding starts: the origin, facing +Z
            return np.zeros(feats.shape[:-2]), np.zeros(feats.shape[:-2] + (3,))
        r_rot, r_pos = recover_root_torch(torch.from_numpy(feats[..., : frame + 1, :]))
        half_angle = torch.atan2(r_rot[..., frame, 2], r_rot[..., frame, 0]).numpy()
        root = r_pos[..., frame, :].numpy()
        return -2.0 * half_angle, root * np.array([1.0, 0.0, 1.0])
    joints = rep.decode_numpy(feats[..., frame : frame + 1, :])[..., 0, :, :]
    return facing_yaw(joints, rep.skeleton), joints[..., 0, :] * np.array([1.0, 0.0, 1.0])


def to_canonical(rep: Representation, features: np.ndarray, yaw, offset) -> np.ndarray:
    """World features -> the same motion placed canonically (hml: unchanged, it has no placement)."""
    if not carries_placement(rep):
        return np.asarray(features, dtype=np.float64)
    return rigid_yaw_translate(rep, features, *inverse_placement(yaw, offset))


def from_canonical(rep: Representation, features: np.ndarray, yaw, offset) -> np.ndarray:
    """Canonical features -> the world at placement (yaw, offset) (hml: unchanged; its placement comes from the
    features before it when the rows are concatenated)."""
    if not carries_placement(rep):
        return np.asarray(features, dtype=np.float64)
    return rigid_yaw_translate(rep, features, yaw, offset)


def rigid_yaw_translate(rep: Representation, features: np.ndarray, yaw, offset) -> np.ndarray:
    """Features (..., N, D) whose decoding is R_y(yaw) decode(features) + offset (float64; yaw (...), offset
    (..., 3) per motion)."""
    feats = np.array(features, dtype=np.float64)
    if isinstance(rep, JointPositions):
        joints = feats.reshape(feats.shape[:-1] + (rep.skeleton.num_joints, 3))
        return turn_points(joints, yaw, offset).reshape(feats.shape)
    if isinstance(rep, RotationRepresentation):
        k = rep.codec.width
        feats[..., :3] = turn_points(feats[..., :3], yaw, offset)
        feats[..., 3 : 3 + k] = _turn_root_rotation(rep, feats[..., 3 : 3 + k], yaw)
        return feats
    raise ValueError(
        f"{rep.name} features carry no global position or heading (per-frame velocities and root-relative data), "
        "so there is nothing to turn: they are the same wherever the motion stands"
    )


def _turn_root_rotation(rep: RotationRepresentation, root: np.ndarray, yaw) -> np.ndarray:
    """The root's encoded global rotation (..., N, k) -> that of R_y(yaw) R_root, exact for what the codec decodes
    (also for generated, not quite valid values: 6D columns and matrices turn linearly, quaternions multiply)."""
    yaw = np.asarray(yaw, dtype=np.float64)
    shape = yaw.shape + (1,) * (root.ndim - 1 - yaw.ndim)  # per motion, broadcast over frames
    turn = yaw_matrix(yaw).reshape(shape + (3, 3))
    if rep.name == "rp6jr":  # two columns of R; Gram-Schmidt commutes with a rotation
        cols = root.reshape(root.shape[:-1] + (2, 3))
        return np.einsum("...ij,...j->...i", turn[..., None, :, :], cols).reshape(root.shape)
    if rep.name == "rpmjr":
        mats = root.reshape(root.shape[:-1] + (3, 3))
        return (turn @ mats).reshape(root.shape)
    if rep.name == "rpqjr":  # (cos θ/2, 0, sin θ/2, 0) ⊗ q keeps |q|, which the decoder normalises away
        half = yaw.reshape(shape) / 2
        q_yaw = np.stack(np.broadcast_arrays(np.cos(half), 0 * half, np.sin(half), 0 * half), -1)
        turned = qmul(np.broadcast_to(q_yaw, root.shape), root)
        # q and −q are one rotation; keep the training clips' sign convention (w ≥ 0 at the first frame), whole
        # motions flipped at once so the sign stays continuous over time
        return np.where(turned[..., :1, :1] < 0, -turned, turned)
    # axis-angle / Euler: through matrices and back with the codec's own encoder
    mats = rep.codec.decode(torch.from_numpy(root), rep.euler_order).numpy()
    quats = matrix_to_quat(turn @ mats)
    return rep.codec.encode(quats[..., None, :], rep.euler_order)[..., 0, :]
